//! Untrusted text in error lines: a file name, a glTF URI (also
//! percent-encoded) or a field's value that carries control characters
//! reaches the terminal escaped (`\u{1b}`) and on one line, so a file cannot
//! recolour the terminal or forge an `error:` line of its own.

use std::process::Command;

/// Renders `scene.json` (with `contents`) in a fresh directory; returns the
/// exit code and stderr, and checks that no output was written.
fn render(contents: &str) -> (Option<i32>, String) {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("scene.json"), contents).unwrap();
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    let result = Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .arg("render")
        .arg(dir.path().join("scene.json"))
        .arg("-o")
        .arg(out.join("out.png"))
        .output()
        .unwrap();
    assert_eq!(std::fs::read_dir(&out).unwrap().count(), 0, "no output");
    (
        result.status.code(),
        String::from_utf8_lossy(&result.stderr).into_owned(),
    )
}

/// Asserts one `error:` line with no raw control character, containing
/// every string of `must`.
#[track_caller]
fn assert_escaped(code: Option<i32>, stderr: &str, must: &[&str]) {
    assert_eq!(code, Some(1), "{stderr}");
    assert!(stderr.starts_with("error: "), "{stderr:?}");
    assert_eq!(stderr.lines().count(), 1, "one line: {stderr:?}");
    assert!(stderr.ends_with('\n'), "{stderr:?}");
    let raw: Vec<char> = stderr
        .trim_end_matches('\n')
        .chars()
        .filter(|c| c.is_control())
        .collect();
    assert!(
        raw.is_empty(),
        "raw control characters {raw:?} in {stderr:?}"
    );
    for m in must {
        assert!(stderr.contains(m), "must contain {m:?}: {stderr:?}");
    }
}

fn scene_with_texture(name: &str) -> String {
    let name = serde_json::to_string(name).unwrap();
    format!(
        r#"{{
      "camera": {{"position": [0, 0, 4], "look_at": [0, 0, 0], "up": [0, 1, 0], "fov": 40, "width": 16, "height": 16}},
      "shaders": {{"t": {{"type": "phong", "ambient": [0.1, 0.1, 0.1], "diffuse": {{"texture": {name}}},
                         "specular": [0, 0, 0], "shininess": 1}}}},
      "objects": [{{"type": "sphere", "center": [0, 0, 0], "radius": 1, "shader": "t"}}],
      "lights": [{{"type": "point", "position": [2, 2, 3], "intensity": 10}}]
    }}"#
    )
}

#[test]
fn a_texture_name_with_control_characters_is_escaped() {
    let (code, stderr) = render(&scene_with_texture(
        "x\u{1b}[31mred\r\nerror: forged\u{0}.png",
    ));
    assert_escaped(
        code,
        &stderr,
        &["\\u{1b}[31mred\\u{d}\\u{a}error: forged\\u{0}.png"],
    );
}

#[test]
fn bidirectional_overrides_are_escaped() {
    let (code, stderr) = render(&scene_with_texture("a\u{202e}gnp.exe"));
    assert_escaped(code, &stderr, &["a\\u{202e}gnp.exe"]);
}

#[test]
fn a_gltf_uri_with_control_characters_is_escaped_also_percent_encoded() {
    for uri in [
        "mesh\u{1b}]0;title\u{7}.bin",
        "mesh%1B%5B2J%0Aerror:%20forged.bin",
    ] {
        let dir = tempfile::tempdir().unwrap();
        let gltf = serde_json::json!({
            "asset": {"version": "2.0"},
            "buffers": [{"uri": uri, "byteLength": 36}],
            "bufferViews": [{"buffer": 0, "byteLength": 36}],
            "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                           "min": [0, 0, 0], "max": [1, 1, 0]}],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
            "nodes": [{"mesh": 0}],
            "scenes": [{"nodes": [0]}],
            "scene": 0
        });
        let path = dir.path().join("model.gltf");
        std::fs::write(&path, gltf.to_string()).unwrap();
        let result = Command::new(env!("CARGO_BIN_EXE_penumbra"))
            .arg("render")
            .arg(&path)
            .arg("-o")
            .arg(dir.path().join("out.png"))
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&result.stderr);
        let errors: Vec<&str> = stderr
            .lines()
            .filter(|l| !l.starts_with("note: "))
            .collect();
        assert_eq!(errors.len(), 1, "{stderr:?}");
        assert_escaped(
            result.status.code(),
            &format!("{}\n", errors[0]),
            &["model.gltf"],
        );
        assert!(!dir.path().join("out.png").exists());
    }
}
