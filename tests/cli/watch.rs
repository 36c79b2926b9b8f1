//! `penumbra watch` as a user runs it: the real binary on a temporary copy
//! of the shaders and a scene, edited from outside.

use crate::watch_support::*;

#[test]
fn the_binary_reloads_reports_errors_and_recovers() {
    let fx = Fixture::new();
    let mut p = Child::start(&fx, &["--debounce-ms", "40"]);
    p.wait_line("the first render", false, |l| {
        l.starts_with("reload 0: start")
    });
    let c0 = fx.centre();
    assert!(c0[0] > 200, "{c0:?}");

    std::fs::write(
        fx.shader_path(),
        fx.shader_scaled("vec3<f32>(0.0, 1.0, 1.0)"),
    )
    .unwrap();
    let line = p.wait_line("reload 1", false, |l| l.starts_with("reload 1:"));
    for part in [
        "shaders (shading/phong.wgsl)",
        "compile ",
        "naga ",
        "pipeline ",
        "driver ",
        // On lavapipe the preview process renders the preview
        // (cli::preview_process tests it).
        "preview 16x12 (preview process): compile ",
        "full 64x48",
        "latency ",
    ] {
        assert!(line.contains(part), "`{part}` missing: {line}");
    }
    assert_eq!(fx.centre()[0], 0);
    let good = fx.output();

    // A syntax error: `error: ` + file:line:col, the source line, the caret.
    let broken = fx.shader_scaled("vec3<f32>(0.0, 1.0, 1.0) *");
    let n = broken.lines().position(|l| l.contains("1.0) *;")).unwrap() + 1;
    std::fs::write(fx.shader_path(), &broken).unwrap();
    let want = format!(
        "error: shader error: {}:{n}:",
        fx.shaders.canonicalize().unwrap().join(SHADER).display()
    );
    p.wait_line("the error", true, |l| l.starts_with(&want));
    let src = p.wait_line("the source line", true, |_| true);
    assert!(src.contains(") * vec3<f32>(0.0, 1.0, 1.0) *;"), "{src}");
    let caret = p.wait_line("the caret", true, |_| true);
    // Under the source line, after the gutter (`   |`) if there is one.
    let caret_only = caret.trim_start().trim_start_matches('|').trim_start();
    assert!(caret_only.starts_with('^'), "{caret}");
    let line = p.wait_line("reload 2", false, |l| l.starts_with("reload 2:"));
    assert!(line.contains("ERROR: kept the last good image"), "{line}");
    assert_eq!(fx.output(), good, "output unchanged");

    // Fixed by an editor that saves by rename.
    save_by_rename(
        &fx.shader_path(),
        &fx.shader_scaled("vec3<f32>(1.0, 0.0, 0.0)"),
    );
    let line = p.wait_line("recovery", false, |l| {
        l.starts_with("reload ") && !l.contains("ERROR")
    });
    assert!(line.contains("full 64x48"), "{line}");
    let c = fx.centre();
    assert!(c[0] > 200 && c[1] == 0, "{c:?}");

    // Still alive: a scene edit.
    std::fs::write(&fx.scene, scene_json(1.5, [0.8, 0.3, 0.2])).unwrap();
    let line = p.wait_line("the scene reload", false, |l| {
        l.contains("scene (scene.json)")
    });
    assert!(line.contains("kernel kept"), "{line}");
    assert_eq!(fx.centre(), [0, 0, 0]);
    assert!(p.child.try_wait().unwrap().is_none(), "still running");
}

#[test]
fn serve_rejects_a_bad_address_and_an_unwritable_output() {
    let fx = Fixture::new();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .args(["watch", "--serve", "not an address"])
        .arg(&fx.scene)
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("not an address"), "{err}");

    let out = std::process::Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .arg("watch")
        .arg(&fx.scene)
        .arg("-o")
        .arg(fx.dir.path().join("no/such/dir/out.png"))
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("does not exist"), "{err}");
}

/// Sends `request` to the live page on a new connection and returns the
/// answer's status line (empty when the connection ended without one).
fn status_line(addr: &str, request: &[u8]) -> String {
    use std::io::{Read, Write};
    let mut s = std::net::TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(std::time::Duration::from_secs(5)))
        .unwrap();
    s.write_all(request).unwrap();
    let mut answer = Vec::new();
    let _ = s.read_to_end(&mut answer);
    let text = String::from_utf8_lossy(&answer);
    text.lines().next().unwrap_or("").to_string()
}

/// The tester's attacks on `watch --serve` (issue 36): a terabyte
/// `Content-Length` aborted the process; now it is refused and the page,
/// and the loop, go on.
#[test]
fn serve_survives_a_huge_body_and_still_follows_edits() {
    let fx = Fixture::new();
    let mut p = Child::start(&fx, &["--serve", "127.0.0.1:0", "--debounce-ms", "40"]);
    let serving = p.wait_line("the server address", false, |l| {
        l.starts_with("serving the live preview at ")
    });
    let url = serving.rsplit(' ').next().unwrap();
    let addr = url
        .trim_start_matches("http://")
        .trim_end_matches('/')
        .to_string();
    p.wait_line("the first render", false, |l| l.starts_with("reload 0:"));

    let huge = b"POST / HTTP/1.1\r\nHost: x\r\nContent-Length: 1000000000000\r\n\r\n";
    assert!(status_line(&addr, huge).starts_with("HTTP/1.1 413 "));
    let delete = b"DELETE /image.png HTTP/1.1\r\n\r\n";
    assert!(status_line(&addr, delete).starts_with("HTTP/1.1 405 "));
    let image = b"GET /image.png?v=1 HTTP/1.1\r\n\r\n";
    assert!(status_line(&addr, image).starts_with("HTTP/1.1 200 "));
    assert!(p.child.try_wait().unwrap().is_none(), "still running");

    std::fs::write(
        fx.shader_path(),
        fx.shader_scaled("vec3<f32>(0.0, 1.0, 1.0)"),
    )
    .unwrap();
    p.wait_line("reload 1", false, |l| l.starts_with("reload 1:"));
    assert_eq!(fx.centre()[0], 0);
    assert!(status_line(&addr, image).starts_with("HTTP/1.1 200 "));
}
