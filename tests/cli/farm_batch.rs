//! `penumbra render --batch LIST -o DIR` end to end: one process renders
//! every scene of the list; a broken scene is reported by name while the
//! others render; a rerun skips the complete outputs and redoes broken ones.
//! Needs a Vulkan device (lavapipe in CI).

use std::path::Path;
use std::process::{Command, Output};

fn scene(i: u32, radius: f64) -> String {
    let c = i as f64 / 20.0;
    format!(
        r#"{{
  "camera": {{"position": [0, 1, 5], "look_at": [0, 0.5, 0], "up": [0, 1, 0], "fov": 45, "width": 32, "height": 24}},
  "background": [0.1, 0.1, 0.2],
  "shaders": {{"s": {{"type": "phong", "diffuse": [{c}, 0.5, 0.2]}}}},
  "objects": [{{"type": "sphere", "center": [0, 1, 0], "radius": {radius}, "shader": "s"}}],
  "lights": [{{"type": "point", "position": [2, 3, 2], "intensity": 10}}]
}}"#
    )
}

fn batch(dir: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .args(["render", "--batch", "list.txt", "-o", "out"])
        .current_dir(dir)
        .output()
        .expect("run penumbra")
}

fn outputs(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir.join("out"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn a_batch_of_twenty_with_one_broken_renders_nineteen_and_names_it() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::create_dir(d.join("out")).unwrap();
    let mut list = String::from("# twenty scenes, frame 7 broken\n");
    for i in 0..20 {
        let radius = if i == 7 { -1.0 } else { 1.0 };
        std::fs::write(d.join(format!("frame{i:02}.json")), scene(i, radius)).unwrap();
        list.push_str(&format!("frame{i:02}.json\n"));
    }
    std::fs::write(d.join("list.txt"), list).unwrap();

    let out = batch(d);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    let expected: Vec<String> = (0..20)
        .filter(|&i| i != 7)
        .map(|i| format!("frame{i:02}.png"))
        .collect();
    assert_eq!(outputs(d), expected, "{stderr}");
    let errors: Vec<&str> = stderr.lines().filter(|l| l.starts_with("error:")).collect();
    assert_eq!(errors.len(), 1, "{stderr}");
    assert!(
        errors[0].contains("1 of 20 scenes failed: frame07.json"),
        "{}",
        errors[0]
    );
    assert!(!errors[0].contains("frame08"), "{}", errors[0]);
    // The broken scene's own message names its field.
    assert!(
        stderr.contains("frame07.json: objects[0].radius"),
        "{stderr}"
    );
    // Every image is a real render of its scene: the colour varies by frame.
    let a = image::open(d.join("out/frame00.png")).unwrap().to_rgb8();
    let b = image::open(d.join("out/frame19.png")).unwrap().to_rgb8();
    assert_eq!(a.dimensions(), (32, 24));
    assert_ne!(a, b);

    // Resume: a truncated output is redone, complete ones are skipped.
    let bytes = std::fs::read(d.join("out/frame03.png")).unwrap();
    std::fs::write(d.join("out/frame03.png"), &bytes[..bytes.len() / 2]).unwrap();
    let before = std::fs::metadata(d.join("out/frame05.png"))
        .unwrap()
        .modified()
        .unwrap();
    std::fs::write(d.join("frame07.json"), scene(7, 1.0)).unwrap();
    let out = batch(d);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        stdout.contains("20 scenes, 2 rendered, 18 skipped, 0 failed"),
        "{stdout}"
    );
    assert_eq!(bytes, std::fs::read(d.join("out/frame03.png")).unwrap());
    let after = std::fs::metadata(d.join("out/frame05.png"))
        .unwrap()
        .modified()
        .unwrap();
    assert_eq!(before, after, "a complete output was rewritten");
    assert_eq!(outputs(d).len(), 20);
}

#[test]
fn a_bad_list_is_one_error_naming_the_list_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::create_dir(d.join("out")).unwrap();
    for (list, needle) in [
        (None, "list.txt: cannot read"),
        (Some("a.json\nb.json x.gif\n"), "list.txt:2: output `x.gif`"),
        (
            Some("a.json\nsub/a.json\n"),
            "list.txt:2: output `a.png` is already line 1's",
        ),
    ] {
        let _ = std::fs::remove_file(d.join("list.txt"));
        if let Some(text) = list {
            std::fs::write(d.join("list.txt"), text).unwrap();
        }
        let out = batch(d);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{stderr}");
        let errors: Vec<&str> = stderr.lines().filter(|l| l.starts_with("error:")).collect();
        assert_eq!(errors.len(), 1, "{stderr}");
        assert!(errors[0].contains(needle), "{}", errors[0]);
        assert!(outputs(d).is_empty());
    }
}
