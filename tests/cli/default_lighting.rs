//! A glTF file without lights under glTF's own materials (issue 38): lit by
//! the default environment alone, which geometry enclosing the scene cannot
//! block, over a grey background, and shown tone-mapped with PBR Neutral; the
//! flags `--environment`, `--background`, `--exposure` and `--tonemap` work
//! alike in `render`, `render --batch`, split renders and their `merge`, and
//! `watch` (docs/materials.md, "Default lighting").

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

use serde_json::{json, Value};

/// Khronos' BoxTextured (no lights, no camera) seen from a camera at z = 3
/// looking at the unit box; `enclosed`: the same box again, scaled by −20
/// around everything (a negative scale turns its faces inwards), as
/// VirtualCity's sky-box encloses its city.
fn box_file(dir: &Path, enclosed: bool) -> PathBuf {
    let data = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/khronos/BoxTextured/BoxTextured.gltf");
    let mut gltf: Value = serde_json::from_slice(&std::fs::read(&data).unwrap()).unwrap();
    gltf["cameras"] =
        json!([{ "type": "perspective", "perspective": { "yfov": 0.6, "znear": 0.01 } }]);
    let nodes = gltf["nodes"].as_array_mut().unwrap();
    nodes.push(json!({ "camera": 0, "translation": [0.2, 0.3, 3] }));
    nodes.push(json!({ "mesh": 0, "scale": [-20, -20, -20] }));
    let (camera, enclosure) = (nodes.len() - 2, nodes.len() - 1);
    let roots = gltf["scenes"][0]["nodes"].as_array_mut().unwrap();
    roots.push(json!(camera));
    if enclosed {
        roots.push(json!(enclosure));
    }
    let path = dir.join(if enclosed {
        "enclosed.gltf"
    } else {
        "box.gltf"
    });
    std::fs::write(&path, serde_json::to_vec(&gltf).unwrap()).unwrap();
    path
}

fn penumbra(args: &[&std::ffi::OsStr]) -> Output {
    let out = Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .args(args)
        .output()
        .expect("run penumbra");
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// `penumbra render SCENE -o OUT` at 32×32 with `extra` arguments.
fn render(scene: &Path, out: &Path, extra: &[&str]) -> Output {
    let mut args = vec![
        "render".as_ref(),
        scene.as_os_str(),
        "-o".as_ref(),
        out.as_os_str(),
    ];
    args.extend(["--width", "32", "--height", "32"].map(std::ffi::OsStr::new));
    args.extend(extra.iter().map(std::ffi::OsStr::new));
    penumbra(&args)
}

fn exr(path: &Path) -> Vec<[f32; 4]> {
    let img = image::open(path).unwrap().to_rgba32f();
    img.pixels().map(|p| p.0).collect()
}

fn png(path: &Path) -> Vec<[u8; 4]> {
    let img = image::open(path).unwrap().to_rgba8();
    img.pixels().map(|p| p.0).collect()
}

/// The sRGB code of a linear value (IEC 61966-2-1), written out here.
fn srgb_code(v: f64) -> u8 {
    let e = if v <= 0.0031308 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    };
    (e.clamp(0.0, 1.0) * 255.0).round() as u8
}

/// Pixel (16, 16) sees the box, pixel (0, 0) misses it.
const CENTRE: usize = 16 * 32 + 16;

#[test]
fn a_file_without_lights_is_lit_by_the_environment_even_inside_an_enclosure() {
    let dir = tempfile::tempdir().unwrap();
    let (open, enclosed) = (box_file(dir.path(), false), box_file(dir.path(), true));
    let out = |name: &str| dir.path().join(name);
    let stderr = render(&open, &out("open.exr"), &[]).stderr;
    let stderr = String::from_utf8_lossy(&stderr);
    assert!(
        stderr.contains("lit by the default environment"),
        "{stderr}"
    );
    render(&enclosed, &out("enclosed.exr"), &[]);
    render(&enclosed, &out("phong.exr"), &["--gltf-materials", "phong"]);
    let (open, enclosed, phong) = (
        exr(&out("open.exr")),
        exr(&out("enclosed.exr")),
        exr(&out("phong.exr")),
    );
    // Where rays miss: the grey background, linear 0.25.
    assert_eq!(open[0], [0.25, 0.25, 0.25, 1.0]);
    // The box is lit, and exactly as without the enclosure: the
    // environment casts no shadow rays.
    let lit = open.iter().filter(|p| p[3] == 1.0 && p[0] > 0.02).count();
    assert!(lit > 100, "{lit} lit pixels");
    let mut box_pixels = 0;
    for (a, b) in open.iter().zip(&enclosed) {
        if a[..3] != [0.25; 3] {
            box_pixels += 1;
            for c in 0..3 {
                assert!((a[c] - b[c]).abs() <= 1e-5 * a[c].max(1.0), "{a:?} {b:?}");
            }
        }
    }
    assert!(box_pixels > 100, "{box_pixels}");
    // The seminar's mapping keeps the default lights, which the enclosure
    // blocks: its box is black.
    assert_eq!(phong[CENTRE], [0.0, 0.0, 0.0, 1.0]);
}

#[test]
fn its_png_is_tone_mapped_and_the_flags_override_the_defaults() {
    let dir = tempfile::tempdir().unwrap();
    let scene = box_file(dir.path(), false);
    let out = |name: &str| dir.path().join(name);
    render(&scene, &out("default.png"), &[]);
    render(&scene, &out("none.png"), &["--tonemap", "none"]);
    let red = ["--tonemap", "none", "--background", "1,0,0"];
    render(&scene, &out("red.png"), &red);
    // PBR Neutral of grey 0.25 (its specification, worked by hand): x =
    // 0.25 > 2·0.04, so f = 0.04, and p = 0.21 ≤ K_s = 0.76: 0.25 − 0.04.
    let neutral = srgb_code(0.21);
    assert_eq!(
        png(&out("default.png"))[0],
        [neutral, neutral, neutral, 255]
    );
    let grey = srgb_code(0.25);
    assert_eq!(png(&out("none.png"))[0], [grey, grey, grey, 255]);
    assert_eq!(png(&out("red.png"))[0], [255, 0, 0, 255]);
    // The asked environment replaces the default one (1): twice as bright
    // at intensity 2, not three times.
    render(&scene, &out("one.exr"), &[]);
    render(&scene, &out("two.exr"), &["--environment", "2"]);
    let (one, two) = (exr(&out("one.exr")), exr(&out("two.exr")));
    assert!(one[CENTRE][0] > 0.02, "{:?}", one[CENTRE]);
    for (a, b) in one.iter().zip(&two) {
        if a[..3] != [0.25; 3] {
            for c in 0..3 {
                assert!(
                    (2.0 * a[c] - b[c]).abs() <= 1e-5 * b[c].max(1.0),
                    "{a:?} {b:?}"
                );
            }
        }
    }
}

/// The same flags give the same PNG from `render`, `render --batch`, a
/// split render's parts and `merge`, and `watch`.
#[test]
fn batch_split_renders_and_watch_take_the_same_flags() {
    let dir = tempfile::tempdir().unwrap();
    let scene = box_file(dir.path(), false);
    let out = |name: &str| dir.path().join(name);
    let flags = ["--environment", "2", "--exposure", "1"];
    render(&scene, &out("single.png"), &flags);
    let single = png(&out("single.png"));
    // The default tone mapping applies: the exposed background, linear 0.5,
    // is compressed by PBR Neutral (0.5 − 0.04 = 0.46).
    let code = srgb_code(0.46);
    assert_eq!(single[0], [code, code, code, 255]);

    // A batch of one scene.
    let batch_dir = out("batch");
    std::fs::create_dir(&batch_dir).unwrap();
    let list = out("list.txt");
    std::fs::write(&list, "box.gltf box.png\n").unwrap();
    let mut args: Vec<&std::ffi::OsStr> = vec![
        "render".as_ref(),
        "--batch".as_ref(),
        list.as_os_str(),
        "-o".as_ref(),
        batch_dir.as_os_str(),
    ];
    args.extend(["--width", "32", "--height", "32"].map(std::ffi::OsStr::new));
    args.extend(flags.map(std::ffi::OsStr::new));
    penumbra(&args);
    assert!(png(&batch_dir.join("box.png")) == single, "batch");

    // Two tiles, merged with the tone mapping `farm slurm` gives the merge.
    for (i, lighting) in [(0, "2"), (1, "2"), (2, "3")] {
        let tile = format!("{}/2", i.min(1));
        let part = out(&format!("part{i}.exr"));
        let extra = [
            "--tile",
            &tile,
            "--passes",
            "0..1",
            "--environment",
            lighting,
        ];
        render(&scene, &part, &extra);
    }
    let merged = out("merged.png");
    let mut args: Vec<&std::ffi::OsStr> = vec!["merge".as_ref()];
    let parts = [out("part0.exr"), out("part1.exr")];
    args.extend(parts.iter().map(|p| p.as_os_str()));
    args.extend(["--exposure", "1", "--tonemap", "pbr-neutral", "-o"].map(std::ffi::OsStr::new));
    args.push(merged.as_os_str());
    penumbra(&args);
    assert!(png(&merged) == single, "merge");
    // A part lit otherwise is another render: the merge refuses it.
    let refused = Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .arg("merge")
        .args([out("part0.exr"), out("part2.exr")])
        .arg("-o")
        .arg(out("mixed.png"))
        .output()
        .unwrap();
    assert!(!refused.status.success());
    let stderr = String::from_utf8_lossy(&refused.stderr);
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.starts_with("error: "), "{stderr}");
    assert!(!out("mixed.png").exists());

    // watch writes the same image.
    let watched = out("watched.png");
    let mut child = Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .arg("watch")
        .arg(&scene)
        .arg("-o")
        .arg(&watched)
        .args(["--width", "32", "--height", "32", "--preview", "1"])
        .args(flags)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    while !watched.exists() && t0.elapsed() < Duration::from_secs(120) {
        std::thread::sleep(Duration::from_millis(50));
    }
    let _ = child.kill();
    let _ = child.wait();
    assert!(png(&watched) == single, "watch");
}
