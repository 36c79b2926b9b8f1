//! The hot-reload loop driven in-process on a temporary copy of the shaders
//! and a small scene: shader edits, broken and fixed shaders, scene edits,
//! editors that save by rename or by delete and re-create, bursts of saves.

use crate::watch_support;

use std::time::Duration;

use crate::watch_support::*;

#[test]
fn shader_and_scene_edits_reload_and_errors_keep_the_last_image() {
    let fx = Fixture::new();
    let mut w = Running::start(fx.options());
    let first = &w.reloads[0];
    assert!(first.errors.is_empty(), "{:?}", first.errors);
    let sizes: Vec<_> = first.stages.iter().map(|s| (s.width, s.height)).collect();
    assert_eq!(
        sizes,
        [(16, 12), (64, 48)],
        "a 1/4 preview, then the full image"
    );
    let c0 = fx.centre();
    assert!(c0[0] > 200 && c0[1] > 100, "the red sphere: {c0:?}");

    // A shader edit: no red any more. The kernel is recompiled, the scene
    // upload kept.
    std::fs::write(
        fx.shader_path(),
        fx.shader_scaled("vec3<f32>(0.0, 1.0, 1.0)"),
    )
    .unwrap();
    let r = w.next_reload();
    assert!(r.changes.shaders && !r.changes.scene, "{}", r.line);
    assert!(r.errors.is_empty(), "{:?}", r.errors);
    assert!(r.compile.is_some() && r.upload.is_none(), "{}", r.line);
    // Only the Phong file's shade pipeline, not the traversal; the render
    // after it reuses the hit records.
    assert_eq!(
        r.compile.as_ref().unwrap().recompiled,
        [shade_name(&fx.shader_path())],
        "{}",
        r.line
    );
    assert!(r.stages.iter().all(|s| s.hits_reused), "{r:#?}");
    assert!(
        r.line.contains("shaders (shading/phong.wgsl)"),
        "{}",
        r.line
    );
    assert!(
        r.line.contains("compile ") && r.line.contains("latency "),
        "{}",
        r.line
    );
    let c1 = fx.centre();
    assert_eq!(c1[0], 0, "red multiplied by 0: {c1:?}");
    assert!(
        c1[1].abs_diff(c0[1]) <= 1 && c1[2].abs_diff(c0[2]) <= 1,
        "{c0:?} -> {c1:?}"
    );
    let good = fx.output();

    // Broken: the error names the file, line and column, shows the line and a
    // caret; the output is untouched.
    let broken = fx.shader_scaled("vec3<f32>(0.0, 1.0, 1.0) +");
    let line = broken
        .lines()
        .position(|l| l.contains("vec3<f32>(0.0, 1.0, 1.0) +;"))
        .unwrap()
        + 1;
    std::fs::write(fx.shader_path(), &broken).unwrap();
    let r = w.next_reload();
    assert_eq!(r.errors.len(), 1, "{r:#?}");
    let e = &r.errors[0];
    let want = format!("{}:{line}:", fx.shader_path().display());
    assert!(e.contains(&want), "error should name {want}: {e}");
    let lines: Vec<&str> = e.lines().collect();
    assert!(lines.len() >= 3, "{e}");
    assert!(lines[1].contains(") * vec3<f32>(0.0, 1.0, 1.0) +;"), "{e}");
    let caret_only = lines[2].trim_start().trim_start_matches('|').trim_start();
    assert!(caret_only.starts_with('^'), "caret line: {e}");
    // The caret sits under the column the location names: the source line
    // is shown whole after a gutter of some width, the caret line has the
    // same gutter.
    let col: usize = lines[0]
        .split(&want)
        .nth(1)
        .and_then(|rest| rest.split(':').next())
        .and_then(|c| c.parse().ok())
        .unwrap_or_else(|| panic!("no column in {e}"));
    let source = broken.lines().nth(line - 1).unwrap();
    let gutter = lines[1].len() - source.len();
    assert!(lines[1].ends_with(source), "{e}");
    assert_eq!(lines[2].find('^').unwrap() - gutter, col - 1, "{e}");
    assert!(r.stages.is_empty(), "{r:#?}");
    assert!(r.line.contains("ERROR"), "{}", r.line);
    assert_eq!(
        fx.output(),
        good,
        "a broken shader must not touch the output"
    );

    // A scene edit while the Phong file is broken: the scene's shaders
    // cannot be read, so the scene cannot be uploaded; the error names the
    // shader file and the output stays.
    std::fs::write(&fx.scene, watch_support::scene_json(0.0, [0.8, 0.6, 0.2])).unwrap();
    let r = w.next_reload();
    assert!(r.changes.scene && !r.changes.shaders, "{}", r.line);
    assert!(r.stages.is_empty(), "{r:#?}");
    assert!(r.errors.iter().any(|e| e.contains(&want)), "{r:#?}");
    assert_eq!(fx.output(), good);

    // Fixed: recovery, with the new colour and the scene edit made while the
    // shader was broken (a shader edit retries a scene that did not load).
    std::fs::write(
        fx.shader_path(),
        fx.shader_scaled("vec3<f32>(1.0, 0.0, 1.0)"),
    )
    .unwrap();
    let r = w.next_reload();
    assert!(r.errors.is_empty(), "{:?}", r.errors);
    assert!(r.upload.is_some(), "the scene was retried: {}", r.line);
    let c3 = fx.centre();
    assert!(c3[0] > 200 && c3[1] == 0 && c3[2] > 20, "{c3:?}");

    // Scene edit: the sphere moves right; the kernel is kept (same features).
    std::fs::write(&fx.scene, watch_support::scene_json(1.5, [0.8, 0.6, 0.2])).unwrap();
    let r = w.next_reload();
    assert!(
        r.changes.scene && r.upload.is_some() && r.compile.is_none(),
        "{}",
        r.line
    );
    assert!(
        r.stages.iter().all(|s| s.compile.total().is_zero()),
        "{r:#?}"
    );
    assert!(r.line.contains("kernel kept"), "{}", r.line);
    assert_eq!(fx.centre(), [0, 0, 0], "background where the sphere was");
    // 1.5 units right at distance 5 with a 40° field of view: x ≈ 32 + 24·1.5/(5·tan 20°) ≈ 52.
    let right = pixel(&fx.out, 52, 24);
    assert!(right[0] > 200, "the sphere moved right: {right:?}");

    // A shader saved by rename (new inode): still seen.
    save_by_rename(
        &fx.shader_path(),
        &fx.shader_scaled("vec3<f32>(0.0, 0.0, 1.0)"),
    );
    w.reload_until("the renamed shader", |r| {
        r.errors.is_empty() && r.changes.shaders
    });
    assert_eq!(pixel(&fx.out, 52, 24)[0], 0);

    // The scene saved by delete and re-create: still seen (one reload, or
    // an error for the missing file and then the recovery).
    std::fs::remove_file(&fx.scene).unwrap();
    std::fs::write(&fx.scene, watch_support::scene_json(-1.5, [0.8, 0.6, 0.2])).unwrap();
    w.reload_until("the re-created scene", |r| {
        r.errors.is_empty() && r.changes.scene
    });
    assert_eq!(pixel(&fx.out, 52, 24), [0, 0, 0]);
    let left = pixel(&fx.out, 12, 24);
    assert!(left[2] > 100, "the sphere moved left: {left:?}");

    // The same for a shader file, and then once more (the watch survives).
    for factor in ["vec3<f32>(1.0, 1.0, 0.0)", "vec3<f32>(1.0, 0.0, 0.0)"] {
        std::fs::remove_file(fx.shader_path()).unwrap();
        std::fs::write(fx.shader_path(), fx.shader_scaled(factor)).unwrap();
        w.reload_until("the re-created shader", |r| {
            r.errors.is_empty() && r.changes.shaders
        });
    }
    let left = pixel(&fx.out, 12, 24);
    assert!(left[0] > 200 && left[1] == 0 && left[2] == 0, "{left:?}");
}

#[test]
fn a_burst_of_saves_gives_one_reload() {
    let fx = Fixture::new();
    let mut w = Running::start(fx.options());
    for i in 1..=5 {
        let f = format!("vec3<f32>(0.0, {}.0 / 5.0, 1.0)", i);
        std::fs::write(fx.shader_path(), fx.shader_scaled(&f)).unwrap();
    }
    let r = w.next_reload();
    assert!(r.errors.is_empty(), "{:?}", r.errors);
    // Anything after that comes within the debounce window of the last save.
    let extra = w.next_reload_within(Duration::from_secs(3));
    assert!(
        extra.is_none() || w.next_reload_within(Duration::from_secs(3)).is_none(),
        "5 saves gave more than 2 reloads: {:#?}",
        w.reloads
    );
    // The image shows the last save.
    let c = fx.centre();
    assert_eq!(c[0], 0);
    let want = {
        let fresh = Fixture::new();
        std::fs::write(
            fresh.shader_path(),
            fresh.shader_scaled("vec3<f32>(0.0, 5.0 / 5.0, 1.0)"),
        )
        .unwrap();
        let _running = Running::start(fresh.options());
        fresh.centre()
    };
    assert_eq!(c, want);
}

#[test]
fn a_broken_scene_keeps_the_last_image_and_recovers() {
    let fx = Fixture::new();
    let mut w = Running::start(fx.options());
    let good = fx.output();

    // Not JSON.
    std::fs::write(&fx.scene, "{ \"camera\": ").unwrap();
    let r = w.reload_until("a scene error", |r| !r.errors.is_empty());
    assert!(r.errors[0].contains("scene.json"), "{:?}", r.errors);
    assert!(r.stages.is_empty());
    assert_eq!(fx.output(), good);

    // Valid JSON, impossible value: the field is named.
    std::fs::write(
        &fx.scene,
        scene_json(0.0, [0.8, 0.3, 0.2]).replace("\"radius\": 1", "\"radius\": -1"),
    )
    .unwrap();
    let r = w.reload_until("a radius error", |r| {
        r.errors.iter().any(|e| e.contains("radius"))
    });
    assert!(
        r.errors[0].contains("scene.json") && r.errors[0].contains("radius"),
        "{:?}",
        r.errors
    );
    assert_eq!(fx.output(), good);

    // More than the device can hold: an upload error, also survived.
    std::fs::write(
        &fx.scene,
        scene_json(0.0, [0.8, 0.3, 0.2])
            .replace("\"width\": 64", "\"width\": 16384")
            .replace("\"height\": 48", "\"height\": 16384"),
    )
    .unwrap();
    let r = w.reload_until("a device-limit error", |r| {
        r.errors.iter().any(|e| e.contains("camera.width"))
    });
    assert!(r.stages.is_empty());
    assert_eq!(fx.output(), good);

    // Fixed.
    std::fs::write(&fx.scene, scene_json(0.0, [0.2, 0.3, 0.8])).unwrap();
    let r = w.reload_until("recovery", |r| r.errors.is_empty());
    assert_eq!(r.stages.len(), 2);
    let c = fx.centre();
    assert!(c[2] > 200 && c[0] < 150, "{c:?}");
}

#[test]
fn a_newer_edit_cancels_the_refinement() {
    use penumbra::render::{Renderer, RendererOptions};
    use penumbra::watch::stage::{Changes, Session};
    let fx = Fixture::new();
    let renderer = Renderer::new(&RendererOptions {
        shaders: penumbra::render::ShaderSource::Directory(fx.shaders.clone()),
        ..Default::default()
    })
    .expect("GPU tests need a Vulkan device (tools/setup.sh installs lavapipe)");
    let mut s = Session::new(renderer, &fx.scene, Default::default());
    let applied = s.apply(Changes {
        shaders: true,
        scene: true,
    });
    assert!(applied.render && applied.errors.is_empty(), "{applied:?}");
    // The loop asks the watcher between stages; a pending edit stops it
    // after the preview.
    let mut written = Vec::new();
    let mut asked = 0;
    let cancelled = s
        .render_stages(
            &[4, 1],
            || {
                asked += 1;
                true
            },
            |f| written.push((f.image.width, f.image.height)),
        )
        .unwrap();
    assert!(cancelled);
    assert_eq!(asked, 1);
    assert_eq!(written, [(16, 12)]);
    // Nothing pending: both stages.
    written.clear();
    let cancelled = s
        .render_stages(
            &[4, 1],
            || false,
            |f| written.push((f.image.width, f.image.height)),
        )
        .unwrap();
    assert!(!cancelled);
    assert_eq!(written, [(16, 12), (64, 48)]);

    // With the preview process, the loop's full image is its only stage,
    // and a newer edit stops it between bands too (200 rows: 4 bands).
    let load = penumbra::loaders::LoadOptions {
        width: Some(64),
        height: Some(200),
        ..Default::default()
    };
    let renderer = Renderer::new(&RendererOptions {
        shaders: penumbra::render::ShaderSource::Directory(fx.shaders.clone()),
        ..Default::default()
    })
    .unwrap();
    let mut s = Session::new(renderer, &fx.scene, load);
    assert!(s
        .apply(Changes {
            shaders: true,
            scene: true
        })
        .errors
        .is_empty());
    let mut written = Vec::new();
    let mut asked = 0;
    let cancelled = s
        .render_stages_with(
            &[1],
            true,
            || {
                asked += 1;
                true
            },
            |f| written.push((f.image.width, f.image.height)),
        )
        .unwrap();
    assert!(
        cancelled && written.is_empty() && asked > 0,
        "{asked} {written:?}"
    );
    // Not cancellable: the only stage completes whatever is pending.
    let cancelled = s
        .render_stages_with(
            &[1],
            false,
            || true,
            |f| written.push((f.image.width, f.image.height)),
        )
        .unwrap();
    assert!(!cancelled);
    assert_eq!(written, [(64, 200)]);
}

#[test]
fn the_watcher_sees_edits_between_stages_and_debounces() {
    use penumbra::watch::files::{normalise, FileWatcher, WatchSet};
    use std::sync::atomic::AtomicBool;
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("a.wgsl");
    let other = dir.path().join("other.png");
    std::fs::write(&a, "1").unwrap();
    let set = WatchSet {
        scene: Default::default(),
        shaders: [normalise(&a)].into_iter().collect(),
    };
    let mut w = FileWatcher::new(set, Duration::from_millis(30)).unwrap();
    assert!(!w.pending());
    // Files beside ours, and reading ours, are not changes.
    std::fs::write(&other, "x").unwrap();
    let _ = std::fs::read(&a).unwrap();
    let end = std::time::Instant::now() + Duration::from_millis(300);
    while std::time::Instant::now() < end {
        assert!(!w.pending(), "an unrelated event counted as a change");
        std::thread::sleep(Duration::from_millis(10));
    }
    for i in 0..5 {
        std::fs::write(&a, format!("{i}")).unwrap();
    }
    let end = std::time::Instant::now() + TIMEOUT;
    while !w.pending() {
        assert!(std::time::Instant::now() < end, "no event for the edit");
        std::thread::sleep(Duration::from_millis(5));
    }
    let stop = AtomicBool::new(false);
    let b = w.next_batch(&stop).unwrap();
    assert_eq!(b.paths.into_iter().collect::<Vec<_>>(), [normalise(&a)]);
    assert!(!w.pending(), "five writes, one batch");
}

/// A save that closes the file (or renames a new file into place) ends its
/// batch without waiting for the debounce window; a file still open for
/// writing waits for the window.
#[test]
fn a_closed_save_does_not_wait_for_the_debounce_window() {
    use penumbra::watch::files::{normalise, FileWatcher, WatchSet};
    use std::io::Write as _;
    use std::sync::atomic::AtomicBool;
    use std::time::Instant;
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("a.wgsl");
    std::fs::write(&a, "1").unwrap();
    let set = WatchSet {
        scene: Default::default(),
        shaders: [normalise(&a)].into_iter().collect(),
    };
    let quiet = Duration::from_millis(1500);
    let mut w = FileWatcher::new(set, quiet).unwrap();
    let stop = AtomicBool::new(false);
    // Written and closed: the batch ends long before the window.
    let t = Instant::now();
    std::fs::write(&a, "2").unwrap();
    let b = w.next_batch(&stop).unwrap();
    assert_eq!(b.paths.into_iter().collect::<Vec<_>>(), [normalise(&a)]);
    assert!(
        t.elapsed() < quiet,
        "a closed save waited {:?}",
        t.elapsed()
    );
    // A new file renamed over ours: the same.
    let tmp = dir.path().join("a.wgsl.tmp");
    std::fs::write(&tmp, "3").unwrap();
    let t = Instant::now();
    std::fs::rename(&tmp, &a).unwrap();
    let b = w.next_batch(&stop).unwrap();
    assert_eq!(b.paths.into_iter().collect::<Vec<_>>(), [normalise(&a)]);
    assert!(t.elapsed() < quiet, "a rename waited {:?}", t.elapsed());
    // Written but still open: the batch waits for the window after the
    // last write.
    let mut f = std::fs::OpenOptions::new().append(true).open(&a).unwrap();
    f.write_all(b"4").unwrap();
    f.flush().unwrap();
    let t = Instant::now();
    let b = w.next_batch(&stop).unwrap();
    assert_eq!(b.paths.into_iter().collect::<Vec<_>>(), [normalise(&a)]);
    assert!(
        t.elapsed() >= quiet - Duration::from_millis(100),
        "an open file's batch ended after {:?}",
        t.elapsed()
    );
    drop(f);
}
