//! Times the GPU-ready BVH build (`GpuScene::build_bvh`: tree and quantised
//! records) of the benchmark's 1,002,002-triangle scene, a fresh layout per
//! build, and prints the median and range together with the SAH cost of the
//! trees of that scene, the bunny and the bunny subdivided 3×; then the
//! two phases timed apart: the host tree, and the primitive references and
//! quantised records encoded from it.
//!
//!   cargo run --release -p penumbra-tools --bin build_time -- [BUILDS]
//!
//! To compare two commits, run it at each in turn a few times (the second
//! core of a small machine comes and goes: compare runs taken alternately).

use std::io::Write;
use std::time::Instant;

use common::meshes;
use common::ms;
use penumbra::render::layout::GpuScene;

fn main() -> anyhow::Result<()> {
    let builds: usize = match std::env::args().nth(1) {
        Some(a) => a
            .parse()
            .ok()
            .filter(|&n| n > 0)
            .ok_or_else(|| anyhow::anyhow!("BUILDS: expected a positive integer, got '{a}'"))?,
        None => 7,
    };
    let bunny = meshes::bunny_scene(&common::repo_root())?;
    let scene = meshes::sphere_scene(&bunny, 1_000_000);
    let mut build_ms: Vec<f64> = (0..builds)
        .map(|_| {
            let mut gpu = GpuScene::new(&scene);
            let start = Instant::now();
            gpu.build_bvh();
            ms(start.elapsed())
        })
        .collect();
    build_ms.sort_by(f64::total_cmp);
    let mut out = std::io::stdout().lock();
    writeln!(
        out,
        "{} triangles: build {:.1} ms median [{:.1}–{:.1}] of {builds}",
        scene.triangle_count(),
        build_ms[build_ms.len() / 2],
        build_ms[0],
        build_ms[build_ms.len() - 1]
    )?;
    // Phases of the build, timed apart on fresh layouts (medians).
    let mut tree_ms = Vec::new();
    let mut encode_ms = Vec::new();
    for _ in 0..builds {
        let mut gpu = GpuScene::new(&scene);
        let start = Instant::now();
        let built = gpu.build_chunked();
        tree_ms.push(ms(start.elapsed()));
        let start = Instant::now();
        gpu.encode_bvh(&built);
        encode_ms.push(ms(start.elapsed()));
    }
    tree_ms.sort_by(f64::total_cmp);
    encode_ms.sort_by(f64::total_cmp);
    writeln!(
        out,
        "phases (medians, timed apart): tree {:.1} ms, references and records {:.1} ms",
        tree_ms[builds / 2],
        encode_ms[builds / 2]
    )?;
    let sah = |s: &penumbra::scene::Scene| GpuScene::new(s).build_tree().sah_cost();
    writeln!(
        out,
        "SAH cost: this scene {:.4}, bunny {:.4}, bunny subdivided 3x {:.4}",
        sah(&scene),
        sah(&bunny),
        sah(&meshes::subdivided_bunny(&bunny, 3))
    )?;
    Ok(())
}
