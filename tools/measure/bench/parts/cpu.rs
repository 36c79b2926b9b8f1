//! The CPU port's part (section 6): the plain Rust port of penumbra's
//! algorithm (`crate::cpu`) against lavapipe on the bunny, frames
//! interleaved, the two images compared, and the traversal replayed for
//! the SIMD-8 utilisation model.

use std::time::Instant;

use common::{ms, Stat};
use penumbra::render::layout::GpuScene;
use penumbra::render::{Accel, TriangleTest};

use crate::measure::{frame, hits, kernel, renderer, upload};
use crate::schema::CpuPart;
use crate::Args;

/// The part: interleaved GPU and CPU frames of the same scene and kernel.
pub fn run(args: &Args) -> anyhow::Result<CpuPart> {
    let mut r = renderer(args)?;
    let bunny = common::meshes::bunny_scene(&common::repo_root())?;
    let mut gpu_scene = GpuScene::new(&bunny);
    gpu_scene.build_bvh();
    let cpu = crate::cpu::CpuScene::new(&gpu_scene, &bunny.shaders).map_err(anyhow::Error::msg)?;
    // The port implements the seminar's u,v-first Möller–Trumbore.
    let k = kernel(Accel::Bvh, TriangleTest::UvFirst);
    let up = upload(&mut r, &bunny, k)?;
    let (w, h) = up.size();
    let reps = if args.quick { 2 } else { 5 };
    // Warm-up of both (the GPU's first frame compiles the kernel).
    frame(&mut r, &up, k, w, h)?;
    frame(&mut r, &up, k, w, h)?;
    cpu.render(w, h);
    let (mut tg, mut tc, mut ratio) = (Vec::new(), Vec::new(), Vec::new());
    let mut last = None;
    for i in 0..reps {
        eprintln!("  cpu: pair {}/{reps}", i + 1);
        let g = frame(&mut r, &up, k, w, h)?;
        let t0 = Instant::now();
        let c = cpu.render(w, h);
        let c_ms = ms(t0.elapsed());
        let g_ms = ms(g.stats.timings.render);
        tg.push(g_ms);
        tc.push(c_ms);
        ratio.push(g_ms / c_ms);
        last = Some((g, c));
    }
    let (g, c) = last.expect("at least one pair");
    let mut max_abs_diff = 0f32;
    let mut over = 0;
    for (a, b) in g.image.pixels.iter().zip(&c.pixels) {
        let d = (0..4).map(|i| (a[i] - b[i]).abs()).fold(0f32, f32::max);
        max_abs_diff = max_abs_diff.max(d);
        over += (d > 1e-3) as usize;
    }
    let steps = cpu.traversal_steps(w, h);
    Ok(CpuPart {
        threads: rayon::current_num_threads(),
        width: w,
        height: h,
        cpu_ms: Stat::of(&tc),
        gpu_ms: Stat::of(&tg),
        ratio: Stat::of(&ratio),
        cpu_hits: c.pixels.iter().filter(|p| p[3] == 1.0).count(),
        gpu_hits: hits(&g),
        cpu_shadow_rays: c.shadow_rays,
        gpu_shadow_rays: g.stats.shadow_rays,
        max_abs_diff,
        pixels_over_1e3: over,
        simd8_utilisation: steps.utilisation,
        mean_steps: steps.mean,
    })
}
