//! Bad area-light and sampling input: one clear error naming the file and
//! field (or option), a non-zero exit, and no output file.

use std::process::Command;

fn base(light: &str) -> String {
    format!(
        r#"{{
  "camera": {{"position": [0, 2, 5], "look_at": [0, 0, 0], "width": 32, "height": 24}},
  "shaders": {{"w": {{"type": "phong", "diffuse": [1, 1, 1]}}}},
  "objects": [{{"type": "plane", "point": [0, 0, 0], "normal": [0, 1, 0], "shader": "w"}}],
  "lights": [{light}]
}}"#
    )
}

/// Runs `penumbra render` on the scene and returns (success, stderr, files
/// left in the output directory).
fn run(scene: &str, args: &[&str]) -> (bool, String, usize) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("scene.json");
    std::fs::write(&path, scene).unwrap();
    let out_dir = dir.path().join("out");
    std::fs::create_dir(&out_dir).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .arg("render")
        .arg(&path)
        .arg("-o")
        .arg(out_dir.join("image.png"))
        .args(args)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!stderr.contains("panicked"), "{stderr}");
    (
        out.status.success(),
        stderr,
        std::fs::read_dir(&out_dir).unwrap().count(),
    )
}

#[track_caller]
fn fails(scene: &str, args: &[&str], wanted: &[&str]) {
    let (ok, stderr, files) = run(scene, args);
    assert!(!ok, "should fail: {stderr}");
    assert!(stderr.starts_with("error: "), "{stderr}");
    for w in wanted {
        assert!(stderr.contains(w), "missing {w:?} in {stderr}");
    }
    assert_eq!(files, 0, "no output file: {stderr}");
}

const RECT: &str = r#"{"type": "rect", "corner": [-1, 3, -1], "edge1": [2, 0, 0], "edge2": [0, 0, 2], "samples": 4}"#;
const SPHERE: &str = r#"{"type": "sphere", "center": [0, 3, 0], "radius": 0.5, "samples": 4}"#;

#[test]
fn valid_area_lights_render() {
    for l in [RECT, SPHERE] {
        let (ok, stderr, files) = run(
            &base(l),
            &["--spp", "2", "--seed", "7", "--sampler", "random"],
        );
        assert!(ok && files == 1, "{stderr}");
    }
}

#[test]
fn degenerate_rectangles() {
    let zero = RECT.replace(r#""edge1": [2, 0, 0]"#, r#""edge1": [0, 0, 0]"#);
    fails(
        &base(&zero),
        &[],
        &["scene.json", "lights[0].edge2", "zero area"],
    );
    let parallel = RECT.replace(r#""edge2": [0, 0, 2]"#, r#""edge2": [4, 0, 0]"#);
    fails(&base(&parallel), &[], &["lights[0].edge2", "zero area"]);
    let missing = RECT.replace(r#", "edge2": [0, 0, 2]"#, "");
    fails(&base(&missing), &[], &["lights[0]", "edge2"]);
}

#[test]
fn bad_sphere_lights() {
    fails(
        &base(&SPHERE.replace("0.5", "0")),
        &[],
        &["lights[0].radius", "positive"],
    );
    fails(
        &base(&SPHERE.replace("0.5", "-1")),
        &[],
        &["lights[0].radius"],
    );
    let wrong_field = SPHERE.replace(r#""radius""#, r#""edge1": [1, 0, 0], "radius""#);
    fails(
        &base(&wrong_field),
        &[],
        &["lights[0].edge1", "not a field of a sphere light"],
    );
}

#[test]
fn zero_and_absurd_sample_counts() {
    fails(
        &base(&RECT.replace(r#""samples": 4"#, r#""samples": 0"#)),
        &[],
        &["lights[0].samples", "1..=4096"],
    );
    fails(
        &base(&RECT.replace(r#""samples": 4"#, r#""samples": 100000"#)),
        &[],
        &["lights[0].samples"],
    );
    fails(
        &base(&RECT.replace(r#""samples": 4"#, r#""samples": -3"#)),
        &[],
        &["lights[0].samples"],
    );
    let point = r#"{"type": "point", "position": [0, 3, 0], "samples": 4}"#;
    fails(
        &base(point),
        &[],
        &["lights[0].samples", "not a field of a point light"],
    );
    fails(&base(RECT), &["--area-samples", "0"], &["--area-samples"]);
    fails(
        &base(RECT),
        &["--area-samples", "9999"],
        &["--area-samples"],
    );
    fails(&base(RECT), &["--spp", "0"], &["--spp"]);
    fails(&base(RECT), &["--spp", "many"], &["--spp"]);
    fails(&base(RECT), &["--time-budget", "-1"], &["--time-budget"]);
    fails(&base(RECT), &["--time-budget", "NaN"], &["--time-budget"]);
    fails(&base(RECT), &["--sampler", "sobol"], &["--sampler"]);
}
