//! Shared set-up of the hot-reload tests: a temporary copy of the shaders and
//! a small scene, edits, and waiting for reloads with generous timeouts
//! (polling, never a fixed sleep as the only synchronisation).
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, RecvTimeoutError};
use std::sync::Arc;
use std::time::{Duration, Instant};

use penumbra::render::ShaderSource;
use penumbra::watch::{self, Event, Reload, WatchOptions};

/// A first render compiles the kernel (lavapipe: about a second per kernel
/// on two cores, more under the validation layer); allow far more.
pub const TIMEOUT: Duration = Duration::from_secs(120);

/// A red sphere at the origin, seen from +z; `x` moves it sideways.
pub fn scene_json(x: f64, rgb: [f64; 3]) -> String {
    format!(
        r#"{{
  "camera": {{ "position": [0, 0, 5], "look_at": [0, 0, 0], "up": [0, 1, 0], "fov": 40, "width": 64, "height": 48 }},
  "background": [0, 0, 0],
  "shaders": {{ "m": {{ "type": "phong", "ambient": {rgb:?}, "diffuse": [0, 0, 0], "specular": [0, 0, 0], "shininess": 1 }} }},
  "objects": [ {{ "type": "sphere", "center": [{x}, 0, 0], "radius": 1, "shader": "m" }} ],
  "lights": [ {{ "type": "directional", "direction": [0, 0, -1], "ambient": [1, 1, 1], "diffuse": [0, 0, 0], "specular": [0, 0, 0] }} ]
}}"#
    )
}

/// Copies a directory tree.
pub fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let entry = entry.unwrap();
        let dest = to.join(entry.file_name());
        if entry.file_type().unwrap().is_dir() {
            copy_dir(&entry.path(), &dest);
        } else {
            std::fs::copy(entry.path(), dest).unwrap();
        }
    }
}

/// A temporary directory with `shaders/`, `scene.json` and the output path.
pub struct Fixture {
    pub dir: tempfile::TempDir,
    pub shaders: PathBuf,
    pub scene: PathBuf,
    pub out: PathBuf,
    /// `shading/phong.wgsl` as copied.
    pub shader_original: String,
}

/// The shader file the tests edit: the built-in Phong shader, which the
/// fixture's scene uses.
pub const SHADER: &str = "shading/phong.wgsl";

impl Fixture {
    pub fn new() -> Fixture {
        let dir = tempfile::tempdir().unwrap();
        let shaders = dir.path().join("shaders");
        copy_dir(
            &Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders"),
            &shaders,
        );
        let scene = dir.path().join("scene.json");
        std::fs::write(&scene, scene_json(0.0, [0.8, 0.3, 0.2])).unwrap();
        let out = dir.path().join("out.png");
        let shader_original = std::fs::read_to_string(shaders.join(SHADER)).unwrap();
        Fixture {
            dir,
            shaders,
            scene,
            out,
            shader_original,
        }
    }

    pub fn options(&self) -> WatchOptions {
        let mut o = WatchOptions::new(&self.scene, &self.out);
        o.renderer.shaders = ShaderSource::Directory(self.shaders.clone());
        o.renderer.validation = std::env::var("PENUMBRA_VALIDATION").as_deref() == Ok("1");
        o
    }

    pub fn shader_path(&self) -> PathBuf {
        self.shaders.join(SHADER)
    }

    /// `ambient()` and `shade()` with their colours multiplied by `factor`
    /// (WGSL).
    pub fn shader_scaled(&self, factor: &str) -> String {
        scale_shade(&self.shader_original, factor)
    }

    /// `penumbra watch SCENE -o OUT --shaders DIR` plus `extra` (and
    /// `--validate` under PENUMBRA_VALIDATION=1), not started.
    pub fn watch_command(&self, extra: &[&str]) -> std::process::Command {
        let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_penumbra"));
        cmd.arg("watch")
            .arg(&self.scene)
            .arg("-o")
            .arg(&self.out)
            .arg("--shaders")
            .arg(&self.shaders)
            .args(extra);
        if std::env::var("PENUMBRA_VALIDATION").as_deref() == Ok("1") {
            cmd.arg("--validate");
        }
        cmd
    }

    pub fn output(&self) -> Vec<u8> {
        std::fs::read(&self.out).unwrap()
    }

    /// The output's centre pixel, sRGB 8 bit.
    pub fn centre(&self) -> [u8; 3] {
        pixel(&self.out, 32, 24)
    }
}

/// Multiplies what `ambient()` and `shade()` return by `factor` (WGSL):
/// the colour of a Phong-type shader file, scaled.
pub fn scale_shade(src: &str, factor: &str) -> String {
    let src = scale_return(src, "fn ambient(", factor);
    scale_return(&src, "fn shade(", factor)
}

/// Multiplies the value of the first `return` after `function` (e.g.
/// `fn shade(`) by `factor`.
pub fn scale_return(src: &str, function: &str, factor: &str) -> String {
    let start = src
        .find(function)
        .unwrap_or_else(|| panic!("the shader has {function}"));
    let ret = start
        + src[start..]
            .find("return ")
            .unwrap_or_else(|| panic!("{function} returns"));
    let value = ret + "return ".len();
    let end = value + src[value..].find(';').expect("return ...;");
    format!(
        "{}({}) * {factor}{}",
        &src[..value],
        &src[value..end],
        &src[end..]
    )
}

/// The name a reload report gives the shade pipeline of shader file `path`
/// (a built-in in the watched `--shaders` copy, or a user's file): as the
/// loop resolves the directory.
pub fn shade_name(path: &Path) -> String {
    let dir = path.parent().unwrap().canonicalize().unwrap();
    format!("shade {}", dir.join(path.file_name().unwrap()).display())
}

/// A pixel of a PNG file.
pub fn pixel(path: &Path, x: u32, y: u32) -> [u8; 3] {
    let img = image::open(path).unwrap().to_rgb8();
    img.get_pixel(x, y).0
}

/// Writes `text` to `path` the way editors that save by rename do: a new
/// file beside it, renamed over it (the old inode goes away).
pub fn save_by_rename(path: &Path, text: &str) {
    let tmp = path.with_extension("swp~");
    std::fs::write(&tmp, text).unwrap();
    std::fs::rename(&tmp, path).unwrap();
}

/// The loop running in a thread of this test.
pub struct Running {
    pub stop: Arc<AtomicBool>,
    pub rx: Receiver<Event>,
    pub thread: Option<std::thread::JoinHandle<anyhow::Result<()>>>,
    pub reloads: Vec<Reload>,
}

impl Running {
    pub fn start(opts: WatchOptions) -> Running {
        let stop = Arc::new(AtomicBool::new(false));
        let (tx, rx) = std::sync::mpsc::channel();
        let s = stop.clone();
        let thread = std::thread::spawn(move || watch::run(&opts, s, tx));
        let mut r = Running {
            stop,
            rx,
            thread: Some(thread),
            reloads: Vec::new(),
        };
        let first = r.next_reload();
        assert_eq!(first.number, 0);
        r
    }

    /// The next reload, or a panic after [`TIMEOUT`].
    pub fn next_reload(&mut self) -> Reload {
        self.next_reload_within(TIMEOUT)
            .unwrap_or_else(|| panic!("no reload within {TIMEOUT:?}; so far: {:#?}", self.reloads))
    }

    pub fn next_reload_within(&mut self, timeout: Duration) -> Option<Reload> {
        let end = Instant::now() + timeout;
        loop {
            let left = end.saturating_duration_since(Instant::now());
            match self.rx.recv_timeout(left) {
                Ok(Event::Reload(r)) => {
                    eprintln!("{}", r.line);
                    for e in &r.errors {
                        eprintln!("  error: {e}");
                    }
                    self.reloads.push(r.clone());
                    return Some(r);
                }
                Ok(_) => continue,
                Err(RecvTimeoutError::Timeout) => return None,
                Err(RecvTimeoutError::Disconnected) => {
                    let t = self.thread.take().unwrap();
                    panic!("the loop ended: {:?}", t.join());
                }
            }
        }
    }

    /// Reloads until `pred` holds for one (edits may be seen as more than
    /// one batch); panics after [`TIMEOUT`].
    pub fn reload_until(&mut self, what: &str, mut pred: impl FnMut(&Reload) -> bool) -> Reload {
        let end = Instant::now() + TIMEOUT;
        loop {
            let left = end.saturating_duration_since(Instant::now());
            match self.next_reload_within(left) {
                Some(r) if pred(&r) => return r,
                Some(_) => continue,
                None => panic!(
                    "no reload with {what} within {TIMEOUT:?}; so far: {:#?}",
                    self.reloads
                ),
            }
        }
    }
}

impl Drop for Running {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            if let Ok(Err(e)) = t.join() {
                if !std::thread::panicking() {
                    panic!("the loop failed: {e:#}");
                }
            }
        }
    }
}

/// `penumbra watch` running as a child process; killed on drop.
pub struct Child {
    pub child: std::process::Child,
    lines: Receiver<(bool, String)>,
    /// Everything read so far: (from stderr, line).
    pub seen: Vec<(bool, String)>,
    /// Per stream (stdout, stderr): where the next wait starts in `seen`.
    cursor: [usize; 2],
}

impl Child {
    /// Starts `penumbra watch SCENE -o OUT --shaders DIR` plus `extra`.
    pub fn start(fx: &Fixture, extra: &[&str]) -> Child {
        use std::io::BufRead;
        use std::process::Stdio;
        let mut cmd = fx.watch_command(extra);
        cmd.stdout(Stdio::piped()).stderr(Stdio::piped());
        let mut child = cmd.spawn().expect("start penumbra watch");
        let (tx, lines) = std::sync::mpsc::channel();
        let out = child.stdout.take().unwrap();
        let err = child.stderr.take().unwrap();
        let tx2 = tx.clone();
        std::thread::spawn(move || {
            for l in std::io::BufReader::new(out).lines().map_while(Result::ok) {
                let _ = tx.send((false, l));
            }
        });
        std::thread::spawn(move || {
            for l in std::io::BufReader::new(err).lines().map_while(Result::ok) {
                let _ = tx2.send((true, l));
            }
        });
        Child {
            child,
            lines,
            seen: Vec::new(),
            cursor: [0, 0],
        }
    }

    /// Waits for a line of stdout (`err` false) or stderr (`err` true)
    /// matching `pred`, after the last one matched on that stream; panics
    /// after [`TIMEOUT`] or when the process ends.
    pub fn wait_line(
        &mut self,
        what: &str,
        err: bool,
        mut pred: impl FnMut(&str) -> bool,
    ) -> String {
        let end = Instant::now() + TIMEOUT;
        let mut at = self.cursor[err as usize];
        loop {
            while at < self.seen.len() {
                let (is_err, l) = &self.seen[at];
                at += 1;
                if *is_err == err && pred(l) {
                    self.cursor[err as usize] = at;
                    return l.clone();
                }
            }
            let left = end.saturating_duration_since(Instant::now());
            match self.lines.recv_timeout(left) {
                Ok((is_err, l)) => {
                    eprintln!("{}{l}", if is_err { "[stderr] " } else { "" });
                    self.seen.push((is_err, l));
                }
                Err(e) => panic!(
                    "no line with {what} ({e:?}); exit: {:?}; output so far:\n{}",
                    self.child.try_wait(),
                    self.transcript()
                ),
            }
        }
    }

    /// Everything read so far.
    pub fn transcript(&self) -> String {
        self.seen
            .iter()
            .map(|(e, l)| format!("{}{l}", if *e { "[stderr] " } else { "" }))
            .collect::<Vec<_>>()
            .join("\n")
    }
}

impl Drop for Child {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}
