//! How the parts measure: a renderer on the chosen device, uploads and frames
//! with a given kernel, warmed-up runs of frames, and two variants
//! interleaved A B A B … so that another process taking a core slows both
//! sides of a ratio alike.

use common::{ms, Stat};
use penumbra::render::{Accel, Frame, KernelOptions, Renderer, TriangleTest, UploadedScene};
use penumbra::scene::Scene;

use crate::schema::{Device, Pair};
use crate::Args;

/// A renderer on the device `--device` selects.
pub fn renderer(args: &Args) -> anyhow::Result<Renderer> {
    args.device.renderer()
}

/// The device as the renderer reports it, for the results.
pub fn device(r: &Renderer) -> Device {
    let d = r.device();
    Device {
        name: d.name.clone(),
        device_type: d.device_type.clone(),
        driver_name: d.driver_name.clone(),
        driver_info: d.driver_info.clone(),
        api_version: d.api_version.clone(),
    }
}

/// Pixels of `frame` whose primary ray hit something (alpha 1).
pub fn hits(frame: &Frame) -> usize {
    frame.image.pixels.iter().filter(|p| p[3] == 1.0).count()
}

/// The default kernel with `accel` and `triangle_test`.
pub fn kernel(accel: Accel, triangle_test: TriangleTest) -> KernelOptions {
    KernelOptions {
        accel,
        triangle_test,
        ..Default::default()
    }
}

/// Uploads `scene` with `k`'s acceleration structure.
pub fn upload(r: &mut Renderer, scene: &Scene, k: KernelOptions) -> anyhow::Result<UploadedScene> {
    r.set_kernel(k);
    Ok(r.upload(scene)?)
}

/// Renders `k` on `up` at `w`×`h`.
pub fn frame(
    r: &mut Renderer,
    up: &UploadedScene,
    k: KernelOptions,
    w: u32,
    h: u32,
) -> anyhow::Result<Frame> {
    r.set_kernel(k);
    Ok(r.render(up, penumbra::render::RenderRequest::new(w, h))
        .map(|r| r.frame)?)
}

/// `reps` frames, after a first frame (which compiles the kernel if needed)
/// and `warm` warm-up frames; returns the measured frames' render times and
/// the last frame.
pub fn frames(
    r: &mut Renderer,
    up: &UploadedScene,
    k: KernelOptions,
    (w, h): (u32, u32),
    warm: usize,
    reps: usize,
) -> anyhow::Result<(Vec<f64>, Frame)> {
    let mut last = frame(r, up, k, w, h)?;
    for _ in 0..warm {
        last = frame(r, up, k, w, h)?;
    }
    let mut t = Vec::new();
    for _ in 0..reps {
        last = frame(r, up, k, w, h)?;
        t.push(ms(last.stats.timings.render));
    }
    Ok((t, last))
}

/// Two variants interleaved A B A B ... after one warm-up frame of each.
#[allow(clippy::too_many_arguments)]
pub fn interleave(
    r: &mut Renderer,
    what: &str,
    a: (&str, &UploadedScene, KernelOptions),
    b: (&str, &UploadedScene, KernelOptions),
    (w, h): (u32, u32),
    reps: usize,
) -> anyhow::Result<Pair> {
    for (_, up, k) in [a, b] {
        frame(r, up, k, w, h)?;
        frame(r, up, k, w, h)?;
    }
    let (mut ta, mut tb, mut ratio) = (Vec::new(), Vec::new(), Vec::new());
    for i in 0..reps {
        eprintln!("  {what}: pair {}/{reps}", i + 1);
        let fa = ms(frame(r, a.1, a.2, w, h)?.stats.timings.render);
        let fb = ms(frame(r, b.1, b.2, w, h)?.stats.timings.render);
        ta.push(fa);
        tb.push(fb);
        ratio.push(fa / fb);
    }
    Ok(Pair {
        what: what.into(),
        a: a.0.into(),
        b: b.0.into(),
        width: w,
        height: h,
        a_ms: Stat::of(&ta),
        b_ms: Stat::of(&tb),
        ratio: Stat::of(&ratio),
    })
}
