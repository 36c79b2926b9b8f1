//! `watch`'s preview process (src/watch/preview.rs): the worker spoken to
//! directly renders the preview the loop would have rendered, answers a
//! broken shader with nothing and goes on; the loop survives its death,
//! starts another, and leaves none behind; `--preview-process off` renders
//! the preview in the loop's own process.

use std::io::{BufReader, BufWriter};
use std::process::Stdio;
use std::time::{Duration, Instant};

use penumbra::render::Renderer;
use penumbra::watch::preview::{self, Answer, Request};
use penumbra::watch::stage::{Changes, Session};

use crate::watch_support::*;

const EVERYTHING: Changes = Changes {
    shaders: true,
    scene: true,
};

/// The stages the loop's own process renders of the fixture's files at
/// `size` (None: the scene's 64×48), with `divisors`.
fn stages_here(
    fx: &Fixture,
    size: Option<(u32, u32)>,
    divisors: &[u32],
) -> Vec<penumbra::frame::Image> {
    let mut o = fx.options();
    o.load.width = size.map(|s| s.0);
    o.load.height = size.map(|s| s.1);
    let mut s = Session::new(Renderer::new(&o.renderer).unwrap(), &fx.scene, o.load);
    assert!(s.apply(EVERYTHING).errors.is_empty());
    let mut images = Vec::new();
    s.render_stages(divisors, || false, |f| images.push(f.image))
        .unwrap();
    images
}

/// The largest difference between two images of one size, per channel.
fn largest_difference(a: &penumbra::frame::Image, b: &penumbra::frame::Image) -> f32 {
    assert_eq!((a.width, a.height), (b.width, b.height));
    a.pixels
        .iter()
        .flatten()
        .zip(b.pixels.iter().flatten())
        .map(|(x, y)| (x - y).abs())
        .fold(0f32, f32::max)
}

/// A worker (`penumbra watch` with ENV_WORKER) on the fixture, spoken to
/// directly: write requests to `input`, read answers from `output`.
struct Worker {
    child: std::process::Child,
    input: BufWriter<std::process::ChildStdin>,
    output: BufReader<std::process::ChildStdout>,
}

impl Worker {
    fn start(fx: &Fixture, extra: &[&str]) -> Worker {
        let mut child = fx
            .watch_command(extra)
            .env(preview::ENV_WORKER, "1")
            .envs(preview::QUICK_COMPILE)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .spawn()
            .unwrap();
        Worker {
            input: BufWriter::new(child.stdin.take().unwrap()),
            output: BufReader::new(child.stdout.take().unwrap()),
            child,
        }
    }

    fn send(&mut self, number: u64, changes: Changes, full: bool) {
        let req = Request {
            number,
            changes,
            textures: Vec::new(),
            full,
        };
        req.write(&mut self.input).unwrap();
    }

    fn answer(&mut self, number: u64) -> Answer {
        let (n, answer) = Answer::read(&mut self.output).unwrap();
        assert_eq!(n, number);
        answer
    }

    fn image(&mut self, number: u64, what: &str) -> preview::Preview {
        match self.answer(number) {
            Answer::Image(p) => p,
            other => panic!("no {what}: {other:?}"),
        }
    }
}

const SHADER_EDIT: Changes = Changes {
    shaders: true,
    scene: false,
};

#[test]
fn the_worker_renders_the_loops_images_and_survives_a_broken_shader() {
    let fx = Fixture::new();
    let want = stages_here(&fx, None, &[4, 1]);
    let mut w = Worker::start(&fx, &[]);

    // Compiled without LLVM's optimisations at 128 bits, the images of the
    // loop's own 16×12 preview and 64×48 full image: bit for bit on the
    // Zen 4 of docs/watch.md. The bound allows only what another CPU may
    // give at another SIMD width (lavapipe picks its rsqrt and rcp
    // approximations per width and instruction set, each within 2^-12
    // before a Newton step); a wrong scene, size, shader or setting is off
    // by far more.
    w.send(0, EVERYTHING, false);
    let p = w.image(0, "preview");
    assert_eq!((p.image.width, p.image.height), (16, 12));
    assert_eq!(p.full, (64, 48));
    assert!(p.compile[2] > Duration::ZERO, "the driver compiled");
    assert!(
        p.image.pixels.iter().any(|px| px[0] > 0.1),
        "the sphere is lit"
    );
    let off = largest_difference(&p.image, &want[0]);
    assert!(off <= 1e-4, "the loop's preview differs by {off}");
    // The full image too, when asked: a second answer.
    w.send(1, SHADER_EDIT, true);
    let _ = w.image(1, "preview");
    let f = w.image(1, "full image");
    assert_eq!((f.image.width, f.image.height), (64, 48));
    let off = largest_difference(&f.image, &want[1]);
    assert!(off <= 1e-4, "the loop's full image differs by {off}");

    // A broken shader: nothing to show, and no second answer; then a good
    // one renders both on the kept hit records.
    std::fs::write(fx.shader_path(), fx.shader_scaled("vec3<f32>(0.0) *")).unwrap();
    w.send(2, SHADER_EDIT, true);
    assert_eq!(w.answer(2), Answer::Nothing);
    std::fs::write(
        fx.shader_path(),
        fx.shader_scaled("vec3<f32>(0.0, 1.0, 1.0)"),
    )
    .unwrap();
    w.send(3, SHADER_EDIT, true);
    for (what, size) in [("preview", (16, 12)), ("full image", (64, 48))] {
        let p = w.image(3, what);
        assert_eq!((p.image.width, p.image.height), size);
        assert!(p.hits_reused, "{what}");
        assert!(p.image.pixels.iter().all(|px| px[0] == 0.0), "red is gone");
        assert!(p.image.pixels.iter().any(|px| px[1] > 0.1));
    }

    // The loop's end (its pipe closed) ends the worker.
    drop(w.input);
    assert!(w.child.wait().unwrap().success());
}

#[test]
fn a_newer_request_stops_the_workers_full_image() {
    let fx = Fixture::new();
    // 200 rows: the full image renders in 4 bands of 64 rows.
    let mut w = Worker::start(&fx, &["--width", "64", "--height", "200"]);
    w.send(0, EVERYTHING, false);
    let _ = w.image(0, "preview");
    // Two edits at once: the second is waiting when the first's full image
    // starts, so it stops after its first band and says so.
    std::fs::write(
        fx.shader_path(),
        fx.shader_scaled("vec3<f32>(0.0, 1.0, 1.0)"),
    )
    .unwrap();
    w.send(1, SHADER_EDIT, true);
    w.send(2, SHADER_EDIT, true);
    let p = w.image(1, "preview");
    assert_eq!((p.image.width, p.image.height), (16, 50));
    assert_eq!(w.answer(1), Answer::Nothing, "the full image went on");
    let _ = w.image(2, "preview");
    let f = w.image(2, "full image");
    assert_eq!((f.image.width, f.image.height), (64, 200));
    let want = stages_here(&fx, Some((64, 200)), &[1]);
    let off = largest_difference(&f.image, &want[0]);
    assert!(off <= 1e-4, "the loop's full image differs by {off}");
}

/// The pids of `pid`'s children.
fn children(pid: u32) -> Vec<u32> {
    let mut out = Vec::new();
    for task in std::fs::read_dir(format!("/proc/{pid}/task")).unwrap() {
        let list =
            std::fs::read_to_string(task.unwrap().path().join("children")).unwrap_or_default();
        out.extend(
            list.split_whitespace()
                .filter_map(|p| p.parse::<u32>().ok()),
        );
    }
    out
}

/// Whether process `pid` runs (not gone, not a zombie).
fn running(pid: u32) -> bool {
    std::fs::read_to_string(format!("/proc/{pid}/stat")).is_ok_and(|s| {
        s.rsplit(')')
            .next()
            .is_some_and(|r| !r.trim_start().starts_with('Z'))
    })
}

#[test]
fn the_loop_outlives_its_preview_process_and_leaves_none_behind() {
    let fx = Fixture::new();
    let mut p = Child::start(&fx, &["--debounce-ms", "40"]);
    let line = p.wait_line("the first render", false, |l| {
        l.starts_with("reload 0: start")
    });
    assert!(line.contains("preview 16x12 (preview process)"), "{line}");
    let workers = children(p.child.id());
    assert_eq!(workers.len(), 1, "one preview process: {workers:?}");
    // SAFETY: kill(2) on a process this test's child started.
    assert_eq!(unsafe { libc::kill(workers[0] as i32, libc::SIGKILL) }, 0);

    std::fs::write(
        fx.shader_path(),
        fx.shader_scaled("vec3<f32>(0.0, 1.0, 1.0)"),
    )
    .unwrap();
    let line = p.wait_line("reload 1", false, |l| l.starts_with("reload 1:"));
    assert!(
        line.contains("full 64x48") && !line.contains("ERROR"),
        "{line}"
    );
    assert_eq!(fx.centre()[0], 0);
    // The next edit has a preview process again.
    std::fs::write(
        fx.shader_path(),
        fx.shader_scaled("vec3<f32>(1.0, 0.0, 1.0)"),
    )
    .unwrap();
    let line = p.wait_line("reload 2", false, |l| l.starts_with("reload 2:"));
    assert!(line.contains("preview 16x12 (preview process)"), "{line}");
    let again: Vec<u32> = children(p.child.id())
        .into_iter()
        .filter(|&c| running(c))
        .collect();
    assert_eq!(again.len(), 1, "{again:?}");
    assert_ne!(again, workers);

    // Ctrl-C ends the loop and its preview process.
    // SAFETY: kill(2) on our own child's pid.
    assert_eq!(unsafe { libc::kill(p.child.id() as i32, libc::SIGINT) }, 0);
    p.child.wait().unwrap();
    let t = Instant::now();
    while running(again[0]) {
        assert!(
            t.elapsed() < Duration::from_secs(5),
            "the preview process outlived watch"
        );
        std::thread::sleep(Duration::from_millis(10));
    }
}

#[test]
fn preview_process_off_renders_the_preview_in_the_loop() {
    let fx = Fixture::new();
    let mut p = Child::start(&fx, &["--debounce-ms", "40", "--preview-process", "off"]);
    let line = p.wait_line("the first render", false, |l| {
        l.starts_with("reload 0: start")
    });
    assert!(line.contains("| preview 16x12: render"), "{line}");
    assert!(!line.contains("preview process"), "{line}");
    assert!(children(p.child.id()).is_empty());
}
