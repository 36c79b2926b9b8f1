//! Section 1 of the report: throughput and phases.

use std::fmt::Write as _;

use super::fmt::*;
use crate::schema::*;

/// Section 1: every phase and the frames of each throughput scene, one
/// column per scene.
pub fn section(o: &mut String, r: &Results) {
    let big = r.throughput.scenes.get(1);
    let _ = writeln!(o, "## 1. Throughput and phases\n");
    let _ = writeln!(
        o,
        "`scenes/bunny_scene.glb` at its own camera and size. Each scene is uploaded once (`Renderer::upload`) and rendered repeatedly (`Renderer::render`): the first frame compiles the kernel (naga, pipeline creation, lavapipe's compile at the first dispatch — measured with an empty warm-up dispatch, kept out of the frame), then one warm-up frame, then the measured frames. Rays are counted by the kernel (`RenderStats`); Mrays/s = (primary + shadow rays) / render phase.\n"
    );
    if let Some(b) = big {
        let _ = writeln!(
            o,
            "The larger mesh is the bunny subdivided {}: each triangle split into four at its edge midpoints, and each new vertex displaced by Phong tessellation (Boubekeur and Alexa 2008, shape factor ¾: the midpoint projected onto the tangent planes of both end vertices, averaged) — a smooth, watertight {}-triangle bunny in the same scene. Its frames: median of {}.\n",
            b.scene.trim_start_matches("bunny subdivided "),
            int(b.triangles as u64 - 2),
            b.render_ms.samples.len()
        );
    }
    let scenes = &r.throughput.scenes;
    let _ = write!(o, "| Phase |");
    for s in scenes {
        let _ = write!(o, " {} |", s.scene);
    }
    let _ = write!(o, "\n|---|");
    for _ in scenes {
        let _ = write!(o, "---|");
    }
    let _ = writeln!(o);
    type Row = (&'static str, fn(&Throughput) -> String);
    let rows: [Row; 17] = [
        ("Triangles (incl. the 2 of the ground)", |t| {
            int(t.triangles as u64)
        }),
        ("Image", |t| format!("{}×{}", t.width, t.height)),
        ("Primary rays / hits / shadow rays", |t| {
            format!(
                "{} / {} / {}",
                int(t.primary_rays),
                int(t.hits as u64),
                int(t.shadow_rays)
            )
        }),
        ("Mesh generation (host, not part of penumbra)", |t| {
            if t.scene_build_ms > 0.0 {
                format!("{:.1} ms", t.scene_build_ms)
            } else {
                "—".into()
            }
        }),
        ("BVH build (binned SAH, rayon)", |t| {
            format!("{:.1} ms", t.bvh_build_ms)
        }),
        ("Layout + upload", |t| format!("{:.1} ms", t.upload_ms)),
        (
            "BVH records (one per interior node) / depth / memory",
            |t| {
                format!(
                    "{} / {} / {}",
                    int(t.bvh_nodes as u64),
                    t.bvh_depth,
                    mib(t.bvh_bytes)
                )
            },
        ),
        ("naga: WGSL → SPIR-V", |t| format!("{:.1} ms", t.naga_ms)),
        ("vkCreateComputePipelines", |t| {
            format!("{:.1} ms", t.pipeline_ms)
        }),
        ("Driver compile at first dispatch (cold)", |t| {
            format!("{:.1} ms", t.driver_compile_ms)
        }),
        ("First frame", |t| format!("{:.1} ms", t.first_frame_ms)),
        ("**Render, ms/frame** median [min–max]", |t| {
            format!("**{}**", st(&t.render_ms))
        }),
        ("Frames measured", |t| t.render_ms.samples.len().to_string()),
        ("**Mrays/s** at median [slowest–fastest frame]", |t| {
            format!("**{}**", mrays(t))
        }),
        ("Readback (16 MiB image), median", |t| {
            format!("{:.1} ms", t.readback_ms.median)
        }),
        ("Time per ray", |t| {
            format!(
                "{:.0} ns",
                t.render_ms.median * 1e6 / (t.primary_rays + t.shadow_rays) as f64
            )
        }),
        ("Frames to amortise compile + build", |t| {
            format!(
                "{:.1}",
                (t.naga_ms + t.pipeline_ms + t.driver_compile_ms + t.bvh_build_ms)
                    / t.render_ms.median
            )
        }),
    ];
    for (name, f) in rows {
        let _ = write!(o, "| {name} |");
        for s in scenes {
            let _ = write!(o, " {} |", f(s));
        }
        let _ = writeln!(o);
    }
    let _ = writeln!(o);
    if let Some(c) = r.cli.as_ref().filter(|c| c.not_measured.is_none()) {
        let _ = writeln!(
            o,
            "**One-shot.** A user's `{}` is a process of its own: loading, device start-up, kernel compile, BVH build, one frame and the PNG. Timed from spawn to exit ({} runs each): {} ms with a warm Mesa shader cache (one `MESA_SHADER_CACHE_DIR` that an unmeasured run filled), {} ms cold (a fresh, empty one per run), against {} ms for the steady frame's render phase above.\n",
            c.command,
            c.warm_ms.samples.len(),
            st(&c.warm_ms),
            st(&c.cold_ms),
            st(&r.throughput.scenes[0].render_ms)
        );
    }
}
