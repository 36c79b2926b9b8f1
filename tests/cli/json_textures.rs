//! `penumbra render` on JSON scenes with textures (issue 14): a missing
//! texture file, a corrupt one, one in a format textures do not take, an
//! unknown filter or wrap name, a texture where no texture goes and one
//! given to a Params field that is not `u32` each fail with a non-zero exit
//! status (no panic), one `error: ` line naming the scene file, the JSON
//! path and the texture file, and no output file; the same scene with a
//! good texture renders.

use std::io::Cursor;
use std::path::Path;
use std::process::{Command, Output};

use serde_json::{json, Value};

/// A 4×4 PNG.
fn png() -> Vec<u8> {
    let img = image::RgbaImage::from_fn(4, 4, |x, y| {
        image::Rgba([(60 * x) as u8, (60 * y) as u8, 100, 255])
    });
    let mut out = Vec::new();
    img.write_to(&mut Cursor::new(&mut out), image::ImageFormat::Png)
        .unwrap();
    out
}

/// A textured floor (`diffuse` of shader `floor`) under a sphere.
fn scene(diffuse: Value) -> Value {
    json!({
        "camera": {"position": [0, 2, 5], "look_at": [0, 0, 0], "width": 32, "height": 24},
        "shaders": {
            "floor": {"type": "phong", "diffuse": diffuse},
            "ball": {"type": "blinn_phong", "diffuse": [0.8, 0.2, 0.2]}
        },
        "objects": [
            {"type": "plane", "point": [0, 0, 0], "normal": [0, 1, 0], "shader": "floor"},
            {"type": "sphere", "center": [0, 1, 0], "radius": 1, "shader": "ball"}
        ],
        "lights": [{"type": "directional", "direction": [-1, -2, -1], "ambient": [0.1, 0.1, 0.1]}]
    })
}

/// Renders `json` (written as `scene.json` with `files` beside it) to
/// `out/out.png`; returns the output, the scene's path and the output folder.
fn render(json: &Value, files: &[(&str, &[u8])]) -> (Output, tempfile::TempDir, tempfile::TempDir) {
    let dir = tempfile::tempdir().unwrap();
    for (name, bytes) in files {
        std::fs::write(dir.path().join(name), bytes).unwrap();
    }
    let scene = dir.path().join("scene.json");
    std::fs::write(&scene, serde_json::to_string_pretty(json).unwrap()).unwrap();
    let out_dir = tempfile::tempdir().unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .arg("render")
        .arg(&scene)
        .arg("-o")
        .arg(out_dir.path().join("out.png"))
        .output()
        .expect("run penumbra");
    (out, dir, out_dir)
}

/// Asserts a clean failure: a non-zero exit code that is not a panic's, one
/// `error: ` line naming the scene file as `file: field: message` and every
/// string of `must`, nothing on stdout and nothing in the output folder.
#[track_caller]
fn fails(json: &Value, files: &[(&str, &[u8])], field: &str, must: &[&str]) {
    let (out, dir, out_dir) = render(json, files);
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    let ctx = format!("status {:?}\nstderr:\n{stderr}", out.status);
    eprintln!("{stderr}");
    let code = out.status.code();
    assert!(
        code.is_some() && code != Some(0) && code != Some(101),
        "{ctx}"
    );
    assert!(!stderr.contains("panicked"), "{ctx}");
    assert!(stderr.starts_with("error: "), "{ctx}");
    assert_eq!(stderr.trim_end().lines().count(), 1, "one line\n{ctx}");
    let scene = dir.path().join("scene.json");
    let named = format!("{}: {field}: ", scene.display());
    assert!(stderr.contains(&named), "should name {named:?}\n{ctx}");
    for m in must {
        assert!(stderr.contains(m), "should mention {m:?}\n{ctx}");
    }
    assert!(out.stdout.is_empty(), "{ctx}");
    let left: Vec<_> = std::fs::read_dir(out_dir.path()).unwrap().collect();
    assert!(left.is_empty(), "no output file: {left:?}\n{ctx}");
}

#[test]
fn a_good_texture_renders() {
    let (out, _dir, out_dir) = render(
        &scene(json!({"texture": "wood.png", "filter": "nearest", "scale": 2})),
        &[("wood.png", &png())],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(
        image::image_dimensions(out_dir.path().join("out.png")).unwrap(),
        (32, 24)
    );
}

#[test]
fn a_missing_texture_file() {
    fails(
        &scene(json!({"texture": "wood.png"})),
        &[],
        "shaders.floor.diffuse.texture",
        &["no such file", "wood.png"],
    );
}

#[test]
fn a_corrupt_texture_file() {
    let mut cut = png();
    cut.truncate(cut.len() - 16);
    fails(
        &scene(json!({"texture": "wood.png"})),
        &[("wood.png", &cut)],
        "shaders.floor.diffuse.texture",
        &["wood.png", "corrupt"],
    );
}

#[test]
fn an_unsupported_texture_format() {
    // A BMP's signature, under a .png name: the bytes decide.
    fails(
        &scene(json!({"texture": "wood.png"})),
        &[(
            "wood.png",
            b"BM\x3a\x00\x00\x00\x00\x00\x00\x00\x36\x00\x00\x00",
        )],
        "shaders.floor.diffuse.texture",
        &["wood.png", "PNG or JPEG"],
    );
}

#[test]
fn an_unknown_filter_name() {
    fails(
        &scene(json!({"texture": "wood.png", "filter": "anisotropic"})),
        &[("wood.png", &png())],
        "shaders.floor.diffuse.filter",
        &["unknown filter \"anisotropic\"", "trilinear"],
    );
}

#[test]
fn an_unknown_wrap_name() {
    fails(
        &scene(json!({"texture": "wood.png", "wrap": ["repeat", "border"]})),
        &[("wood.png", &png())],
        "shaders.floor.diffuse.wrap[1]",
        &["unknown wrap mode \"border\"", "clamp"],
    );
}

#[test]
fn a_texture_on_a_field_that_is_not_a_colour() {
    let mut v = scene(json!([1, 1, 1]));
    v["shaders"]["floor"]["shininess"] = json!({"texture": "wood.png"});
    fails(
        &v,
        &[("wood.png", &png())],
        "shaders.floor.shininess",
        &["can only be", "u32 Params"],
    );
}

#[test]
fn a_texture_for_a_params_field_that_is_not_u32() {
    let wgsl = b"struct Params { gain: f32, }
fn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32> { return vec3<f32>(p.gain); }
";
    let mut v = scene(json!([1, 1, 1]));
    v["shaders"]["ball"] =
        json!({"type": "wgsl", "file": "g.wgsl", "params": {"gain": {"texture": "wood.png"}}});
    fails(
        &v,
        &[("wood.png", &png()), ("g.wgsl", wgsl)],
        "shaders.ball.params.gain",
        &["g.wgsl", "f32", "only a u32 field"],
    );
}

#[test]
fn the_example_scene_renders() {
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/textured.json");
    let out_dir = tempfile::tempdir().unwrap();
    let png = out_dir.path().join("t.png");
    let out = Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .arg("render")
        .arg(&scene)
        .arg("-o")
        .arg(&png)
        .args(["--width", "160", "--height", "90"])
        .output()
        .expect("run penumbra");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        out.stderr.is_empty(),
        "no notes: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(image::image_dimensions(&png).unwrap(), (160, 90));
}
