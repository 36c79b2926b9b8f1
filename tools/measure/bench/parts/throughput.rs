//! Section 1's part: the bunny scene (and, in the main throughput part, the
//! bunny subdivided) at its own camera and size: every phase of the first
//! frame in a fresh pipeline cache, then warmed-up frames and readbacks. The
//! knob runs and the profile run this part without the subdivided bunny.

use std::time::{Duration, Instant};

use common::{ms, Stat};
use penumbra::render::{KernelOptions, Renderer};
use penumbra::scene::Scene;

use crate::measure::{device, frame, frames, hits, renderer, upload};
use crate::schema::{Throughput, ThroughputPart};
use crate::Args;

/// Phases and frames of one scene at its own size, in a fresh pipeline cache.
fn throughput_of(
    r: &mut Renderer,
    name: &str,
    scene: &Scene,
    scene_build: Duration,
    reps: usize,
) -> anyhow::Result<Throughput> {
    eprintln!("  throughput: {name}");
    r.clear_pipeline_cache();
    let k = KernelOptions::default();
    let up = upload(r, scene, k)?;
    let (bvh_build, upload_t) = up.upload_timings();
    let (w, h) = up.size();
    let first = frame(r, &up, k, w, h)?;
    let t = first.stats.timings;
    let (render, last) = frames(r, &up, k, (w, h), 1, reps)?;
    let mut readback = Vec::new();
    for _ in 0..reps.min(3) {
        readback.push(ms(frame(r, &up, k, w, h)?.stats.timings.readback));
    }
    let rays = last.stats.rays() as f64;
    let render_ms = Stat::of(&render);
    Ok(Throughput {
        scene: name.into(),
        triangles: scene.triangle_count(),
        width: w,
        height: h,
        scene_build_ms: ms(scene_build),
        naga_ms: ms(t.shader_compile),
        pipeline_ms: ms(t.pipeline_creation),
        driver_compile_ms: ms(t.driver_compile),
        bvh_build_ms: ms(bvh_build),
        upload_ms: ms(upload_t),
        first_frame_ms: ms(t.render),
        bvh_nodes: last.stats.bvh_nodes,
        bvh_depth: last.stats.bvh_depth,
        bvh_bytes: last.stats.bvh_bytes,
        primary_rays: last.stats.primary_rays,
        shadow_rays: last.stats.shadow_rays,
        hits: hits(&last),
        mrays_median: rays / render_ms.median / 1e3,
        mrays_min: rays / render_ms.max / 1e3,
        mrays_max: rays / render_ms.min / 1e3,
        render_ms,
        readback_ms: Stat::of(&readback),
    })
}

/// The driver matrix's part (`crate::parts::drivers`): the bunny and the
/// showcase (`scenes/showcase.json`), each at its own size.
pub fn run_matrix(args: &Args) -> anyhow::Result<ThroughputPart> {
    let mut r = renderer(args)?;
    let root = common::repo_root();
    let bunny = common::meshes::bunny_scene(&root)?;
    let showcase = penumbra::loaders::load_scene(
        &root.join("scenes/showcase.json"),
        &penumbra::loaders::LoadOptions::default(),
    )?
    .scene;
    let reps = if args.quick { 3 } else { 5 };
    let scenes = vec![
        throughput_of(&mut r, "bunny_scene.glb", &bunny, Duration::ZERO, reps)?,
        throughput_of(&mut r, "showcase.json", &showcase, Duration::ZERO, reps)?,
    ];
    Ok(ThroughputPart {
        device: device(&r),
        env: Vec::new(),
        scenes,
    })
}

/// The part: the bunny, and with `big` the subdivided bunny too, with the
/// Mesa environment it ran under.
pub fn run(args: &Args, big: bool) -> anyhow::Result<ThroughputPart> {
    let mut r = renderer(args)?;
    let bunny = common::meshes::bunny_scene(&common::repo_root())?;
    let reps = if args.quick { 3 } else { 7 };
    let mut scenes = vec![throughput_of(
        &mut r,
        "bunny",
        &bunny,
        Duration::ZERO,
        reps,
    )?];
    if big {
        let levels = if args.quick { 1 } else { 3 };
        let t0 = Instant::now();
        let big = common::meshes::subdivided_bunny(&bunny, levels);
        let build = t0.elapsed();
        let name = format!("bunny subdivided {levels}×");
        scenes.push(throughput_of(&mut r, &name, &big, build, reps.min(5))?);
    }
    let env = [
        "MESA_SHADER_CACHE_DISABLE",
        "LP_NUM_THREADS",
        "LP_NATIVE_VECTOR_WIDTH",
    ]
    .iter()
    .filter_map(|k| std::env::var(k).ok().map(|v| (k.to_string(), v)))
    .collect();
    Ok(ThroughputPart {
        device: device(&r),
        env,
        scenes,
    })
}
