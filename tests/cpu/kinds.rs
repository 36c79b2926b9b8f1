//! Coverage per kind (docs/architecture.md, "Checklists"): every light,
//! object and shader kind of the scene format is exercised by the fuzzing
//! harness's mutations and generated seeds, by a bad-input case, by the f64
//! reference's comparison with the GPU (unless the reference refuses the
//! kind; then by its own GPU tests), and is documented in scenes/README.md.
//! The kinds come from the scene model's exhaustive `type_name`s
//! ([`LightKind::TYPES`], [`Shape::TYPES`], [`Shader::TYPES`]), so a new kind
//! fails here until each of those places has it.

use std::collections::BTreeSet;
use std::path::Path;

use penumbra::loaders::{self, LoadOptions};
use penumbra::scene::{LightKind, Scene, Shader, Shape};

fn text(rel: &str) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(rel);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// `blinn_phong` → `BlinnPhong`: the Rust variant of a type name.
fn variant(type_name: &str) -> String {
    type_name
        .split('_')
        .map(|w| {
            let mut c = w.chars();
            c.next()
                .map(|f| f.to_uppercase().chain(c).collect::<String>())
                .unwrap_or_default()
        })
        .collect()
}

/// The scenes under scenes/ that tests/gpu/reference.rs renders with both
/// the GPU and the f64 reference (`load_sized("NAME", …)`).
fn reference_scenes() -> Vec<Scene> {
    let source = text("tests/gpu/reference.rs");
    let names: BTreeSet<&str> = source
        .split("load_sized(\"")
        .skip(1)
        .filter_map(|rest| rest.split('"').next())
        .collect();
    assert!(!names.is_empty(), "tests/gpu/reference.rs loads no scene");
    names
        .into_iter()
        .map(|name| {
            let path = Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("scenes")
                .join(name);
            loaders::load_scene(&path, &LoadOptions::default())
                .unwrap_or_else(|e| panic!("{e}"))
                .scene
        })
        .collect()
}

/// Where a kind of `family` ("lights", "objects", "shaders") must appear.
struct Places {
    /// Files whose text must hold `"TYPE"` or `` `TYPE` `` (the fuzzing
    /// harness's type strings, the scene format's documentation).
    quoted: &'static [&'static str],
    /// Files of which one must hold `"type": "TYPE"`: a scene with the kind.
    typed: &'static [&'static [&'static str]],
}

fn check_places(family: &str, types: &[&str], places: &Places, missing: &mut Vec<String>) {
    for t in types {
        for file in places.quoted {
            let text = text(file);
            if !text.contains(&format!("\"{t}\"")) && !text.contains(&format!("`{t}`")) {
                missing.push(format!("{family} kind \"{t}\": not in {file}"));
            }
        }
        for files in places.typed {
            let typed = format!("\"type\": \"{t}\"");
            if !files.iter().any(|f| text(f).contains(&typed)) {
                missing.push(format!("{family} kind \"{t}\": no {typed} in {files:?}"));
            }
        }
    }
}

/// The kinds the reference comparison covers: those of its scenes, and
/// those that tests/gpu/reference.rs builds in code (`LightKind::Rect`…).
fn reference_covers(types: &[&str], in_scenes: &BTreeSet<&str>, prefix: &str) -> Vec<String> {
    let source = text("tests/gpu/reference.rs");
    types
        .iter()
        .filter(|t| {
            !in_scenes.contains(**t) && !source.contains(&format!("{prefix}::{}", variant(t)))
        })
        .map(|t| format!("\"{t}\": in no scene or code of tests/gpu/reference.rs"))
        .collect()
}

#[test]
fn every_light_kind_is_covered() {
    let mut missing = Vec::new();
    check_places(
        "light",
        &LightKind::TYPES,
        &Places {
            quoted: &["tools/measure/fuzz/mutate.rs", "scenes/README.md"],
            typed: &[
                &["tools/measure/fuzz/seeds.rs"],
                &["tests/cli/bad_input.rs", "tests/cli/area_light_input.rs"],
            ],
        },
        &mut missing,
    );
    let scenes = reference_scenes();
    let used: BTreeSet<&str> = scenes
        .iter()
        .flat_map(|s| s.lights.iter().map(|l| l.kind.type_name()))
        .collect();
    assert!(
        used.iter().all(|t| LightKind::TYPES.contains(t)),
        "{used:?}"
    );
    missing.extend(reference_covers(&LightKind::TYPES, &used, "LightKind"));
    // An end-to-end test of each kind's light against its formula.
    let end_to_end = text("tests/gpu/lights.rs") + &text("tests/gpu/area_lights.rs");
    for t in LightKind::TYPES {
        let typed = format!("\"type\": \"{t}\"");
        let built = format!("LightKind::{}", variant(t));
        if !end_to_end.contains(&typed) && !end_to_end.contains(&built) {
            missing.push(format!(
                "light kind \"{t}\": not in tests/gpu/lights.rs or tests/gpu/area_lights.rs"
            ));
        }
    }
    assert!(missing.is_empty(), "{}", missing.join("\n"));
}

#[test]
fn every_object_kind_is_covered() {
    let mut missing = Vec::new();
    check_places(
        "object",
        &Shape::TYPES,
        &Places {
            quoted: &["tools/measure/fuzz/mutate.rs", "scenes/README.md"],
            typed: &[
                &["tools/measure/fuzz/seeds.rs"],
                &["tests/cli/bad_input.rs"],
            ],
        },
        &mut missing,
    );
    let scenes = reference_scenes();
    let used: BTreeSet<&str> = scenes
        .iter()
        .flat_map(|s| s.objects.iter().map(|o| o.shape.type_name()))
        .collect();
    assert!(used.iter().all(|t| Shape::TYPES.contains(t)), "{used:?}");
    missing.extend(reference_covers(&Shape::TYPES, &used, "Shape"));
    assert!(missing.is_empty(), "{}", missing.join("\n"));
}

#[test]
fn every_shader_kind_is_covered() {
    let mut missing = Vec::new();
    check_places(
        "shader",
        &Shader::TYPES,
        &Places {
            quoted: &["tools/measure/fuzz/mutate.rs", "scenes/README.md"],
            typed: &[
                &["tools/measure/fuzz/seeds.rs"],
                &["tests/cli/bad_input.rs"],
            ],
        },
        &mut missing,
    );
    let scenes = reference_scenes();
    let used: BTreeSet<&str> = scenes
        .iter()
        .flat_map(|s| s.shaders.iter().map(Shader::type_name))
        .collect();
    assert!(used.iter().all(|t| Shader::TYPES.contains(t)), "{used:?}");
    // The reference refuses user WGSL (reference::supports): user shaders
    // are tested against their formulas on the GPU instead.
    let refused: Vec<&str> = Shader::TYPES.into_iter().filter(|t| *t == "wgsl").collect();
    for t in &refused {
        if !text("tests/gpu/user_shaders.rs").contains(&format!("\"type\": \"{t}\"")) {
            missing.push(format!(
                "shader kind \"{t}\": not in tests/gpu/user_shaders.rs"
            ));
        }
    }
    let compared: Vec<&str> = Shader::TYPES
        .into_iter()
        .filter(|t| !refused.contains(t))
        .collect();
    missing.extend(reference_covers(&compared, &used, "Shader"));
    assert!(missing.is_empty(), "{}", missing.join("\n"));
}

#[test]
fn variant_names_follow_the_type_names() {
    assert_eq!(variant("blinn_phong"), "BlinnPhong");
    assert_eq!(variant("rect"), "Rect");
}
