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
struct Places<'a> {
    /// Files whose text must hold `"TYPE"` or `` `TYPE` `` (the fuzzing
    /// harness's type strings, the scene format's documentation).
    quoted: &'a [&'a str],
    /// Files of which one must hold `"type": "TYPE"`: a scene with the kind.
    typed: &'a [&'a [&'a str]],
}

fn check_places(family: &str, types: &[&str], places: &Places<'_>, missing: &mut Vec<String>) {
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

/// What every family is checked for: the fuzz harness's strings and
/// scenes/README.md name each kind, a generated fuzz seed and a case of
/// `bad_input` use it, every kind the reference scenes `used` is one of
/// `types`, and each kind of `compared` is in a reference scene or in the
/// reference tests' code (as `PREFIX::Variant`).
fn family_gaps(
    family: &str,
    types: &[&str],
    bad_input: &'static [&'static str],
    used: &BTreeSet<&str>,
    prefix: &str,
    compared: &[&str],
) -> Vec<String> {
    let mut missing = Vec::new();
    check_places(
        family,
        types,
        &Places {
            quoted: &["tools/measure/fuzz/mutate.rs", "scenes/README.md"],
            typed: &[&["tools/measure/fuzz/seeds.rs"], bad_input],
        },
        &mut missing,
    );
    assert!(used.iter().all(|t| types.contains(t)), "{used:?}");
    missing.extend(reference_covers(compared, used, prefix));
    missing
}

#[test]
fn every_light_kind_is_covered() {
    let used: BTreeSet<&str> = reference_scenes()
        .iter()
        .flat_map(|s| s.lights.iter().map(|l| l.kind.type_name()))
        .collect();
    let mut missing = family_gaps(
        "light",
        &LightKind::TYPES,
        &["tests/cli/bad_input.rs", "tests/cli/area_light_input.rs"],
        &used,
        "LightKind",
        &LightKind::TYPES,
    );
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
    let used: BTreeSet<&str> = reference_scenes()
        .iter()
        .flat_map(|s| s.objects.iter().map(|o| o.shape.type_name()))
        .collect();
    let missing = family_gaps(
        "object",
        &Shape::TYPES,
        &["tests/cli/bad_input.rs"],
        &used,
        "Shape",
        &Shape::TYPES,
    );
    assert!(missing.is_empty(), "{}", missing.join("\n"));
}

#[test]
fn every_shader_kind_is_covered() {
    let used: BTreeSet<&str> = reference_scenes()
        .iter()
        .flat_map(|s| s.shaders.iter().map(Shader::type_name))
        .collect();
    // The reference refuses user WGSL (reference::supports): user shaders
    // are tested against their formulas on the GPU instead.
    let compared: Vec<&str> = Shader::TYPES.into_iter().filter(|t| *t != "wgsl").collect();
    let mut missing = family_gaps(
        "shader",
        &Shader::TYPES,
        &["tests/cli/bad_input.rs"],
        &used,
        "Shader",
        &compared,
    );
    if !text("tests/gpu/user_shaders.rs").contains("\"type\": \"wgsl\"") {
        missing.push("shader kind \"wgsl\": not in tests/gpu/user_shaders.rs".into());
    }
    assert!(missing.is_empty(), "{}", missing.join("\n"));
}

#[test]
fn variant_names_follow_the_type_names() {
    assert_eq!(variant("blinn_phong"), "BlinnPhong");
    assert_eq!(variant("rect"), "Rect");
}
