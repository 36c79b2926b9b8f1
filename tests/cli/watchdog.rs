//! The watchdog for shader code (`--time-limit`): a shader that never ends,
//! through the binary. `render` ends with one `error:` line naming the
//! shader file and writes nothing; `watch` reports it, keeps the last good
//! image, restarts itself (the device cannot stop the shader), renders the
//! next good save, and Ctrl-C ends it within a second in every state.

use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};

use crate::watch_support::*;

/// `shade()` of `src` with a loop in front that never ends: float addition
/// stops at 2^24 and its exit depends on a parameter, so no compiler can
/// prove that it ends or that it does not, and its result is used (NIR
/// removes a loop whose results nothing uses).
fn never_ending(src: &str, param: &str) -> String {
    let at = src.find("fn shade(").expect("a shade function");
    let body = at + src[at..].find('{').expect("its body") + 1;
    format!(
        "{}\n    var spin = 0.0;\n    loop {{\n        if (spin > abs(p.{param}) * 1e30 + 1e30) {{ break; }}\n        spin += 1.0;\n    }}\n    if (spin == 12345.0) {{ return vec3<f32>(spin); }}\n{}",
        &src[..body],
        &src[body..]
    )
}

/// Sends SIGINT to `child` and returns how long it took to exit, panicking
/// after 3 s.
fn interrupt(child: &mut std::process::Child) -> Duration {
    let t = Instant::now();
    // SAFETY: kill(2) on our own child's pid.
    assert_eq!(unsafe { libc::kill(child.id() as i32, libc::SIGINT) }, 0);
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            assert!(status.code().is_some(), "killed by a signal: {status:?}");
            return t.elapsed();
        }
        assert!(t.elapsed() < Duration::from_secs(3), "watch ignored SIGINT");
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// A scene of one lit sphere, `width`×`height`, shaded by the user's shader
/// file `file` (relative to the scene; `Params { weight }`).
fn sphere_scene(file: &str, width: u32, height: u32) -> String {
    format!(
        r#"{{
      "camera": {{"position": [0, 0, 4], "look_at": [0, 0, 0], "up": [0, 1, 0], "fov": 40, "width": {width}, "height": {height}}},
      "shaders": {{"user": {{"type": "wgsl", "file": "{file}", "params": {{"weight": 1}}}}}},
      "objects": [{{"type": "sphere", "center": [0, 0, 0], "radius": 1, "shader": "user"}}],
      "lights": [{{"type": "point", "position": [2, 2, 3], "intensity": 10}}]
    }}"#
    )
}

#[test]
fn render_stops_a_shader_that_never_ends_and_names_its_file() {
    let dir = tempfile::tempdir().unwrap();
    let shader = dir.path().join("spin.wgsl");
    let normals = include_str!("../../scenes/shaders/normals.wgsl");
    std::fs::write(&shader, never_ending(normals, "weight")).unwrap();
    let scene = sphere_scene("spin.wgsl", 32, 24);
    std::fs::write(dir.path().join("scene.json"), scene).unwrap();
    let out_dir = dir.path().join("out");
    std::fs::create_dir(&out_dir).unwrap();
    let t = Instant::now();
    let out = Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .arg("render")
        .arg(dir.path().join("scene.json"))
        .arg("-o")
        .arg(out_dir.join("out.png"))
        .args(["--time-limit", "1"])
        .output()
        .unwrap();
    let took = t.elapsed();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "one line: {stderr}");
    assert!(stderr.starts_with("error: "), "{stderr}");
    assert!(
        stderr.contains("spin.wgsl: the shade stage ran past the time limit of 1 s (--time-limit)"),
        "{stderr}"
    );
    assert!(out.stdout.is_empty());
    assert_eq!(std::fs::read_dir(&out_dir).unwrap().count(), 0, "no output");
    // Not a timing test: a bound far above the limit, to catch a wait
    // without a deadline (the device never ends this shader).
    assert!(took < Duration::from_secs(60), "{took:?}");
}

#[test]
fn time_limit_values_are_checked() {
    for bad in ["0", "-1", "abc", "nan", "1e9"] {
        let out = Command::new(env!("CARGO_BIN_EXE_penumbra"))
            .args(["render", "scene.json", "--time-limit", bad])
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{bad}: {stderr}");
        assert!(
            stderr.starts_with("error: ") && stderr.contains("--time-limit"),
            "{stderr}"
        );
    }
}

#[test]
fn watch_survives_a_shader_that_never_ends() {
    let fx = Fixture::new();
    let mut p = Child::start(
        &fx,
        &[
            "--debounce-ms",
            "40",
            "--time-limit",
            "2",
            "--serve",
            "127.0.0.1:0",
        ],
    );
    let pid = p.child.id();
    let serving = p.wait_line("the page", false, |l| {
        l.starts_with("serving the live preview at ")
    });
    p.wait_line("the first render", false, |l| {
        l.starts_with("reload 0: start")
    });
    let good = fx.output();

    std::fs::write(
        fx.shader_path(),
        never_ending(&fx.shader_original, "shininess"),
    )
    .unwrap();
    let phong = fx.shaders.canonicalize().unwrap().join(SHADER);
    let error = p.wait_line("the time-out", true, |l| {
        l.contains("ran past the time limit of 2 s")
    });
    assert!(error.starts_with("error: "), "{error}");
    assert!(
        error.contains(&phong.display().to_string()),
        "names the file: {error}"
    );
    let line = p.wait_line("reload 1", false, |l| l.starts_with("reload 1:"));
    assert!(line.contains("ERROR: kept the last good image"), "{line}");
    p.wait_line("the restart", false, |l| l.starts_with("restarting: "));
    // The page is back at the same address (the port was 0), with that image.
    let again = p.wait_line("the page again", false, |l| {
        l.starts_with("serving the live preview at ")
    });
    assert_eq!(again, serving);
    let addr = serving
        .trim_start_matches("serving the live preview at http://")
        .trim_end_matches('/');
    // The new process does not run the same files again; same pid.
    let line = p.wait_line("reload 2", false, |l| l.starts_with("reload 2: restart"));
    assert!(line.contains("ERROR: kept the last good image"), "{line}");
    assert_eq!(p.child.id(), pid);
    assert_eq!(fx.output(), good, "the last good image is kept");
    assert_eq!(
        get(addr, "/image.png"),
        good,
        "the page shows the last good image"
    );

    // The next good save renders.
    save_by_rename(
        &fx.shader_path(),
        &fx.shader_scaled("vec3<f32>(1.0, 0.0, 0.0)"),
    );
    let line = p.wait_line("recovery", false, |l| l.starts_with("reload 3:"));
    assert!(
        line.contains("full 64x48") && !line.contains("ERROR"),
        "{line}"
    );
    let c = fx.centre();
    assert!(c[0] > 200 && c[1] == 0, "{c:?}");

    let took = interrupt(&mut p.child);
    assert!(took < Duration::from_secs(1), "SIGINT took {took:?}");
}

#[test]
fn ctrl_c_ends_watch_within_a_second_while_a_shader_runs_on() {
    let fx = Fixture::new();
    // A limit the test never reaches: the shader is still running.
    let mut p = Child::start(&fx, &["--debounce-ms", "40", "--time-limit", "100"]);
    p.wait_line("the first render", false, |l| {
        l.starts_with("reload 0: start")
    });
    let good = fx.output();
    std::fs::write(
        fx.shader_path(),
        never_ending(&fx.shader_original, "shininess"),
    )
    .unwrap();
    // The reload compiles (well under a second on lavapipe) and then spins.
    std::thread::sleep(Duration::from_secs(3));
    assert!(p.child.try_wait().unwrap().is_none());
    let took = interrupt(&mut p.child);
    assert!(took < Duration::from_secs(1), "SIGINT took {took:?}");
    assert_eq!(fx.output(), good, "the last good image is kept");
    assert_eq!(leftovers(fx.dir.path()), Vec::<String>::new());
}

/// Files in `dir` other than the fixture's.
fn leftovers(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| !["shaders", "scene.json", "out.png"].contains(&n.as_str()))
        .collect()
}

/// The body of `GET path` from the live page at `addr`.
fn get(addr: &str, path: &str) -> Vec<u8> {
    use std::io::{Read, Write};
    let mut c = std::net::TcpStream::connect(addr).unwrap();
    c.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
    write!(
        c,
        "GET {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\r\n"
    )
    .unwrap();
    let mut bytes = Vec::new();
    c.read_to_end(&mut bytes).unwrap();
    let head_end = bytes
        .windows(4)
        .position(|w| w == b"\r\n\r\n")
        .expect("a response head")
        + 4;
    let head = String::from_utf8_lossy(&bytes[..head_end]).into_owned();
    assert!(head.starts_with("HTTP/1.1 200"), "{head}");
    bytes.split_off(head_end)
}

/// A scene of one sphere shaded by the user's `user.wgsl` (Params `weight`),
/// 64×48, written over the fixture's scene.
fn user_shader_scene(fx: &Fixture, source: &str) -> std::path::PathBuf {
    let scene = sphere_scene("user.wgsl", 64, 48);
    let shader = fx.dir.path().join("user.wgsl");
    std::fs::write(&shader, source).unwrap();
    std::fs::write(&fx.scene, scene).unwrap();
    shader
}

#[test]
fn watch_survives_hostile_shaders_saved_into_it() {
    let fx = Fixture::new();
    let normals = include_str!("../../scenes/shaders/normals.wgsl");
    let shader = user_shader_scene(&fx, normals);
    let mut p = Child::start(&fx, &["--debounce-ms", "40", "--time-limit", "2"]);
    p.wait_line("the first render", false, |l| {
        l.starts_with("reload 0: start")
    });

    // A multibyte character in a comment is just a comment.
    let commented = format!("/* é ✓ 日本 — */\n{normals}// ü\n");
    save_by_rename(&shader, &commented);
    let line = p.wait_line("reload 1", false, |l| l.starts_with("reload 1:"));
    assert!(
        line.contains("full 64x48") && !line.contains("ERROR"),
        "{line}"
    );
    let good = fx.output();

    // Each refused with the file and place; the last good image is kept.
    let sum: String = (0..30000)
        .map(|i| format!("{i}.0"))
        .collect::<Vec<_>>()
        .join(" + ");
    let hostile = [
        (
            "a huge array",
            normals.replace(
                "return vec3<f32>(0.0);",
                "var a: array<f32, 100000000>;\n    a[u32(s.normal.x)] = 1.0;\n    return vec3<f32>(a[1]);",
            ),
        ),
        (
            "a deep expression",
            normals.replace("return vec3<f32>(0.0);", &format!("return vec3<f32>({sum});")),
        ),
    ];
    let name = shader.canonicalize().unwrap().display().to_string();
    for (n, (what, source)) in hostile.iter().enumerate() {
        assert_ne!(source, normals, "{what}: the edit applies");
        save_by_rename(&shader, source);
        let error = p.wait_line(what, true, |l| l.starts_with("error: "));
        assert!(
            error.contains(&format!("{name}:")),
            "{what}: names the file: {error}"
        );
        let number = n + 2;
        let line = p.wait_line(what, false, |l| l.starts_with(&format!("reload {number}:")));
        assert!(
            line.contains("ERROR: kept the last good image"),
            "{what}: {line}"
        );
        assert_eq!(fx.output(), good, "{what}: the last good image is kept");
    }

    // A loop that never ends: reported, and watch restarts.
    save_by_rename(&shader, &never_ending(normals, "weight"));
    let error = p.wait_line("the time-out", true, |l| {
        l.contains("ran past the time limit of 2 s")
    });
    assert!(error.contains(&name), "names the file: {error}");
    p.wait_line("the restart", false, |l| l.starts_with("reload 5: restart"));
    assert_eq!(fx.output(), good, "the last good image is kept");

    // The next good save renders.
    save_by_rename(&shader, &normals.replace("p.weight *", "0.5 * p.weight *"));
    let line = p.wait_line("recovery", false, |l| l.starts_with("reload 6:"));
    assert!(
        line.contains("full 64x48") && !line.contains("ERROR"),
        "{line}"
    );
    assert_ne!(fx.output(), good, "a new image");

    let took = interrupt(&mut p.child);
    assert!(took < Duration::from_secs(1), "SIGINT took {took:?}");
}

#[test]
fn a_batch_ends_at_a_scene_that_hangs_the_device() {
    let dir = tempfile::tempdir().unwrap();
    let normals = include_str!("../../scenes/shaders/normals.wgsl");
    std::fs::write(dir.path().join("good.wgsl"), normals).unwrap();
    std::fs::write(
        dir.path().join("spin.wgsl"),
        never_ending(normals, "weight"),
    )
    .unwrap();
    for (scene, shader) in [
        ("a.json", "good.wgsl"),
        ("b.json", "spin.wgsl"),
        ("c.json", "good.wgsl"),
    ] {
        let text = sphere_scene(shader, 32, 24);
        std::fs::write(dir.path().join(scene), text).unwrap();
    }
    std::fs::write(dir.path().join("list.txt"), "a.json\nb.json\nc.json\n").unwrap();
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    let result = Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .args(["render", "--batch"])
        .arg(dir.path().join("list.txt"))
        .arg("-o")
        .arg(&out)
        .args(["--time-limit", "1"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&result.stderr);
    let stdout = String::from_utf8_lossy(&result.stdout);
    assert_eq!(result.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("spin.wgsl: the shade stage ran past the time limit of 1 s"),
        "{stderr}"
    );
    assert!(
        stderr.contains("1 scene(s) after it were not started"),
        "{stderr}"
    );
    assert!(
        stdout.contains("3 scenes, 1 rendered, 0 skipped, 1 failed, 1 not started"),
        "{stdout}"
    );
    assert!(out.join("a.png").exists());
    assert!(!out.join("b.png").exists() && !out.join("c.png").exists());
}
