//! The progress bar and the one summary line of `penumbra render`.

use std::time::Duration;

use penumbra::frame::{Image, RenderStats};
use penumbra::render::{Aovs, Frame, PassInfo, RenderError, RenderRequest, Renderer, Sampling};
use penumbra::scene::Scene;
use penumbra::vector_width;

use crate::cli::ms;

/// The one summary line of `penumbra render`, on the GPU or the CPU
/// reference: `WHO: WxH, N spp, R rays (P primary + S shadow) | PHASE TIME,
/// … | X Mrays/s`, then `note` (empty, or ` | …`).
pub fn line(
    who: &str,
    image: &Image,
    stats: &RenderStats,
    phases: &[(&str, Duration)],
    note: &str,
) -> String {
    let phases: Vec<String> = phases
        .iter()
        .map(|(name, d)| format!("{name} {}", ms(*d)))
        .collect();
    format!(
        "{who}: {}x{}, {} spp, {} rays ({} primary + {} shadow) | {} | {:.1} Mrays/s{note}",
        image.width,
        image.height,
        stats.passes,
        stats.rays(),
        stats.primary_rays,
        stats.shadow_rays,
        phases.join(", "),
        stats.mrays_per_second()
    )
}

/// Uploads and renders in passes, with a progress bar (passes and rays/s)
/// when there is more than one pass and stderr is a terminal.
pub fn render_with_progress(
    renderer: &mut Renderer,
    scene: &Scene,
    sampling: &Sampling,
    with_aovs: bool,
) -> Result<(Frame, Option<Aovs>), RenderError> {
    let uploaded = renderer.upload(scene)?;
    let bar = if sampling.spp > 1 {
        indicatif::ProgressBar::new(sampling.spp as u64)
    } else {
        indicatif::ProgressBar::hidden()
    };
    bar.set_style(
        indicatif::ProgressStyle::with_template("{bar:30} {pos}/{len} passes, {msg}, eta {eta}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let (w, h) = uploaded.size();
    let mut on_pass = |p: &PassInfo| {
        bar.set_position(p.done as u64);
        let rate = p.rays as f64 / p.elapsed.as_secs_f64().max(1e-9) / 1e6;
        bar.set_message(format!("{rate:.1} Mrays/s"));
    };
    let result = if with_aovs {
        renderer
            .render(
                &uploaded,
                RenderRequest::with_aovs(w, h, sampling, &mut on_pass),
            )
            .map(|r| (r.frame, r.aovs.unwrap_or_default()))
            .map(|(f, a)| (f, Some(a)))
    } else {
        renderer
            .render(
                &uploaded,
                RenderRequest::progressive(w, h, sampling, &mut on_pass),
            )
            .map(|r| r.frame)
            .map(|f| (f, None))
    };
    bar.finish_and_clear();
    let (mut frame, aovs) = result?;
    let (accel_build, upload) = uploaded.upload_timings();
    frame.stats.timings.accel_build = accel_build;
    frame.stats.timings.upload = upload;
    Ok((frame, aovs))
}

/// The summary line of a render on the device.
pub fn gpu_line(
    renderer: &Renderer,
    scene: &Scene,
    frame: &Frame,
    load: Duration,
    write: Duration,
    vector_width: Option<vector_width::Choice>,
) -> String {
    let s = &frame.stats;
    let t = &s.timings;
    let dev = renderer.device();
    // The width matters to CPU devices (lavapipe) only.
    let width_note = match vector_width {
        Some(c) if dev.device_type == "CPU" => format!(" | {c}"),
        _ => String::new(),
    };
    line(
        &format!("{} ({})", dev.name, dev.device_type),
        &frame.image,
        s,
        &[
            ("load", load),
            ("shader compile", t.shader_compile),
            ("pipeline creation", t.pipeline_creation),
            ("driver compile", t.driver_compile),
            ("BVH build", t.accel_build),
            ("upload", t.upload),
            ("GPU render", t.render),
            ("readback", t.readback),
            ("write", write),
        ],
        &format!(
            "{}{}{width_note}{}",
            driver_compiles_note(&frame.driver_compiles),
            triangles_note(scene),
            texture_note(s.texture_bytes)
        ),
    )
}

/// ` | driver compile: hit 120.3 ms, shade shading/phong.wgsl 80.1 ms`:
/// each pipeline the render built, with the driver's compile at its first
/// dispatch (issue 39: a textured scene's compile is a cost of its own);
/// empty when every pipeline came from the cache.
pub fn driver_compiles_note(compiles: &[(String, Duration)]) -> String {
    if compiles.is_empty() {
        return String::new();
    }
    let each: Vec<String> = compiles
        .iter()
        .map(|(name, d)| format!("{name} {}", ms(*d)))
        .collect();
    format!(" | driver compile: {}", each.join(", "))
}

/// ` | textures N MiB (mip-maps included)` for a scene with textures.
pub fn texture_note(bytes: u64) -> String {
    if bytes == 0 {
        return String::new();
    }
    format!(
        " | textures {:.2} MiB (mip-maps included)",
        bytes as f64 / 1048576.0
    )
}

/// ` | N triangles`: the scene's, glTF instances expanded (issue 39).
pub fn triangles_note(scene: &Scene) -> String {
    format!(" | {} triangles", scene.triangle_count())
}
