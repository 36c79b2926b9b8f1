//! The `penumbra` binary on bad input: every case must fail with a non-zero
//! exit status (no panic, no signal), print exactly one `error: ` line that
//! names the scene file and the offending field (or the command-line option),
//! and leave nothing behind in the output directory.
//!
//! Each scene case starts from one small valid scene ([`base`], which
//! `valid_base_scene_renders` checks) and changes one thing.

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use serde_json::{json, Value};
use tempfile::TempDir;

/// The valid starting point. Objects: 0 plane, 1 sphere, 2 triangle.
/// Lights: 0 directional, 1 point, 2 spot. Shaders: red, white, floor (checker).
fn base() -> Value {
    json!({
        "camera": {
            "position": [0, 1, 5], "look_at": [0, 0.5, 0], "up": [0, 1, 0],
            "fov": 45, "width": 64, "height": 48
        },
        "background": [0.1, 0.1, 0.2],
        "shaders": {
            "red": {"type": "phong", "ambient": [0.1, 0, 0], "diffuse": [0.8, 0.1, 0.1],
                    "specular": [0.5, 0.5, 0.5], "shininess": 20},
            "white": {"type": "blinn_phong", "diffuse": [0.8, 0.8, 0.8]},
            "floor": {"type": "checker", "size": 1, "even": "red", "odd": "white"}
        },
        "objects": [
            {"type": "plane", "point": [0, 0, 0], "normal": [0, 1, 0], "shader": "floor"},
            {"type": "sphere", "center": [0, 1, 0], "radius": 1, "shader": "red"},
            {"type": "triangle", "vertices": [[-2, 0, -1], [-1, 0, -1], [-1.5, 1, -1]], "shader": "white"}
        ],
        "lights": [
            {"type": "directional", "direction": [-1, -1, -1], "ambient": [0.1, 0.1, 0.1]},
            {"type": "point", "position": [2, 3, 2], "intensity": 10},
            {"type": "spot", "position": [0, 4, 0], "direction": [0, -1, 0],
             "inner_angle": 20, "outer_angle": 30, "intensity": 5}
        ]
    })
}

/// The base scene with one change.
fn mutated(change: impl FnOnce(&mut Value)) -> String {
    let mut v = base();
    change(&mut v);
    serde_json::to_string_pretty(&v).unwrap()
}

/// A scene file in its own temporary directory.
struct SceneFile {
    _dir: TempDir,
    path: PathBuf,
}

fn scene_file(name: &str, bytes: impl AsRef<[u8]>) -> SceneFile {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join(name);
    std::fs::write(&path, bytes).expect("write scene");
    SceneFile { _dir: dir, path }
}

fn penumbra(args: &[OsString], env: &[(&str, &str)]) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_penumbra"));
    cmd.args(args);
    if !env.is_empty() {
        // Without a driver the validation layer (CI runs the suite with it on)
        // would add the loader's own complaints to stderr.
        cmd.env_remove("PENUMBRA_VALIDATION");
    }
    for (k, v) in env {
        cmd.env(k, v);
    }
    cmd.output().expect("run penumbra")
}

/// The arguments `render SCENE -o OUTPUT` plus `extra`.
fn render_to(scene: &Path, output: &Path, extra: &[&str]) -> Vec<OsString> {
    let mut args: Vec<OsString> = vec!["render".into(), scene.into(), "-o".into(), output.into()];
    args.extend(extra.iter().map(OsString::from));
    args
}

/// The arguments `render SCENE -o OUT_DIR/out.png` plus `extra`.
fn render_args(scene: &Path, out_dir: &Path, extra: &[&str]) -> Vec<OsString> {
    render_to(scene, &out_dir.join("out.png"), extra)
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// Files left in `dir` (should be none after a failed run).
fn leftovers(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .expect("read output dir")
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect()
}

/// How strict to be about stderr's shape.
#[derive(Clone, Copy, PartialEq)]
enum Shape {
    /// Our own error: exactly one line, `error: ...`.
    OneLine,
    /// clap's usage error: starts with `error: `, followed by a usage hint.
    Clap,
    /// An error at a place in a source file: the `error: ...` line, then the
    /// source line and a caret line under the place.
    Source,
}

/// Asserts a clean failure: non-zero exit code (not a signal, not a panic),
/// the expected error shape containing every string of `must`, nothing on
/// stdout and an empty output directory (`out_dir`, allowed to keep `keep`).
#[track_caller]
fn assert_fails(
    out: &Output,
    out_dir: &Path,
    keep: &[&str],
    shape: Shape,
    must: &[&str],
) -> String {
    let stderr = text(&out.stderr);
    let stdout = text(&out.stdout);
    // Shown with `cargo test --test cli bad_input:: -- --nocapture`, to read every message.
    eprintln!("{stderr}");
    let ctx = format!(
        "status: {:?}\nstderr:\n{stderr}\nstdout:\n{stdout}",
        out.status
    );
    let code = out.status.code();
    assert!(code.is_some(), "killed by a signal\n{ctx}");
    assert_ne!(code, Some(0), "expected failure\n{ctx}");
    assert_ne!(code, Some(101), "exit code 101 means a panic\n{ctx}");
    assert!(
        !stderr.contains("panicked") && !stderr.contains("RUST_BACKTRACE"),
        "panic\n{ctx}"
    );
    assert!(
        stderr.starts_with("error: "),
        "stderr must start with `error: `\n{ctx}"
    );
    if shape == Shape::OneLine || shape == Shape::Source {
        let lines = if shape == Shape::OneLine { 1 } else { 3 };
        assert_eq!(
            stderr.trim_end().lines().count(),
            lines,
            "stderr must be {lines} line(s)\n{ctx}"
        );
        assert!(
            stderr.ends_with('\n'),
            "stderr must end with a newline\n{ctx}"
        );
    }
    // No clause twice (an error whose message also comes back as its
    // `source()` is printed twice by `{:#}`).
    let first = stderr.lines().next().unwrap_or_default();
    let clauses: Vec<&str> = first.split(": ").filter(|c| c.len() >= 12).collect();
    for (i, c) in clauses.iter().enumerate() {
        assert!(!clauses[i + 1..].contains(c), "{c:?} is repeated\n{ctx}");
    }
    for m in must {
        assert!(stderr.contains(m), "stderr must mention {m:?}\n{ctx}");
    }
    assert!(stdout.is_empty(), "nothing on stdout on failure\n{ctx}");
    let left: Vec<String> = leftovers(out_dir)
        .into_iter()
        .filter(|f| !keep.contains(&f.as_str()))
        .collect();
    assert!(
        left.is_empty(),
        "files left in the output directory: {left:?}\n{ctx}"
    );
    stderr
}

/// Renders `scene` (given as file name + contents) into a fresh output
/// directory with `extra` arguments and asserts a clean one-line failure
/// naming the scene path and every string of `must`.
#[track_caller]
fn fails_with(name: &str, contents: impl AsRef<[u8]>, extra: &[&str], must: &[&str]) -> String {
    let scene = scene_file(name, contents);
    let out_dir = tempfile::tempdir().expect("tempdir");
    let out = penumbra(&render_args(&scene.path, out_dir.path(), extra), &[]);
    let path = scene.path.display().to_string();
    let mut all = vec![path.as_str()];
    all.extend_from_slice(must);
    assert_fails(&out, out_dir.path(), &[], Shape::OneLine, &all)
}

/// A JSON scene that fails with `field` and the other strings of `must`
/// named, in the form `file: field: message`.
#[track_caller]
fn json_fails(contents: &str, field: &str, must: &[&str]) -> String {
    let stderr = fails_with("scene.json", contents, &[], must);
    assert!(
        stderr.contains(&format!(": {field}: ")),
        "stderr must name the field `{field}` as `file: {field}: message`\nstderr:\n{stderr}"
    );
    stderr
}

// ---------------------------------------------------------------- positive

#[test]
fn valid_base_scene_renders() {
    let scene = scene_file("scene.json", mutated(|_| {}));
    let out_dir = tempfile::tempdir().unwrap();
    let png = out_dir.path().join("out.png");
    let args: Vec<OsString> = vec![
        "render".into(),
        scene.path.clone().into(),
        "-o".into(),
        png.clone().into(),
    ];
    let out = penumbra(&args, &[]);
    let (stdout, stderr) = (text(&out.stdout), text(&out.stderr));
    let ctx = format!(
        "status: {:?}\nstderr:\n{stderr}\nstdout:\n{stdout}",
        out.status
    );
    assert!(out.status.success(), "{ctx}");
    assert!(stderr.is_empty(), "no warnings or notes expected\n{ctx}");
    let lines: Vec<&str> = stdout.lines().collect();
    assert_eq!(lines.len(), 1, "one summary line\n{ctx}");
    assert!(
        lines[0].contains("Mrays/s") && lines[0].contains("primary"),
        "{ctx}"
    );
    assert!(lines[0].contains("64x48"), "{ctx}");
    assert_eq!(
        image::image_dimensions(&png).expect("read the PNG"),
        (64, 48)
    );
    assert_eq!(
        leftovers(out_dir.path()),
        vec!["out.png".to_string()],
        "no temporary files left"
    );

    // The command-line size overrides the scene's.
    let png2 = out_dir.path().join("small.png");
    let args: Vec<OsString> = vec![
        "render".into(),
        scene.path.clone().into(),
        "-o".into(),
        png2.clone().into(),
        "--width".into(),
        "20".into(),
        "--height".into(),
        "10".into(),
    ];
    let out = penumbra(&args, &[]);
    assert!(out.status.success(), "stderr:\n{}", text(&out.stderr));
    assert_eq!(
        image::image_dimensions(&png2).expect("read the PNG"),
        (20, 10)
    );
}

// ------------------------------------------------------------- the tables
//
// Each row of these tables is one `#[test]`, named by its first column, so
// that every case is run and reported on its own.

/// Rows `name: |v| change => "field", [must...];`: the base scene with the
/// change fails in the form `file: field: message`, naming the scene file,
/// the field and every string of `must` ([`json_fails`]).
macro_rules! field_cases {
    ($($name:ident: |$v:ident| $change:expr => $field:literal, [$($must:expr),+ $(,)?];)+) => {$(
        #[test]
        fn $name() {
            let s = mutated(|$v| {
                $change;
            });
            json_fails(&s, $field, &[$($must),+]);
        }
    )+};
}

/// Rows `name: (file name, contents) => [must...];`: a scene file with these
/// contents fails naming its path and every string of `must` ([`fails_with`]).
macro_rules! file_cases {
    ($($name:ident: ($file:literal, $contents:expr) => [$($must:expr),+ $(,)?];)+) => {$(
        #[test]
        fn $name() {
            fails_with($file, $contents, &[], &[$($must),+]);
        }
    )+};
}

/// Rows `name: [args...] => shape, [must...];`: the valid base scene rendered
/// with these extra arguments fails in `shape`, naming every string of
/// `must` ([`cli_fails`]).
macro_rules! cli_cases {
    ($($name:ident: [$($arg:expr),+] => $shape:ident, [$($must:expr),+ $(,)?];)+) => {$(
        #[test]
        fn $name() {
            cli_fails(&[$($arg),+], Shape::$shape, &[$($must),+]);
        }
    )+};
}

/// Rows `name: "path" => [must...];`: the valid base scene rendered to
/// `path` (relative to a fresh output directory) fails naming the output
/// path and every string of `must` ([`output_fails`]).
macro_rules! output_cases {
    ($($name:ident: $target:literal => [$($must:expr),+ $(,)?];)+) => {$(
        #[test]
        fn $name() {
            output_fails($target, &[$($must),+]);
        }
    )+};
}

/// Rows `name: file, params, raw => "field", shape, [must...];`: the base
/// scene whose sphere uses the WGSL shader `file` with `params` (and `raw`
/// text replacements, see [`wgsl_scene`]) fails in `shape`, naming the scene
/// file, the field and every string of `must` ([`wgsl_fails`]).
macro_rules! wgsl_cases {
    ($($name:ident: $file:literal, $params:expr, $raw:expr => $field:literal, $shape:ident, [$($must:expr),+ $(,)?];)+) => {$(
        #[test]
        fn $name() {
            wgsl_fails($file, $params, $raw, $field, Shape::$shape, &[$($must),+]);
        }
    )+};
}

/// Renders `render <valid scene> -o <fresh dir>/target` and asserts a clean
/// one-line failure naming the output path and every string of `must`.
#[track_caller]
fn output_fails(target: &str, must: &[&str]) -> String {
    let scene = scene_file("scene.json", mutated(|_| {}));
    let out_dir = tempfile::tempdir().unwrap();
    let target = out_dir.path().join(target);
    let t = target.display().to_string();
    let mut all = vec![t.as_str()];
    all.extend_from_slice(must);
    assert_fails(
        &penumbra(&render_to(&scene.path, &target, &[]), &[]),
        out_dir.path(),
        &[],
        Shape::OneLine,
        &all,
    )
}

// ------------------------------------------------------- structure / types

file_cases! {
    unknown_top_level_field: ("scene.json", mutated(|v| v["fog"] = json!(0.5)))
        => ["unknown field `fog`"];
    unknown_field_in_object: ("scene.json", mutated(|v| v["objects"][1]["colour"] = json!([1, 0, 0])))
        => ["objects[1]", "unknown field `colour`"];
}

field_cases! {
    missing_camera_width: |v| v["camera"].as_object_mut().unwrap().remove("width")
        => "camera", ["missing field `width`"];
    sphere_without_radius: |v| v["objects"][1].as_object_mut().unwrap().remove("radius")
        => "objects[1]", ["`radius`", "sphere"];
    radius_is_a_string: |v| v["objects"][1]["radius"] = json!("1")
        => "objects[1].radius", ["invalid type"];
    position_with_two_numbers: |v| v["camera"]["position"] = json!([0, 1])
        => "camera.position", ["invalid length 2"];
    sphere_with_normal: |v| v["objects"][1]["normal"] = json!([0, 1, 0])
        => "objects[1].normal", ["not a field of a sphere"];
}

file_cases! {
    unknown_object_type: ("scene.json", mutated(|v| v["objects"][1]["type"] = json!("cube")))
        => ["objects[1]", "unknown variant `cube`"];
}

#[test]
fn non_finite_number() {
    // serde_json cannot represent 1e999 as f64 and refuses it while parsing.
    let s = mutated(|_| {}).replace("\"radius\": 1", "\"radius\": 1e999");
    assert!(s.contains("1e999"));
    json_fails(&s, "objects[1].radius", &["number out of range"]);
}

// ------------------------------------------------------------------ values

field_cases! {
    negative_radius: |v| v["objects"][1]["radius"] = json!(-1.0)
        => "objects[1].radius", ["must be positive", "-1"];
    zero_radius: |v| v["objects"][1]["radius"] = json!(0)
        => "objects[1].radius", ["must be positive"];
    // 1e39 is a finite f64 but no f32: the kernel could not even store it.
    vertex_beyond_f32: |v| v["objects"][2]["vertices"][2] = json!([0, 1e39, 0])
        => "objects[2].vertices[2]", ["must lie within ±1e18", "f32"];
    sphere_radius_beyond_the_coordinate_limit: |v| v["objects"][1]["radius"] = json!(1e30)
        => "objects[1].radius", ["at most 1e18", "1e30"];
    light_position_beyond_the_coordinate_limit: |v| v["lights"][1]["position"] = json!([2, 1e20, 2])
        => "lights[1].position", ["must lie within ±1e18"];
}

#[test]
fn mesh_scaled_beyond_the_coordinate_limit() {
    let bunny = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/bunny.glb");
    let s = mutated(|v| {
        v["objects"].as_array_mut().unwrap().push(json!({
            "type": "mesh", "file": bunny, "shader": "red",
            "transform": {"scale": 1e30}
        }));
    });
    fails_with(
        "scene.json",
        s,
        &[],
        &["objects[3].positions[", "must lie within ±1e18"],
    );
}

field_cases! {
    zero_plane_normal: |v| v["objects"][0]["normal"] = json!([0, 0, 0])
        => "objects[0].normal", ["non-zero"];
    zero_light_direction: |v| v["lights"][0]["direction"] = json!([0, 0, 0])
        => "lights[0].direction", ["non-zero"];
    camera_up_parallel_to_view: |v| v["camera"]["up"] = json!([0, 0.5, 5])
        => "camera.up", ["parallel"];
    look_at_equals_position: |v| v["camera"]["look_at"] = json!([0, 1, 5])
        => "camera.look_at", ["camera.position"];
    look_at_and_yaw: |v| v["camera"]["yaw"] = json!(10)
        => "camera", ["look_at", "yaw"];
}

#[test]
fn fov_out_of_range() {
    for fov in [json!(0), json!(180), json!(-5), json!(200)] {
        let s = mutated(|v| v["camera"]["fov"] = fov.clone());
        json_fails(&s, "camera.fov", &["(0, 180)", &format!("got {fov}")]);
    }
}

field_cases! {
    scene_width_zero: |v| v["camera"]["width"] = json!(0)
        => "camera.width", ["1..=16384", "got 0"];
    scene_width_above_maximum: |v| v["camera"]["width"] = json!(20000)
        => "camera.width", ["1..=16384", "got 20000"];
}

#[test]
fn image_larger_than_one_render_holds() {
    // 16384 x 16384 x 16 bytes = 4 GiB, above the 1 GiB one render holds
    // (render::bands::MAX_IMAGE_BYTES); tiles of a split render can.
    let s = mutated(|_| {});
    let e = fails_with(
        "scene.json",
        s,
        &["--width", "16384", "--height", "16384"],
        &["1024 MiB one render holds", "16384x16384", "--tile"],
    );
    assert!(
        e.contains(": --width/--height: "),
        "must name the option\n{e}"
    );
    // The same from the scene file names the scene field.
    let s = mutated(|v| {
        v["camera"]["width"] = json!(16384);
        v["camera"]["height"] = json!(16384);
    });
    let e = json_fails(
        &s,
        "camera.width/camera.height",
        &["1024 MiB one render holds", "16384x16384"],
    );
    // The field is the scene's (the advice names the tile option).
    assert!(!e.contains(": --width"), "no option was given\n{e}");
}

// ------------------------------------------------------------ command line

/// Runs `render <valid scene> -o <fresh dir>/out.png` plus `extra` and
/// asserts a clean failure mentioning `must`.
#[track_caller]
fn cli_fails(extra: &[&str], shape: Shape, must: &[&str]) -> String {
    let scene = scene_file("scene.json", mutated(|_| {}));
    let out_dir = tempfile::tempdir().unwrap();
    let args = render_args(&scene.path, out_dir.path(), extra);
    assert_fails(&penumbra(&args, &[]), out_dir.path(), &[], shape, must)
}

cli_cases! {
    cli_width_zero: ["--width", "0"] => Clap, ["--width"];
    cli_width_not_a_number: ["--width", "abc"] => Clap, ["--width", "abc"];
    cli_width_above_maximum: ["--width", "20000"] => Clap, ["--width", "20000"];
    cli_unknown_device: ["--device", "nosuchdevice"] => OneLine, ["nosuchdevice", "available: 0: "];
    cli_unknown_gltf_materials: ["--gltf-materials", "pbr"] => Clap, ["--gltf-materials", "pbr", "metallic-roughness"];
    cli_exposure_not_a_number: ["--exposure", "nan"] => Clap, ["--exposure", "nan", "finite"];
    cli_exposure_out_of_range: ["--exposure", "-100"] => Clap, ["--exposure", "-100", "[-64, 64]"];
    cli_unknown_tonemap: ["--tonemap", "filmic"] => Clap, ["--tonemap", "filmic", "pbr-neutral"];
    cli_environment_negative: ["--environment", "-1"] => Clap, ["--environment", "-1", "[0, 1e6]"];
    cli_environment_not_a_number: ["--environment", "bright"] => Clap, ["--environment", "bright", "finite"];
    cli_background_two_values: ["--background", "0.5,0.5"] => Clap, ["--background", "0.5,0.5", "R,G,B"];
    cli_background_infinite: ["--background", "0,inf,0"] => Clap, ["--background", "0,inf,0", "finite"];
    cli_background_negative: ["--background", "0,-1,0"] => Clap, ["--background", "0,-1,0", "[0, 1e6]"];
}

#[test]
fn cli_shader_directory_missing() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("no_shaders");
    let m = missing.display().to_string();
    cli_fails(
        &["--shaders", &m],
        Shape::OneLine,
        &["shader error", &m, "cannot read shader"],
    );
}

// ----------------------------------------------------------------- shaders

field_cases! {
    object_refers_to_unknown_shader: |v| v["objects"][1]["shader"] = json!("nope")
        => "objects[1].shader", ["no shader named \"nope\""];
    checker_refers_to_unknown_shader: |v| v["shaders"]["floor"]["odd"] = json!("nope")
        => "shaders.floor.odd", ["no shader named \"nope\""];
}

#[test]
fn checker_cycle() {
    let s = mutated(|v| {
        v["shaders"]["a"] = json!({"type": "checker", "size": 1, "even": "b", "odd": "red"});
        v["shaders"]["b"] = json!({"type": "checker", "size": 1, "even": "a", "odd": "white"});
        v["objects"][1]["shader"] = json!("a");
    });
    let e = fails_with("scene.json", s, &[], &["cycle"]);
    // Named as in the file (`shaders.a`), not by an internal index.
    assert!(
        e.contains(": shaders.a") || e.contains(": shaders.b"),
        "must name the shader by its name\n{e}"
    );
}

field_cases! {
    checker_size_zero: |v| v["shaders"]["floor"]["size"] = json!(0)
        => "shaders.floor.size", ["must be positive"];
    negative_colour_component: |v| v["shaders"]["red"]["diffuse"] = json!([0.8, -0.1, 0.1])
        => "shaders.red.diffuse", ["non-negative"];
    negative_background_component: |v| v["background"] = json!([0, 0, -1])
        => "background", ["non-negative"];
    negative_shininess: |v| v["shaders"]["red"]["shininess"] = json!(-2)
        => "shaders.red.shininess", [">= 0"];
    roughness_above_one: |v| v["shaders"]["red"] = json!({"type": "metallic_roughness", "roughness": 1.5})
        => "shaders.red.roughness", ["[0, 1]", "1.5"];
    negative_metallic: |v| v["shaders"]["red"] = json!({"type": "metallic_roughness", "metallic": -0.1})
        => "shaders.red.metallic", ["[0, 1]"];
    negative_base_colour: |v| v["shaders"]["red"] = json!({"type": "metallic_roughness", "base_colour": [0.5, -1, 0]})
        => "shaders.red.base_colour", ["non-negative"];
    shininess_of_metallic_roughness: |v| v["shaders"]["red"] = json!({"type": "metallic_roughness", "shininess": 3})
        => "shaders.red.shininess", ["not a field of a metallic_roughness shader"];
    params_of_metallic_roughness: |v| v["shaders"]["red"] = json!({"type": "metallic_roughness", "params": {"x": 1}})
        => "shaders.red.params", ["not a field of a metallic_roughness shader"];
    roughness_of_phong: |v| v["shaders"]["red"]["roughness"] = json!(0.5)
        => "shaders.red.roughness", ["not a field of a phong shader"];
    glossiness_above_one: |v| v["shaders"]["red"] = json!({"type": "specular_glossiness", "glossiness": 2})
        => "shaders.red.glossiness", ["[0, 1]", "2"];
    negative_specular_of_specular_glossiness: |v| v["shaders"]["red"] = json!({"type": "specular_glossiness", "specular": [0, -1, 0]})
        => "shaders.red.specular", ["non-negative"];
    glossiness_of_metallic_roughness: |v| v["shaders"]["red"] = json!({"type": "metallic_roughness", "glossiness": 0.5})
        => "shaders.red.glossiness", ["not a field of a metallic_roughness shader"];
    metallic_roughness_not_a_texture: |v| v["shaders"]["red"] = json!({"type": "metallic_roughness", "metallic_roughness": [1, 1, 1]})
        => "shaders.red.metallic_roughness", ["must be a texture"];
}

// ------------------------------------------------------------------ lights

#[test]
fn spot_inner_not_below_outer() {
    for inner in [30, 40] {
        let s = mutated(|v| v["lights"][2]["inner_angle"] = json!(inner));
        json_fails(&s, "lights[2].inner_angle", &["outer_angle"]);
    }
}

field_cases! {
    spot_outer_above_90: |v| v["lights"][2]["outer_angle"] = json!(100)
        => "lights[2].outer_angle", ["90"];
    negative_intensity: |v| v["lights"][1]["intensity"] = json!(-1)
        => "lights[1].intensity", [">= 0"];
    negative_light_colour: |v| v["lights"][0]["ambient"] = json!([-0.1, 0, 0])
        => "lights[0].ambient", ["non-negative"];
    environment_zero_up: |v| v["lights"][0] = json!({"type": "environment", "up": [0, 0, 0]})
        => "lights[0].up", ["non-zero"];
    environment_zero_samples: |v| v["lights"][0] = json!({"type": "environment", "samples": 0})
        => "lights[0].samples", ["1..=4096"];
    up_not_a_field_of_a_point_light: |v| v["lights"][1]["up"] = json!([0, 1, 0])
        => "lights[1].up", ["not a field of a point light"];
}

// ------------------------------------------------------------------- files

field_cases! {
    mesh_file_missing: |v| v["objects"]
        .as_array_mut()
        .unwrap()
        .push(json!({"type": "mesh", "file": "missing.glb"}))
        => "objects[3].file", ["missing.glb"];
}

#[test]
fn scene_file_does_not_exist() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("nothing.json");
    let out_dir = tempfile::tempdir().unwrap();
    let args = render_args(&path, out_dir.path(), &[]);
    let p = path.display().to_string();
    assert_fails(
        &penumbra(&args, &[]),
        out_dir.path(),
        &[],
        Shape::OneLine,
        &[&p, "cannot read scene"],
    );
}

file_cases! {
    scene_file_is_garbage_bytes: ("scene.json", [0xffu8, 0xfe, 0x00, 0x13, 0x80, 0x7b, 0x22])
        => ["cannot read scene"];
    scene_file_is_not_json: ("scene.json", "camera = { width = 64 }\n")
        => ["expected value", "line 1"];
    scene_file_is_empty: ("scene.json", "") => ["EOF"];
    scene_file_with_unsupported_extension: ("scene.txt", mutated(|_| {}))
        => ["unknown scene format", ".json"];
}

output_cases! {
    output_directory_does_not_exist: "no/such/out.png" => ["cannot write", "does not exist"];
    output_with_unsupported_extension: "out.jpg" => ["unknown output format", ".png"];
}

#[test]
fn output_is_a_directory() {
    let scene = scene_file("scene.json", mutated(|_| {}));
    let out_dir = tempfile::tempdir().unwrap();
    // A directory with an image name gets past the extension check and must
    // be refused before rendering; one without is refused for its name.
    for (name, why) in [
        ("out.png", "is a directory"),
        ("plain_dir", "unknown output format"),
    ] {
        let target = out_dir.path().join(name);
        std::fs::create_dir(&target).unwrap();
        let args = render_to(&scene.path, &target, &[]);
        let t = target.display().to_string();
        assert_fails(
            &penumbra(&args, &[]),
            out_dir.path(),
            &["out.png", "plain_dir"],
            Shape::OneLine,
            &[&t, why],
        );
        assert!(target.is_dir(), "the directory must survive");
        assert_eq!(
            leftovers(&target),
            Vec::<String>::new(),
            "nothing written inside it"
        );
    }
}

// ------------------------------------------------------------------ Vulkan

const NO_DRIVER: [(&str, &str); 2] = [
    ("VK_ICD_FILENAMES", "/nonexistent.json"),
    ("VK_DRIVER_FILES", "/nonexistent.json"),
];

#[test]
fn no_vulkan_driver_render() {
    let scene = scene_file("scene.json", mutated(|_| {}));
    let out_dir = tempfile::tempdir().unwrap();
    let args = render_args(&scene.path, out_dir.path(), &[]);
    let e = assert_fails(
        &penumbra(&args, &NO_DRIVER),
        out_dir.path(),
        &[],
        Shape::OneLine,
        &["lavapipe", "tools/setup.sh"],
    );
    assert!(e.contains("apt-get install"), "{e}");
}

#[test]
fn no_vulkan_driver_devices() {
    let out_dir = tempfile::tempdir().unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .arg("devices")
        .current_dir(out_dir.path())
        .env_remove("PENUMBRA_VALIDATION")
        .envs(NO_DRIVER)
        .output()
        .unwrap();
    let e = assert_fails(
        &out,
        out_dir.path(),
        &[],
        Shape::OneLine,
        &["lavapipe", "tools/setup.sh"],
    );
    assert!(e.contains("apt-get install"), "{e}");
}

// ------------------------------------------------- untrusted files (fuzzing)

/// The regression files of the fuzzing harness (tests/data/fuzz), each
/// copied into its own folder beside the traps its URIs name: a FIFO
/// `fifo.bin` and a file `../outside.bin` outside the scene's folder.
struct Trapped {
    _dir: TempDir,
    scene: PathBuf,
}

fn trapped(name: &str) -> Trapped {
    let dir = tempfile::tempdir().expect("tempdir");
    let folder = dir.path().join("scene");
    std::fs::create_dir(&folder).unwrap();
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/fuzz");
    let scene = folder.join(name);
    std::fs::copy(data.join(name), &scene).expect("copy regression file");
    std::fs::write(dir.path().join("outside.bin"), [0u8; 64]).unwrap();
    let fifo = std::ffi::CString::new(
        folder
            .join("fifo.bin")
            .into_os_string()
            .into_encoded_bytes(),
    )
    .unwrap();
    // SAFETY: a valid NUL-terminated path.
    assert_eq!(unsafe { libc::mkfifo(fifo.as_ptr(), 0o600) }, 0, "mkfifo");
    Trapped { _dir: dir, scene }
}

#[test]
fn fuzzing_regressions_fail_with_their_errors() {
    // (file, field, message): each fails at once, without a panic, a hang on
    // the FIFO or reading /dev/zero, or expanding the sparse accessor.
    let cases = [
        (
            "camera_type_mismatch.gltf",
            "cameras[0].orthographic",
            "the camera's type is \"orthographic\" but it has no `orthographic` object",
        ),
        (
            "sparse_amplification.gltf",
            "meshes[0].primitives[0]",
            "more than the scene memory budget of 4096.0 MiB",
        ),
        (
            "buffer_dev_zero.gltf",
            "buffers[0].uri",
            "the buffer /dev/zero is not a regular file",
        ),
        (
            "buffer_fifo.gltf",
            "buffers[0].uri",
            "fifo.bin is not a regular file",
        ),
    ];
    for (name, field, message) in cases {
        let t = trapped(name);
        let out_dir = tempfile::tempdir().unwrap();
        let out = penumbra(&render_args(&t.scene, out_dir.path(), &[]), &[]);
        let scene = t.scene.display().to_string();
        let field = format!(": {field}: ");
        assert_fails(
            &out,
            out_dir.path(),
            &[],
            Shape::OneLine,
            &[&scene, &field, message],
        );
    }
}

#[test]
fn restrict_paths_refuses_files_outside_the_scene_folder() {
    let t = trapped("buffer_outside.gltf");
    let out_dir = tempfile::tempdir().unwrap();
    let out = penumbra(
        &render_args(&t.scene, out_dir.path(), &["--restrict-paths"]),
        &[],
    );
    assert_fails(
        &out,
        out_dir.path(),
        &[],
        Shape::OneLine,
        &[
            ": buffers[0].uri: ",
            "outside.bin lies outside the scene's folder",
            "(--restrict-paths)",
        ],
    );
    // Without the flag the same file is read: it renders.
    let out = penumbra(&render_args(&t.scene, out_dir.path(), &[]), &[]);
    assert!(out.status.success(), "stderr:\n{}", text(&out.stderr));
    assert!(out_dir.path().join("out.png").is_file());
}

#[test]
fn restrict_paths_refuses_a_json_mesh_outside_the_scene_folder() {
    let dir = tempfile::tempdir().unwrap();
    let folder = dir.path().join("scene");
    std::fs::create_dir(&folder).unwrap();
    let bunny = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/bunny.glb");
    std::fs::copy(bunny, dir.path().join("bunny.glb")).unwrap();
    let scene = folder.join("scene.json");
    let json = mutated(|v| {
        v["objects"]
            .as_array_mut()
            .unwrap()
            .push(json!({"type": "mesh", "file": "../bunny.glb"}))
    });
    std::fs::write(&scene, json).unwrap();
    let out_dir = tempfile::tempdir().unwrap();
    let out = penumbra(
        &render_args(&scene, out_dir.path(), &["--restrict-paths"]),
        &[],
    );
    assert_fails(
        &out,
        out_dir.path(),
        &[],
        Shape::OneLine,
        &[
            ": objects[3].file: ",
            "bunny.glb lies outside the scene's folder",
        ],
    );
}

#[test]
fn max_scene_memory_bounds_the_geometry() {
    // Twelve instances of the bunny (each about 0.4 MiB as loaded) exceed 1 MiB.
    let dir = tempfile::tempdir().unwrap();
    let bunny = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/bunny.glb");
    std::fs::copy(bunny, dir.path().join("bunny.glb")).unwrap();
    let scene = dir.path().join("scene.json");
    let json = mutated(|v| {
        for _ in 0..12 {
            let mesh = json!({"type": "mesh", "file": "bunny.glb"});
            v["objects"].as_array_mut().unwrap().push(mesh);
        }
    });
    std::fs::write(&scene, json).unwrap();
    let out_dir = tempfile::tempdir().unwrap();
    let out = penumbra(
        &render_args(&scene, out_dir.path(), &["--max-scene-memory", "1"]),
        &[],
    );
    assert_fails(
        &out,
        out_dir.path(),
        &[],
        Shape::OneLine,
        &[
            "bunny.glb: ",
            "scene memory budget of 1.0 MiB (1048576 bytes, --max-scene-memory)",
        ],
    );
    let out = penumbra(
        &render_args(&scene, out_dir.path(), &["--max-scene-memory", "0"]),
        &[],
    );
    assert_fails(
        &out,
        out_dir.path(),
        &[],
        Shape::Clap,
        &["--max-scene-memory"],
    );
}

#[test]
fn an_internal_error_is_one_line_naming_the_file_and_leaves_no_output() {
    let scene = scene_file("scene.json", mutated(|_| {}));
    let out_dir = tempfile::tempdir().unwrap();
    let args = render_args(&scene.path, out_dir.path(), &["--reference"]);
    let out = penumbra(&args, &[("PENUMBRA_TEST_INTERNAL_ERROR", "1")]);
    assert_eq!(
        out.status.code(),
        Some(70),
        "stderr:\n{}",
        text(&out.stderr)
    );
    let p = scene.path.display().to_string();
    assert_fails(
        &out,
        out_dir.path(),
        &[],
        Shape::OneLine,
        &[
            &p,
            "internal error: PENUMBRA_TEST_INTERNAL_ERROR is set",
            "a bug in penumbra",
        ],
    );
}

#[test]
fn merge_refuses_a_part_claiming_an_image_larger_than_a_render() {
    // A part file of 2.7 KiB whose windows claim a 2^20 x 2^20 image: refused
    // from its header, before any pixel buffer is allocated.
    let part = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/fuzz/part_huge_window.exr");
    let out_dir = tempfile::tempdir().unwrap();
    let args: Vec<OsString> = vec![
        "merge".into(),
        part.clone().into(),
        "-o".into(),
        out_dir.path().join("out.png").into(),
    ];
    let out = penumbra(&args, &[]);
    let must = format!(
        "{}: displayWindow: 1048576x1048576 is larger than a render can be (16384 pixels a side)",
        part.display()
    );
    assert_fails(&out, out_dir.path(), &[], Shape::OneLine, &[&must]);
}

// ------------------------------------------------------------ WGSL shaders

/// The base scene whose sphere uses the shader `toon` of type `wgsl` from
/// `file` (copied from `tests/data/shaders/` into the scene's folder) with
/// `params` (left out when `None`). `raw` replaces text of the JSON, for
/// numbers that `json!` cannot hold. Returns the folder and the scene path.
fn wgsl_scene(file: &str, params: Option<Value>, raw: &[(&str, &str)]) -> (TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/shaders");
    if data.join(file).is_file() {
        std::fs::copy(data.join(file), dir.path().join(file)).unwrap();
    }
    let mut json = mutated(|v| {
        let mut toon = json!({"type": "wgsl", "file": file});
        if let Some(p) = params {
            toon["params"] = p;
        }
        v["shaders"]["toon"] = toon;
        v["objects"][1]["shader"] = json!("toon");
    });
    for (from, to) in raw {
        assert!(json.contains(from), "{from} not in the scene");
        json = json.replace(from, to);
    }
    let scene = dir.path().join("scene.json");
    std::fs::write(&scene, json).unwrap();
    (dir, scene)
}

/// Valid params of `toon.wgsl` with one change.
fn toon_params(change: impl FnOnce(&mut Value)) -> Option<Value> {
    let mut p = json!({"base": [0.9, 0.3, 0.2], "bands": 4, "gain": 1.5});
    change(&mut p);
    Some(p)
}

/// Renders the scene of [`wgsl_scene`] and asserts a clean failure of
/// `shape` naming the scene file, `field` as `: field: `, and every string
/// of `must`.
#[track_caller]
fn wgsl_fails(
    file: &str,
    params: Option<Value>,
    raw: &[(&str, &str)],
    field: &str,
    shape: Shape,
    must: &[&str],
) -> String {
    let (_dir, scene) = wgsl_scene(file, params, raw);
    let out_dir = tempfile::tempdir().unwrap();
    let out = penumbra(&render_args(&scene, out_dir.path(), &[]), &[]);
    let path = scene.display().to_string();
    let at = format!(": {field}: ");
    let mut all = vec![path.as_str(), at.as_str()];
    all.extend_from_slice(must);
    assert_fails(&out, out_dir.path(), &[], shape, &all)
}

wgsl_cases! {
    wgsl_shader_without_shade: "no_shade.wgsl", None, &[] => "shaders.toon.file", OneLine, [
        "no_shade.wgsl: ",
        "no `fn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32>`",
    ];
    wgsl_shade_with_the_wrong_return_type: "shade_returns_f32.wgsl", None, &[] => "shaders.toon.file", Source, [
        "shade_returns_f32.wgsl:2:",
        "`shade` returns f32, it must be `fn shade(Surface, LightSample, Params) -> vec3<f32>`",
    ];
}

#[test]
fn wgsl_syntax_error_points_into_the_users_file() {
    let stderr = wgsl_fails(
        "syntax_error.wgsl",
        None,
        &[],
        "shaders.toon.file",
        Shape::Source,
        &["syntax_error.wgsl:4:13: "],
    );
    let lines: Vec<&str> = stderr.lines().collect();
    assert_eq!(lines[1], " 4 |     let q = ;", "{stderr}");
    assert_eq!(lines[2], "   |             ^", "{stderr}");
}

wgsl_cases! {
    wgsl_file_missing: "missing.wgsl", None, &[] => "shaders.toon.file", OneLine, [
        "no such file",
        "missing.wgsl",
    ];
    wgsl_params_field_missing: "toon.wgsl", toon_params(|p| {
        p.as_object_mut().unwrap().remove("bands");
    }), &[] => "shaders.toon.params.bands", OneLine, [
        "missing: Params field `bands: u32` of toon.wgsl has no value",
    ];
    // Without `params` at all, the first field is missing.
    wgsl_params_left_out_miss_the_first_field: "toon.wgsl", None, &[] => "shaders.toon.params.base", OneLine, [
        "missing: Params field `base: vec3<f32>` of toon.wgsl has no value",
    ];
    wgsl_params_extra_field: "toon.wgsl", toon_params(|p| p["extra"] = json!(1)), &[]
        => "shaders.toon.params.extra", OneLine, ["toon.wgsl's Params has no field `extra`"];
    // A file without Params takes no params.
    wgsl_params_for_a_file_without_params: "plain.wgsl", Some(json!({"gain": 1})), &[]
        => "shaders.toon.params.gain", OneLine, ["plain.wgsl's Params has no field `gain`"];
    wgsl_params_of_the_wrong_type: "toon.wgsl", toon_params(|p| p["gain"] = json!("bright")), &[]
        => "shaders.toon.params.gain", OneLine, [
        "Params field `gain` of toon.wgsl is f32, expected a number, got a string",
    ];
    wgsl_params_vec3_of_two_numbers: "toon.wgsl", toon_params(|p| p["base"] = json!([0.9, 0.3])), &[]
        => "shaders.toon.params.base", OneLine, [
        "Params field `base` of toon.wgsl is vec3<f32>, expected an array of 3 numbers, got 2",
    ];
    wgsl_params_u32_of_a_fraction: "toon.wgsl", toon_params(|p| p["bands"] = json!(1.5)), &[]
        => "shaders.toon.params.bands", OneLine, [
        "Params field `bands` of toon.wgsl is u32, expected an integer in 0..=4294967295, got 1.5",
    ];
    wgsl_params_u32_of_a_negative_number: "toon.wgsl", toon_params(|p| p["bands"] = json!(-1)), &[]
        => "shaders.toon.params.bands", OneLine, ["is u32, expected an integer", "got -1"];
    // Beyond f64: serde_json refuses the number while parsing, at its path.
    wgsl_params_not_finite: "toon.wgsl", toon_params(|p| p["gain"] = json!("HUGE")), &[("\"HUGE\"", "1e999")]
        => "shaders.toon.params.gain", OneLine, ["number out of range"];
    // Beyond f32: finite as JSON, infinite as the shader's f32.
    wgsl_params_beyond_f32: "toon.wgsl", toon_params(|p| p["base"] = json!([0.9, 1e39, 0.2])), &[]
        => "shaders.toon.params.base", OneLine, [
        "Params field `base` of toon.wgsl is vec3<f32>, expected a finite number, got 1e39",
    ];
}
#[test]
fn reference_refuses_a_wgsl_shader() {
    let (_dir, scene) = wgsl_scene("toon.wgsl", toon_params(|_| {}), &[]);
    let out_dir = tempfile::tempdir().unwrap();
    let out = penumbra(&render_args(&scene, out_dir.path(), &["--reference"]), &[]);
    let path = scene.display().to_string();
    assert_fails(
        &out,
        out_dir.path(),
        &[],
        Shape::OneLine,
        &[
            &path,
            "the f64 reference renders only the built-in shaders (phong, blinn_phong, metallic_roughness, checker)",
            "is a WGSL file",
            "toon.wgsl",
        ],
    );
}

// ------------------------------------------- untrusted files (issue 36, C)

/// A PNG of `side`×`side` 1-bit grey texels, all black: a few KB that
/// claim `side`² texels.
fn png_bomb(side: u32) -> Vec<u8> {
    let mut out = Vec::new();
    let mut encoder = png::Encoder::new(&mut out, side, side);
    encoder.set_color(png::ColorType::Grayscale);
    encoder.set_depth(png::BitDepth::One);
    encoder.set_compression(png::Compression::Fast);
    let mut writer = encoder.write_header().unwrap();
    let mut stream = writer.stream_writer().unwrap();
    let row = vec![0u8; side.div_ceil(8) as usize];
    for _ in 0..side {
        std::io::Write::write_all(&mut stream, &row).unwrap();
    }
    stream.finish().unwrap();
    writer.finish().unwrap();
    out
}

/// A valid 16×16 JPEG whose frame header (SOF0) is patched to claim
/// `side`×`side` texels.
fn jpeg_bomb(side: u16) -> Vec<u8> {
    let img = image::RgbImage::from_pixel(16, 16, image::Rgb([120, 90, 60]));
    let mut jpeg = Vec::new();
    img.write_to(
        &mut std::io::Cursor::new(&mut jpeg),
        image::ImageFormat::Jpeg,
    )
    .unwrap();
    // Markers from after SOI: FF xx, then a big-endian length.
    let mut i = 2;
    while jpeg[i + 1] != 0xC0 {
        i += 2 + usize::from(u16::from_be_bytes([jpeg[i + 2], jpeg[i + 3]]));
    }
    // SOF0: length (2), precision (1), height (2), width (2).
    jpeg[i + 5..i + 7].copy_from_slice(&side.to_be_bytes());
    jpeg[i + 7..i + 9].copy_from_slice(&side.to_be_bytes());
    jpeg
}

/// Renders the base scene with `image` (named `name`) as the red shader's
/// diffuse texture and `extra` arguments; asserts a clean failure naming
/// the scene, the texture's field, the image and every string of `must`.
#[track_caller]
fn texture_fails(name: &str, image: &[u8], extra: &[&str], must: &[&str]) -> String {
    let scene = scene_file(
        "scene.json",
        mutated(|v| v["shaders"]["red"]["diffuse"] = json!({"texture": name})),
    );
    std::fs::write(scene.path.with_file_name(name), image).unwrap();
    let out_dir = tempfile::tempdir().unwrap();
    let out = penumbra(&render_args(&scene.path, out_dir.path(), extra), &[]);
    let path = scene.path.display().to_string();
    let mut all = vec![path.as_str(), ": shaders.red.diffuse.texture: ", name];
    all.extend_from_slice(must);
    assert_fails(&out, out_dir.path(), &[], Shape::OneLine, &all)
}

#[test]
fn a_png_bomb_is_refused_from_its_header() {
    // 9000×9000 texels in about 10 KB. Decoding it and uploading its mip
    // chain takes about 2.1 GB (src/loaders/texture.rs, texture_bytes): a
    // 1 GiB budget refuses it from the header, before a row is inflated.
    let bomb = png_bomb(9000);
    assert!(bomb.len() < 100_000, "{} bytes", bomb.len());
    texture_fails(
        "bomb.png",
        &bomb,
        &["--max-scene-memory", "1024"],
        &[
            "is 9000×9000 texels by its header",
            "more than the scene memory budget of 1024.0 MiB",
            "refused before decoding",
        ],
    );
}

#[test]
fn a_jpeg_bomb_is_refused_from_its_header_by_the_device_limit() {
    // About 600 bytes whose header claims 16384×16384 texels: 2.7 GiB of
    // mip chain on the device, more than lavapipe's 1 GiB texture image.
    // The default memory budget (4 GiB) would let the decode start; the
    // device's limit, known before loading, refuses it first.
    let bomb = jpeg_bomb(16384);
    assert!(bomb.len() < 2000, "{} bytes", bomb.len());
    texture_fails(
        "bomb.jpg",
        &bomb,
        &[],
        &[
            "is 16384×16384 texels by its header",
            "this device's texture image holds",
            "refused before decoding",
        ],
    );
}

#[test]
fn a_jpeg_too_small_for_its_header_is_refused_before_decoding() {
    // 10000×10000 fits the device and the memory budget, but no JPEG of a
    // few hundred bytes holds it (one bit per 8×8 block: 195 KB at least);
    // decoded, the missing data would be filled in and rendered (2.6 GB).
    texture_fails(
        "short.jpg",
        &jpeg_bomb(10000),
        &[],
        &[
            "is 10000×10000 texels by its header, but its ",
            "bytes cannot hold them (a JPEG codes at least a bit per 8×8 block: 195312 bytes at least); refused before decoding",
        ],
    );
}

#[test]
fn a_texture_larger_than_a_side_is_refused_from_its_header() {
    texture_fails(
        "wide.jpg",
        &jpeg_bomb(20000),
        &["--reference"],
        &["is 20000×20000 texels by its header, larger than the 16384 texels a side"],
    );
}

/// `tests/data/khronos/BoxTextured` (buffers and image embedded) with one
/// change, rendered; asserts a clean failure naming the file, `field` and
/// every string of `must`.
#[track_caller]
fn box_textured_fails(change: impl FnOnce(&mut Value), field: &str, must: &[&str]) {
    let data = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/khronos/BoxTextured/BoxTextured.gltf");
    let mut gltf: Value = serde_json::from_slice(&std::fs::read(data).unwrap()).unwrap();
    change(&mut gltf);
    let scene = scene_file("box.gltf", serde_json::to_vec(&gltf).unwrap());
    let out_dir = tempfile::tempdir().unwrap();
    let out = penumbra(&render_args(&scene.path, out_dir.path(), &[]), &[]);
    let path = scene.path.display().to_string();
    let at = format!("{path}: {field}: ");
    let mut all = vec![at.as_str()];
    all.extend_from_slice(must);
    assert_fails(&out, out_dir.path(), &[], Shape::OneLine, &all);
}

#[test]
fn gltf_indices_above_u32_are_refused_not_wrapped() {
    // 2^32 would be read `as u32`, index 0, which exists in this file.
    box_textured_fails(
        |g| {
            g["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["index"] =
                json!(1u64 << 32)
        },
        "materials[0].pbrMetallicRoughness.baseColorTexture.index",
        &["index 4294967296 is larger than a glTF index can be (4294967295 at most)"],
    );
    box_textured_fails(
        |g| g["textures"][0]["source"] = json!(1u64 << 32),
        "textures[0].source",
        &["index 4294967296 is larger than a glTF index can be"],
    );
    // In range for u32 but not for the file: the crate's range check.
    box_textured_fails(
        |g| g["textures"][0]["source"] = json!(7),
        "textures[0].source",
        &["Index out of bounds"],
    );
}

#[test]
fn gltf_metallic_and_roughness_factors_outside_0_1_are_refused() {
    // The gltf crate may read them; glTF 2.0 bounds both to [0, 1].
    box_textured_fails(
        |g| g["materials"][0]["pbrMetallicRoughness"]["roughnessFactor"] = json!(1.5),
        "materials[0].pbrMetallicRoughness.roughnessFactor",
        &["must be in [0, 1], got 1.5"],
    );
    box_textured_fails(
        |g| g["materials"][0]["pbrMetallicRoughness"]["metallicFactor"] = json!(-0.5),
        "materials[0].pbrMetallicRoughness.metallicFactor",
        &["must be in [0, 1], got -0.5"],
    );
}

#[test]
fn gltf_texture_transform_errors_name_the_files_field() {
    box_textured_fails(
        |g| {
            g["extensionsUsed"] = json!(["KHR_texture_transform"]);
            g["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["extensions"] =
                json!({"KHR_texture_transform": {"scale": [0, 1]}});
        },
        "materials[0].pbrMetallicRoughness.baseColorTexture.extensions.KHR_texture_transform.scale",
        &["must be non-zero in u and v"],
    );
}

#[test]
fn gltf_draco_data_that_is_no_draco_stream_and_basisu_are_named() {
    // As Duck's glTF-Draco variant: the accessors have no bufferView (the
    // data is in the Draco stream), which the crate's validation must not
    // report; here the named view holds no Draco stream.
    box_textured_fails(
        |g| {
            g["extensionsUsed"] = json!(["KHR_draco_mesh_compression"]);
            g["extensionsRequired"] = json!(["KHR_draco_mesh_compression"]);
            g["accessors"][0]
                .as_object_mut()
                .unwrap()
                .remove("bufferView");
            g["meshes"][0]["primitives"][0]["extensions"] = json!({
                "KHR_draco_mesh_compression": {"bufferView": 0, "attributes": {"POSITION": 0}}
            });
        },
        "meshes[0].primitives[0].extensions.KHR_draco_mesh_compression.bufferView",
        &["bufferViews[0] is not a valid Draco mesh"],
    );
    // As StainedGlassLamp's KTX variant: a texture with no `source`, its
    // image a KTX2 file (the identifier, then nothing valid).
    box_textured_fails(
        |g| {
            g["extensionsUsed"] = json!(["KHR_texture_basisu"]);
            g["extensionsRequired"] = json!(["KHR_texture_basisu"]);
            g["textures"][0].as_object_mut().unwrap().remove("source");
            g["textures"][0]["extensions"] = json!({"KHR_texture_basisu": {"source": 0}});
            // «KTX 20» and its line endings, then zeros.
            g["images"][0]["uri"] = json!("data:image/ktx2;base64,q0tUWCAyMLsNChoKAAAAAAAA");
        },
        "images[0].uri",
        &["is a corrupt KTX2 image"],
    );
    // Any other unknown required extension is named too.
    box_textured_fails(
        |g| g["extensionsRequired"] = json!(["KHR_texture_transform", "EXT_made_up"]),
        "extensionsRequired[1]",
        &["requires extension EXT_made_up, which penumbra does not support"],
    );
}

#[test]
fn gltf_quantized_meshopt_and_instancing_errors_name_the_files_field() {
    // A NORMAL of unsigned bytes: not allowed, even with KHR_mesh_quantization.
    box_textured_fails(
        |g| {
            g["extensionsUsed"] = json!(["KHR_mesh_quantization"]);
            g["accessors"][1]["componentType"] = json!(5121);
            g["accessors"][1]["normalized"] = json!(true);
        },
        "meshes[0].primitives[0].attributes.NORMAL",
        &["accessors[1] is normalized UNSIGNED_BYTE, expected FLOAT, normalized BYTE, normalized SHORT"],
    );
    // A meshopt bomb: 72 bytes claiming 2^32 elements of 252 bytes, refused
    // from the declared size before anything is allocated.
    box_textured_fails(
        |g| {
            let count = 1u64 << 32;
            g["extensionsUsed"] = json!(["EXT_meshopt_compression"]);
            g["bufferViews"][0]["byteLength"] = json!(count * 252);
            g["bufferViews"][0]["extensions"] = json!({"EXT_meshopt_compression": {
                "buffer": 0, "byteOffset": 768, "byteLength": 72, "byteStride": 252,
                "count": count, "mode": "ATTRIBUTES"}});
        },
        "bufferViews[0].extensions.EXT_meshopt_compression.count",
        &[
            "with this view's 1082331758592 decoded bytes",
            "--max-scene-memory",
        ],
    );
    // 2^28 instances of the box, charged before any is read.
    box_textured_fails(
        |g| {
            g["extensionsUsed"] = json!(["EXT_mesh_gpu_instancing"]);
            g["accessors"].as_array_mut().unwrap().push(
                json!({"bufferView": 1, "componentType": 5126, "count": 1 << 28, "type": "VEC3"}),
            );
            g["nodes"][2]["extensions"] =
                json!({"EXT_mesh_gpu_instancing": {"attributes": {"TRANSLATION": 4}}});
        },
        "nodes[2].extensions.EXT_mesh_gpu_instancing",
        &[
            "268435456 instances of meshes[0].primitives[0]: ",
            "--max-scene-memory",
        ],
    );
}

#[test]
fn camera_option_names_the_cameras_a_file_has() {
    // BoxTextured places no camera: --camera 2 has none to pick.
    let data = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/khronos/BoxTextured/BoxTextured.gltf");
    let out_dir = tempfile::tempdir().unwrap();
    let out = penumbra(&render_args(&data, out_dir.path(), &["--camera", "2"]), &[]);
    let at = format!("{}: cameras: ", data.display());
    assert_fails(
        &out,
        out_dir.path(),
        &[],
        Shape::OneLine,
        &[
            &at,
            "--camera 2: no node of the default scene places cameras[2]",
            "--camera framing",
        ],
    );
    // A JSON scene has one camera.
    let scene = scene_file("scene.json", mutated(|_| {}));
    let out = penumbra(
        &render_args(&scene.path, out_dir.path(), &["--camera", "framing"]),
        &[],
    );
    let at = format!("{}: camera: ", scene.path.display());
    assert_fails(
        &out,
        out_dir.path(),
        &[],
        Shape::OneLine,
        &[&at, "--camera chooses among a glTF file's cameras"],
    );
}

#[test]
fn gltf_validation_errors_name_the_primitive_not_the_scene_object() {
    // Scaled by 1e20, the box lies beyond what the kernel's f32 holds; the
    // scene's validation finds it as objects[0].positions[0].
    box_textured_fails(
        |g| {
            g["nodes"][0]["matrix"] =
                json!([1e20, 0, 0, 0, 0, 1e20, 0, 0, 0, 0, 1e20, 0, 0, 0, 0, 1]);
            g["nodes"]
                .as_array_mut()
                .unwrap()
                .push(json!({"camera": 0}));
            g["cameras"] =
                json!([{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1}}]);
            g["scenes"][0]["nodes"] = json!([0, 3]);
        },
        "meshes[0].primitives[0].attributes.POSITION",
        &["vertex 0: must lie within ±1e18", "in world space"],
    );
}

#[test]
fn merge_names_each_repeated_part_once_in_a_bounded_line() {
    // 10,000 copies (hard links) of one part: one line naming the first few
    // and counting the rest, not one that lists every earlier copy for each.
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = d.join("scene.json");
    std::fs::write(&scene, mutated(|_| {})).unwrap();
    let part = d.join("part.exr");
    let out = penumbra(&render_to(&scene, &part, &["--tile", "0/1"]), &[]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let copies = 10_000;
    let mut args: Vec<OsString> = vec!["merge".into(), part.clone().into()];
    for i in 0..copies {
        let copy = d.join(format!("copy{i:05}.exr"));
        std::fs::hard_link(&part, &copy).unwrap();
        args.push(copy.into());
    }
    let out_dir = tempfile::tempdir().unwrap();
    args.extend(["-o".into(), out_dir.path().join("out.png").into()]);
    let out = penumbra(&args, &[]);
    let stderr = assert_fails(
        &out,
        out_dir.path(),
        &[],
        Shape::OneLine,
        &[
            "tile 0/1: ",
            "copy00001.exr, ",
            "copy00005.exr and 9995 more (passes 0..1) repeat passes already in ",
            "copy00000.exr",
        ],
    );
    assert!(stderr.len() < 1000, "{} bytes", stderr.len());
    // Each named once (copy00000 is first by name: the one they repeat).
    for i in 0..copies {
        let name = format!("copy{i:05}.exr");
        assert!(stderr.matches(&name).count() <= 1, "{name} twice: {stderr}");
    }
}

// ------------------------------------------ hostile user shaders (issue 36)

/// The sphere of the base scene shaded by `hostile.wgsl` with text `source`
/// (no params); returns the folder and the scene path.
fn hostile_scene(source: &str) -> (TempDir, PathBuf) {
    let (dir, scene) = wgsl_scene("hostile.wgsl", None, &[]);
    std::fs::write(dir.path().join("hostile.wgsl"), source).unwrap();
    (dir, scene)
}

/// `fn shade` with `body` before its return.
fn hostile_shade(body: &str) -> String {
    format!("fn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32> {{\n{body}\n    return s.normal;\n}}\n")
}

/// Renders the scene of [`hostile_scene`] and asserts a clean failure of
/// `shape` that names the scene file, its field `shaders.toon.file`,
/// `hostile.wgsl` followed by `place` (`:LINE:COL: `, or `: ` without a
/// place), and every string of `must`.
#[track_caller]
fn hostile_fails(source: &str, place: &str, shape: Shape, must: &[&str]) -> String {
    let (_dir, scene) = hostile_scene(source);
    let out_dir = tempfile::tempdir().unwrap();
    let out = penumbra(&render_args(&scene, out_dir.path(), &[]), &[]);
    let path = scene.display().to_string();
    let file = format!("hostile.wgsl{place}");
    let mut all = vec![path.as_str(), ": shaders.toon.file: ", file.as_str()];
    all.extend_from_slice(must);
    assert_fails(&out, out_dir.path(), &[], shape, &all)
}

/// A multibyte character in a comment panicked the comment scan (exit 70):
/// the file renders, in every kind of comment and at the end of the file.
#[test]
fn a_multibyte_character_in_a_shader_comment_renders() {
    let source = format!(
        "/* é 🦀 /* ü */ */\n// ß\n{}/* ä",
        hostile_shade("    let x = 1.0; /* é */")
    );
    let (_dir, scene) = hostile_scene(&source);
    let out_dir = tempfile::tempdir().unwrap();
    let out = penumbra(&render_args(&scene, out_dir.path(), &[]), &[]);
    // An unterminated comment at the end is a syntax error, at its place.
    assert_fails(&out, out_dir.path(), &[], Shape::Source, &["hostile.wgsl:"]);
    let source = source.trim_end_matches("/* ä").to_string() + "/* ä */";
    std::fs::write(scene.parent().unwrap().join("hostile.wgsl"), source).unwrap();
    let out = penumbra(&render_args(&scene, out_dir.path(), &[]), &[]);
    assert!(out.status.success(), "{}", text(&out.stderr));
}

#[test]
fn a_huge_function_array_is_refused_before_work() {
    hostile_fails(
        &hostile_shade("    var a: array<f32, 100000000>;\n    a[0] = 1.0;"),
        ":2:5: ",
        Shape::Source,
        &["array<f32, 100000000> takes 400000000 bytes; a shader may hold at most 16384 bytes per invocation"],
    );
}

#[test]
fn huge_private_and_workgroup_arrays_are_refused() {
    hostile_fails(
        &format!(
            "var<private> a: array<f32, 1000000>;\n{}",
            hostile_shade("")
        ),
        ":1:1: ",
        Shape::Source,
        &["takes 4000000 bytes"],
    );
    hostile_fails(
        &format!("var<workgroup> a: array<f32, 1000000>;\n{}", hostile_shade("")),
        ":1:5: ",
        Shape::Source,
        &["`var<workgroup>`: a shader file may declare variables only in the function and private address spaces"],
    );
}

#[test]
fn a_type_too_large_to_lay_out_names_the_file() {
    hostile_fails(
        &hostile_shade("    var a: array<array<f32, 1000000>, 1000000>;"),
        ":2:",
        Shape::Source,
        &["is too large to lay out; a shader may hold at most 16384 bytes"],
    );
}

/// The 60 KB file whose return is a sum of 30 000 terms overflowed
/// naga's stack (exit 134).
#[test]
fn a_sum_of_30000_terms_is_refused_before_naga() {
    let sum = vec!["s.normal"; 7_000].join("+");
    hostile_fails(
        &format!(
            "fn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32> {{\n    return {sum};\n}}\n"
        ),
        ":2:",
        Shape::Source,
        &["this statement has more than 1024 tokens"],
    );
    let sum = vec!["1.0"; 30_000].join("+");
    let source = format!(
        "fn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32> {{\n    return vec3<f32>({sum});\n}}\n"
    );
    assert!(source.len() > 64 * 1024);
    hostile_fails(
        &source,
        ":2:",
        Shape::Source,
        &["a shader file may have at most 65536 bytes"],
    );
}

/// 2 000 nested parentheses: naga's "internal WGSL front end error", now
/// refused with the place of the 33rd level.
#[test]
fn two_thousand_nested_parentheses_are_refused_at_their_place() {
    let deep = format!("{}1.0{}", "(".repeat(2000), ")".repeat(2000));
    hostile_fails(
        &hostile_shade(&format!("    let x = {deep};")),
        ":2:44: ",
        Shape::Source,
        &["brackets nest more than 32 deep"],
    );
}

#[test]
fn too_many_functions_and_params_fields_are_refused() {
    let functions: String = (0..200).map(|i| format!("fn f{i}() {{}}\n")).collect();
    hostile_fails(
        &format!("{functions}{}", hostile_shade("")),
        ":65:1: ",
        Shape::Source,
        &["more than 64 functions, the limit of one shader file"],
    );
    let fields: String = (0..10_000).map(|i| format!("f{i}: f32,")).collect();
    hostile_fails(
        &format!("struct Params {{ {fields} }}\n{}", hostile_shade("")),
        ":1:",
        Shape::Source,
        &["a shader file may have at most 65536 bytes"],
    );
    let fields: String = (0..100).map(|i| format!("f{i}: f32,\n")).collect();
    hostile_fails(
        &format!("struct Params {{\n{fields}}}\n{}", hostile_shade("")),
        ":66:1: ",
        Shape::Source,
        &["Params has more than 64 fields, the limit"],
    );
}

/// A user file that declares the engine's buffers at their bindings could
/// read and write them out of range.
#[test]
fn a_shader_declaring_resources_is_refused() {
    hostile_fails(
        &format!(
            "@group(0) @binding(3) var<storage, read_write> counters: array<u32>;\n{}",
            hostile_shade("    counters[100000000u] = 1u;")
        ),
        ":1:2: ",
        Shape::Source,
        &["`@group`: a shader file must not declare resources"],
    );
}

/// naga's errors that named "shaders" and no place: an override without a
/// value, an operation a compute shader cannot run.
#[test]
fn naga_errors_name_the_users_file_and_place() {
    hostile_fails(
        &format!(
            "override gain: f32;\n{}",
            hostile_shade("    let g = gain;")
        ),
        ":1:",
        Shape::Source,
        &["override `gain` has no value"],
    );
    hostile_fails(
        &hostile_shade("    let d = dpdx(s.position.x);"),
        ":1:",
        Shape::Source,
        &["`shade` uses an operation that the shade stage, a compute shader, cannot run"],
    );
}

/// Array values count like variables: 500 `let` arrays indexed at run time
/// grew the renderer to 4.7 GB and ran past 120 s before they did.
#[test]
fn array_values_indexed_at_run_time_are_refused() {
    let lets: String = (0..500)
        .map(|i| format!("    let a{i} = array<f32, 4096>();\n    x += a{i}[u32(s.uv.x)];\n"))
        .collect();
    hostile_fails(
        &hostile_shade(&format!("    var x = 0.0;\n{lets}")),
        ":3:14: ",
        Shape::Source,
        &[
            "array values take",
            "a shader may hold at most 16384 bytes per invocation",
        ],
    );
}
