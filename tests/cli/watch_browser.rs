//! End to end: `penumbra watch --serve` driven in headless Chromium (Debian's
//! `chromium`, installed by `tools/setup.sh --tests`) over the DevTools protocol
//! on a pipe (`--remote-debugging-pipe`: no WebSocket client needed). A
//! shader edit must change the image on the page, a broken shader must show
//! its error over the last good image, and the fix must clear it.

use std::fs::File;
use std::io::{BufRead, BufReader, Write};
use std::os::fd::FromRawFd;
use std::os::unix::process::CommandExt;
use std::process::{Command, Stdio};
use std::sync::mpsc::{Receiver, RecvTimeoutError};
use std::time::{Duration, Instant};

use crate::watch_support::*;
use serde_json::{json, Value};

/// Headless Chromium with the DevTools protocol on fds 3 (in) and 4 (out).
struct Browser {
    child: std::process::Child,
    to: File,
    from: Receiver<Value>,
    next_id: u64,
    session: String,
    _profile: tempfile::TempDir,
}

fn find_chromium() -> std::path::PathBuf {
    for p in ["/usr/bin/chromium", "/usr/bin/chromium-browser"] {
        if std::path::Path::new(p).exists() {
            return p.into();
        }
    }
    panic!("this test needs Debian's chromium: run `tools/setup.sh --tests` (or apt-get install chromium)");
}

fn pipe() -> (i32, i32) {
    let mut fds = [0; 2];
    // SAFETY: fds is a valid array of two ints.
    let rc = unsafe { libc::pipe2(fds.as_mut_ptr(), libc::O_CLOEXEC) };
    assert_eq!(rc, 0, "pipe2: {}", std::io::Error::last_os_error());
    (fds[0], fds[1])
}

impl Browser {
    fn open(url: &str) -> Browser {
        let profile = tempfile::tempdir().unwrap();
        let (cmd_r, cmd_w) = pipe();
        let (res_r, res_w) = pipe();
        let mut cmd = Command::new(find_chromium());
        cmd.args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--remote-debugging-pipe",
        ])
        .arg(format!("--user-data-dir={}", profile.path().display()))
        .arg("about:blank")
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null());
        // SAFETY: only async-signal-safe calls (fcntl, dup2) between fork and exec.
        unsafe {
            cmd.pre_exec(move || {
                // Out of the way of 3 and 4 first, then into place (dup2
                // clears close-on-exec).
                let r = libc::fcntl(cmd_r, libc::F_DUPFD_CLOEXEC, 10);
                let w = libc::fcntl(res_w, libc::F_DUPFD_CLOEXEC, 10);
                if r < 0 || w < 0 || libc::dup2(r, 3) < 0 || libc::dup2(w, 4) < 0 {
                    return Err(std::io::Error::last_os_error());
                }
                Ok(())
            });
        }
        let child = cmd.spawn().expect("start chromium");
        // SAFETY: the fds come from pipe2 above and are owned here only.
        let (to, from_file) = unsafe {
            libc::close(cmd_r);
            libc::close(res_w);
            (File::from_raw_fd(cmd_w), File::from_raw_fd(res_r))
        };
        let (tx, from) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            let mut r = BufReader::new(from_file);
            let mut buf = Vec::new();
            while r.read_until(0, &mut buf).map(|n| n > 0).unwrap_or(false) {
                if buf.last() == Some(&0) {
                    buf.pop();
                }
                if let Ok(v) = serde_json::from_slice::<Value>(&buf) {
                    if tx.send(v).is_err() {
                        return;
                    }
                }
                buf.clear();
            }
        });
        let mut b = Browser {
            child,
            to,
            from,
            next_id: 0,
            session: String::new(),
            _profile: profile,
        };
        let target = b.call(None, "Target.createTarget", json!({ "url": url }));
        let target_id = target["targetId"].as_str().expect("targetId").to_string();
        let attached = b.call(
            None,
            "Target.attachToTarget",
            json!({ "targetId": target_id, "flatten": true }),
        );
        b.session = attached["sessionId"]
            .as_str()
            .expect("sessionId")
            .to_string();
        b
    }

    fn call(&mut self, session: Option<&str>, method: &str, params: Value) -> Value {
        self.next_id += 1;
        let id = self.next_id;
        let mut msg = json!({ "id": id, "method": method, "params": params });
        if let Some(s) = session {
            msg["sessionId"] = json!(s);
        }
        let mut bytes = serde_json::to_vec(&msg).unwrap();
        bytes.push(0);
        self.to.write_all(&bytes).expect("write to chromium");
        let end = Instant::now() + Duration::from_secs(60);
        loop {
            let left = end.saturating_duration_since(Instant::now());
            match self.from.recv_timeout(left) {
                Ok(v) if v["id"].as_u64() == Some(id) => {
                    if let Some(e) = v.get("error") {
                        panic!("{method}: {e}");
                    }
                    return v["result"].clone();
                }
                Ok(_) => continue, // events
                Err(RecvTimeoutError::Timeout) => panic!("{method}: no answer from chromium"),
                Err(RecvTimeoutError::Disconnected) => {
                    panic!("{method}: chromium went away: {:?}", self.child.try_wait())
                }
            }
        }
    }

    /// What the page shows: image version, the centre pixel of the image as
    /// drawn, the error box and the timing line.
    fn page(&mut self) -> Value {
        const EXPR: &str = r#"(() => {
            const img = document.getElementById('image');
            const err = document.getElementById('error');
            let px = null;
            if (img.complete && img.naturalWidth > 0) {
                const c = document.createElement('canvas');
                c.width = img.naturalWidth; c.height = img.naturalHeight;
                const g = c.getContext('2d');
                g.drawImage(img, 0, 0);
                px = Array.from(g.getImageData(32, 24, 1, 1).data.slice(0, 3));
            }
            return JSON.stringify({
                version: img.dataset.version || null,
                // The latest image the server announced (the page's own
                // variable); `version` catches up once it has loaded.
                announced: typeof shown === 'undefined' ? null : String(shown),
                px,
                error: err.hidden ? null : err.textContent,
                line: document.getElementById('line').textContent,
                status: document.getElementById('status').textContent,
            });
        })()"#;
        let session = self.session.clone();
        let r = self.call(
            Some(&session),
            "Runtime.evaluate",
            json!({ "expression": EXPR, "returnByValue": true }),
        );
        let s = r["result"]["value"].as_str().unwrap_or("null").to_string();
        serde_json::from_str(&s).unwrap_or(Value::Null)
    }

    /// Polls the page until `pred` holds; panics after [`TIMEOUT`].
    fn wait(&mut self, what: &str, mut pred: impl FnMut(&Value) -> bool) -> Value {
        let end = Instant::now() + TIMEOUT;
        let mut last = Value::Null;
        while Instant::now() < end {
            last = self.page();
            if pred(&last) {
                return last;
            }
            std::thread::sleep(Duration::from_millis(100));
        }
        panic!("the page never showed {what}; last seen: {last}");
    }
}

impl Drop for Browser {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn px(v: &Value) -> Option<[u64; 3]> {
    let a = v["px"].as_array()?;
    Some([a[0].as_u64()?, a[1].as_u64()?, a[2].as_u64()?])
}

#[test]
fn the_live_page_follows_edits_and_shows_errors() {
    let fx = Fixture::new();
    let mut p = Child::start(&fx, &["--serve", "127.0.0.1:0"]);
    let serving = p.wait_line("the server address", false, |l| {
        l.starts_with("serving the live preview at ")
    });
    let url = serving.rsplit(' ').next().unwrap().to_string();
    assert!(url.starts_with("http://127.0.0.1:"), "{url}");
    p.wait_line("the first render", false, |l| l.starts_with("reload 0:"));

    let mut b = Browser::open(&url);
    let first = b.wait("the first image, live", |v| {
        px(v).is_some_and(|c| c[0] > 200)
            && v["status"] == "live"
            && v["line"].as_str().is_some_and(|l| l.contains("full 64x48"))
    });
    assert!(first["error"].is_null(), "{first}");
    let v0 = first["version"].as_str().unwrap().to_string();

    // A shader edit: the page's image loses its red.
    std::fs::write(
        fx.shader_path(),
        fx.shader_scaled("vec3<f32>(0.0, 1.0, 1.0)"),
    )
    .unwrap();
    // The reload's last image: its timing line is published after all of
    // its images, and the page must show the latest one it was told of
    // (else the full image can replace the preview after the error below).
    let edited = b.wait("the edited image", |v| {
        px(v).is_some_and(|c| c[0] == 0)
            && v["line"]
                .as_str()
                .is_some_and(|l| l.contains("shaders (shading/phong.wgsl)"))
            && v["version"] == v["announced"]
    });
    assert_ne!(edited["version"].as_str().unwrap(), v0);
    assert!(edited["error"].is_null(), "{edited}");
    assert!(
        edited["line"]
            .as_str()
            .unwrap()
            .contains("shaders (shading/phong.wgsl)"),
        "{edited}"
    );
    let good = px(&edited).unwrap();

    // Broken: the error appears over the last good image.
    let broken = fx.shader_scaled("vec3<f32>(0.0, 1.0, 1.0) +");
    let n = broken.lines().position(|l| l.contains("1.0) +;")).unwrap() + 1;
    std::fs::write(fx.shader_path(), &broken).unwrap();
    let at = format!("shading/phong.wgsl:{n}:");
    let shown = b.wait("the error", |v| {
        v["error"].as_str().is_some_and(|e| e.contains(&at))
    });
    let e = shown["error"].as_str().unwrap();
    assert!(e.contains("1.0) +;") && e.contains('^'), "{e}");
    assert_eq!(px(&shown), Some(good), "the last good image stays");
    assert_eq!(shown["version"], edited["version"]);

    // Fixed: the error clears and the new image shows.
    std::fs::write(
        fx.shader_path(),
        fx.shader_scaled("vec3<f32>(1.0, 0.0, 1.0)"),
    )
    .unwrap();
    let fixed = b.wait("the fixed image without error", |v| {
        v["error"].is_null() && px(v).is_some_and(|c| c[0] > 200 && c[1] == 0)
    });
    assert_ne!(fixed["version"], edited["version"]);
}
