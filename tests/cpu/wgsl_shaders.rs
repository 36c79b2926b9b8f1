//! Shaders as WGSL files (issue 13) through the JSON loader: what a valid
//! `wgsl` shader loads as (fields, values, packed words), files shared by
//! several shaders, checkers of WGSL shaders, the path guard, and the scene
//! model's own checks. The command line's errors are in `tests/cli/bad_input.rs`.

use std::path::{Path, PathBuf};

use penumbra::loaders::{load_scene, LoadOptions, Loaded};
use penumbra::scene::{ParamField, ParamType, ParamValue, Shader, WgslShader};
use serde_json::{json, Value};
use tempfile::TempDir;

/// A scene of one sphere per shader named in `objects`, with `shaders`.
fn scene(shaders: Value, objects: &[&str]) -> Value {
    let objects: Vec<Value> = objects
        .iter()
        .enumerate()
        .map(|(i, s)| {
            json!({"type": "sphere", "center": [i as f64 * 3.0, 0, 0], "radius": 1, "shader": s})
        })
        .collect();
    json!({
        "camera": {"position": [0, 0, 8], "look_at": [0, 0, 0], "width": 16, "height": 16},
        "shaders": shaders,
        "objects": objects,
        "lights": [{"type": "point", "position": [2, 3, 4], "ambient": [0.1, 0.1, 0.1]}]
    })
}

/// Writes `json` as `scene.json` into a fresh folder with copies of the
/// test shader files `wgsl` (from `tests/data/shaders/`).
fn write(json: &Value, wgsl: &[&str]) -> (TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/shaders");
    for f in wgsl {
        std::fs::copy(data.join(f), dir.path().join(f)).unwrap();
    }
    let path = dir.path().join("scene.json");
    std::fs::write(&path, serde_json::to_string_pretty(json).unwrap()).unwrap();
    (dir, path)
}

fn load(json: &Value, wgsl: &[&str]) -> (TempDir, PathBuf, Loaded) {
    let (dir, path) = write(json, wgsl);
    let loaded = load_scene(&path, &LoadOptions::default()).unwrap();
    (dir, path, loaded)
}

fn wgsl(s: &Shader) -> &WgslShader {
    match s {
        Shader::Wgsl(w) => w,
        other => panic!("not a WGSL shader: {other:?}"),
    }
}

fn bits(xs: &[f32]) -> Vec<u32> {
    xs.iter().map(|x| x.to_bits()).collect()
}

#[test]
fn a_wgsl_shader_loads_with_its_params_packed_in_field_order() {
    let json = scene(
        json!({"toon": {"type": "wgsl", "file": "toon.wgsl",
                        "params": {"gain": 1.5, "bands": 4, "base": [0.9, 0.3, 0.2]}}}),
        &["toon"],
    );
    let (dir, path, loaded) = load(&json, &["toon.wgsl"]);
    let w = wgsl(&loaded.scene.shaders[0]);
    assert_eq!(w.path, dir.path().join("toon.wgsl"));
    assert_eq!(
        w.source,
        std::fs::read_to_string(dir.path().join("toon.wgsl")).unwrap()
    );
    let field = |name: &str, ty| ParamField {
        name: name.into(),
        ty,
    };
    assert_eq!(
        w.fields,
        vec![
            field("base", ParamType::Vec3),
            field("bands", ParamType::U32),
            field("gain", ParamType::F32),
        ]
    );
    assert_eq!(
        w.values,
        vec![
            ParamValue::Vec(vec![0.9, 0.3, 0.2]),
            ParamValue::U32(4),
            ParamValue::F32(1.5),
        ]
    );
    assert!(w.has_ambient);
    let mut expected = bits(&[0.9, 0.3, 0.2]);
    expected.push(4);
    expected.extend(bits(&[1.5]));
    assert_eq!(w.words(|_| u32::MAX), expected);
    // The watcher reloads when the shader file changes.
    assert_eq!(loaded.files, vec![path, dir.path().join("toon.wgsl")]);
    // A WGSL shader is no kernel feature (it is a shade pipeline of its own).
    let f = loaded.scene.features();
    assert!(!f.checker);
}

#[test]
fn a_file_without_params_needs_none() {
    for toon in [
        json!({"type": "wgsl", "file": "plain.wgsl"}),
        json!({"type": "wgsl", "file": "plain.wgsl", "params": {}}),
    ] {
        let (_dir, _path, loaded) = load(&scene(json!({"n": toon}), &["n"]), &["plain.wgsl"]);
        let w = wgsl(&loaded.scene.shaders[0]);
        assert!(w.fields.is_empty() && w.values.is_empty() && !w.has_ambient);
        assert!(w.words(|_| u32::MAX).is_empty());
    }
}

#[test]
fn shaders_share_a_file_with_their_own_params_and_checkers_name_them() {
    let json = scene(
        json!({
            "warm": {"type": "wgsl", "file": "toon.wgsl",
                     "params": {"base": [1, 0.5, 0], "bands": 3, "gain": 1}},
            "cold": {"type": "wgsl", "file": "toon.wgsl",
                     "params": {"base": [0, 0.5, 1], "bands": 5, "gain": 2}},
            "board": {"type": "checker", "size": 0.5, "even": "warm", "odd": "cold"},
            "red": {"type": "phong", "diffuse": [1, 0, 0]}
        }),
        &["board", "red", "warm"],
    );
    let (dir, path, loaded) = load(&json, &["toon.wgsl"]);
    // Shaders are numbered by name: board, cold, red, warm.
    let s = &loaded.scene.shaders;
    let Shader::Checker(board) = &s[0] else {
        panic!("{:?}", s[0]);
    };
    assert_eq!((board.even, board.odd), (3, 1));
    assert_eq!(wgsl(&s[1]).values[1], ParamValue::U32(5));
    assert_eq!(wgsl(&s[3]).values[1], ParamValue::U32(3));
    assert_eq!(wgsl(&s[1]).path, wgsl(&s[3]).path);
    // The file is read (and listed) once.
    assert_eq!(loaded.files, vec![path, dir.path().join("toon.wgsl")]);
    // The reference renders only the built-in shaders.
    let why = penumbra::reference::supports(&loaded.scene).unwrap_err();
    assert!(
        why.starts_with(
            "the f64 reference renders only the built-in shaders (phong, blinn_phong, metallic_roughness, checker); shader `shaders["
        ),
        "{why}"
    );
    assert!(why.contains("toon.wgsl"), "{why}");
}

#[test]
fn the_reference_ignores_an_unused_wgsl_shader() {
    let json = scene(
        json!({
            "toon": {"type": "wgsl", "file": "plain.wgsl"},
            "red": {"type": "phong", "diffuse": [1, 0, 0]}
        }),
        &["red"],
    );
    let (_dir, _path, loaded) = load(&json, &["plain.wgsl"]);
    penumbra::reference::supports(&loaded.scene).unwrap();
}

#[test]
fn restrict_paths_refuses_a_shader_file_outside_the_scene_folder() {
    let outer = tempfile::tempdir().unwrap();
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/shaders");
    std::fs::copy(data.join("plain.wgsl"), outer.path().join("plain.wgsl")).unwrap();
    let inner = outer.path().join("scene");
    std::fs::create_dir(&inner).unwrap();
    let path = inner.join("scene.json");
    let json = scene(
        json!({"n": {"type": "wgsl", "file": "../plain.wgsl"}}),
        &["n"],
    );
    std::fs::write(&path, json.to_string()).unwrap();
    let opts = LoadOptions {
        restrict_paths: true,
        ..Default::default()
    };
    let e = load_scene(&path, &opts).unwrap_err();
    assert_eq!(e.file, path);
    assert_eq!(e.field, "shaders.n.file");
    assert!(e.message.contains("lies outside the scene's folder"), "{e}");
    // Unrestricted, it loads.
    load_scene(&path, &LoadOptions::default()).unwrap();
}

#[test]
fn a_wgsl_shader_takes_only_file_and_params() {
    let json = scene(
        json!({"n": {"type": "wgsl", "file": "plain.wgsl", "diffuse": [1, 1, 1]}}),
        &["n"],
    );
    let (_dir, path) = write(&json, &["plain.wgsl"]);
    let e = load_scene(&path, &LoadOptions::default()).unwrap_err();
    assert_eq!(e.field, "shaders.n.diffuse");
    assert_eq!(e.message, "not a field of a wgsl shader");
    let json = scene(json!({"n": {"type": "wgsl"}}), &["n"]);
    let (_dir, path) = write(&json, &[]);
    let e = load_scene(&path, &LoadOptions::default()).unwrap_err();
    assert_eq!(e.field, "shaders.n");
    assert_eq!(
        e.message,
        "missing field `file` (required for a wgsl shader)"
    );
    let json = scene(
        json!({"n": {"type": "phong", "diffuse": [1, 1, 1], "params": {}}}),
        &["n"],
    );
    let (_dir, path) = write(&json, &[]);
    let e = load_scene(&path, &LoadOptions::default()).unwrap_err();
    assert_eq!(e.field, "shaders.n.params");
}

#[test]
fn validation_checks_values_against_fields() {
    let json = scene(
        json!({"toon": {"type": "wgsl", "file": "toon.wgsl",
                        "params": {"gain": 1.5, "bands": 4, "base": [0.9, 0.3, 0.2]}}}),
        &["toon"],
    );
    let (_dir, _path, loaded) = load(&json, &["toon.wgsl"]);
    let with = |change: &dyn Fn(&mut WgslShader)| {
        let mut s = loaded.scene.clone();
        let Shader::Wgsl(w) = &mut s.shaders[0] else {
            unreachable!()
        };
        change(w);
        s.validate()
    };
    with(&|_| {}).unwrap();
    let e = with(&|w| {
        w.values.pop();
    })
    .unwrap_err();
    assert_eq!(e.field, "shaders[0].values");
    let e = with(&|w| w.values[1] = ParamValue::F32(4.0)).unwrap_err();
    assert_eq!(e.field, "shaders[0].values.bands");
    let e = with(&|w| w.values[0] = ParamValue::Vec(vec![1.0, 2.0])).unwrap_err();
    assert_eq!(e.field, "shaders[0].values.base");
    let e = with(&|w| w.values[2] = ParamValue::F32(f32::NAN)).unwrap_err();
    assert_eq!(e.field, "shaders[0].values.gain");
    assert!(e.message.contains("must be finite"), "{e}");
    let e = with(&|w| w.values[0] = ParamValue::Vec(vec![1.0, f32::INFINITY, 0.0])).unwrap_err();
    assert_eq!(e.field, "shaders[0].values.base");
}
