//! `watch`'s preview process (src/watch/preview.rs): the worker spoken to
//! directly renders the preview the loop would have rendered, answers a
//! broken shader with nothing and goes on; the loop survives its death,
//! starts another, and leaves none behind; `--preview-process off` renders
//! the preview in the loop's own process.

use std::io::{BufReader, BufWriter};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use penumbra::render::Renderer;
use penumbra::watch::preview::{self, Answer, Request};
use penumbra::watch::stage::{Changes, Session};

use crate::watch_support::*;

const EVERYTHING: Changes = Changes {
    shaders: true,
    scene: true,
};

/// The preview the loop's own process renders of the fixture's files.
fn preview_here(fx: &Fixture) -> penumbra::frame::Image {
    let o = fx.options();
    let mut s = Session::new(Renderer::new(&o.renderer).unwrap(), &fx.scene, o.load);
    assert!(s.apply(EVERYTHING).errors.is_empty());
    let mut image = None;
    s.render_stages(&[4], || false, |f| image = Some(f.image))
        .unwrap();
    image.unwrap()
}

#[test]
fn the_worker_renders_the_loops_preview_and_survives_a_broken_shader() {
    let fx = Fixture::new();
    let want = preview_here(&fx);
    let mut child = Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .arg("watch")
        .arg(&fx.scene)
        .arg("-o")
        .arg(&fx.out)
        .arg("--shaders")
        .arg(&fx.shaders)
        .env(preview::ENV_WORKER, "1")
        .envs(preview::QUICK_COMPILE)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    let mut input = BufWriter::new(child.stdin.take().unwrap());
    let mut output = BufReader::new(child.stdout.take().unwrap());
    let mut ask = |number: u64, changes: Changes| {
        let req = Request {
            number,
            changes,
            textures: Vec::new(),
        };
        req.write(&mut input).unwrap();
        let (n, answer) = Answer::read(&mut output).unwrap();
        assert_eq!(n, number);
        answer
    };

    // Compiled without LLVM's optimisations at 128 bits, the image of the
    // loop's own 16×12 preview: bit for bit on the Zen 4 of docs/watch.md.
    // The bound allows only what another CPU may give at another SIMD width
    // (lavapipe picks its rsqrt and rcp approximations per width and
    // instruction set, each within 2^-12 before a Newton step); a wrong
    // scene, size, shader or setting is off by far more.
    let Answer::Image(p) = ask(0, EVERYTHING) else {
        panic!("no preview");
    };
    assert_eq!((p.image.width, p.image.height), (16, 12));
    assert_eq!(p.full, (64, 48));
    assert!(p.compile[2] > Duration::ZERO, "the driver compiled");
    assert!(
        p.image.pixels.iter().any(|px| px[0] > 0.1),
        "the sphere is lit"
    );
    assert_eq!((want.width, want.height), (16, 12));
    let off = p
        .image
        .pixels
        .iter()
        .flatten()
        .zip(want.pixels.iter().flatten())
        .map(|(a, b)| (a - b).abs())
        .fold(0f32, f32::max);
    assert!(off <= 1e-4, "the loop's preview differs by {off}");

    // A broken shader: nothing to show; then a good one renders on the
    // kept hit records.
    let edit = Changes {
        shaders: true,
        scene: false,
    };
    std::fs::write(fx.shader_path(), fx.shader_scaled("vec3<f32>(0.0) *")).unwrap();
    assert_eq!(ask(1, edit), Answer::Nothing);
    std::fs::write(
        fx.shader_path(),
        fx.shader_scaled("vec3<f32>(0.0, 1.0, 1.0)"),
    )
    .unwrap();
    let Answer::Image(p) = ask(2, edit) else {
        panic!("no preview after the fix");
    };
    assert!(p.hits_reused);
    assert!(p.image.pixels.iter().all(|px| px[0] == 0.0), "red is gone");
    assert!(p.image.pixels.iter().any(|px| px[1] > 0.1));

    // The loop's end (its pipe closed) ends the worker.
    drop(input);
    assert!(child.wait().unwrap().success());
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
    assert!(line.contains("preview (preview process) 16x12"), "{line}");
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
    assert!(line.contains("preview (preview process) 16x12"), "{line}");
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
