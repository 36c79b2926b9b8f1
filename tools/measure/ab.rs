//! A/B timing of two shader trees on one scene: is my edit faster?
//!
//! `cargo run --release -p penumbra-tools --bin ab -- SCENE --b my_shaders/` renders the
//! scene with the built-in shaders (A, or `--a DIR`) and with `DIR` (B, or
//! the built-in ones too without `--b`, to compare settings such as
//! `--b-traversal packet`),
//! interleaved A B A B … after a warm-up frame of each, and prints both
//! medians and the median of the per-pair ratios B/A with its range. Pairs,
//! not two separate runs, because a 2-core machine's second core comes and
//! goes for minutes at a time (see docs/bench.md).

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context as _;
use clap::Parser;

use common::device::DeviceArg;
use common::load::worker_cpu_ns;
use common::ms;
use common::stats::median_min_max;
use penumbra::loaders::{self, LoadOptions};
use penumbra::render::{KernelOptions, Renderer, RendererOptions, ShaderSource, Traversal};

#[derive(Parser)]
#[command(name = "ab", about = "Interleaved A/B frame times of two shader trees")]
struct Args {
    /// The scene (.json, .gltf or .glb).
    scene: PathBuf,
    /// Shader tree A (default: the shaders built into the binary).
    #[arg(long)]
    a: Option<PathBuf>,
    /// Shader tree B (default: the shaders built into the binary).
    #[arg(long)]
    b: Option<PathBuf>,
    /// Subdivide the scene's first mesh this many times first, each
    /// triangle into four (3 makes the bunny's 3,676 triangles the
    /// benchmark's 235k-triangle bunny: common::meshes::subdivided_bunny).
    #[arg(long, default_value_t = 0)]
    subdivide: u32,
    /// Side A's BVH traversal: `per-lane` or `packet` (`KernelOptions::traversal`).
    #[arg(long, default_value = "per-lane")]
    a_traversal: Traversal,
    /// Side B's BVH traversal.
    #[arg(long, default_value = "per-lane")]
    b_traversal: Traversal,
    /// Measured pairs.
    #[arg(long, default_value_t = 7)]
    pairs: usize,
    #[command(flatten)]
    device: DeviceArg,
    /// Compare the CPU time the driver's threads spend per frame (every
    /// thread but the main one, from /proc/self/task/*/schedstat) instead of
    /// wall time: time-sharing the cores with other processes inflates wall
    /// time, not this. For lavapipe on Linux only.
    #[arg(long)]
    cpu_time: bool,
    /// Stage memory bound of side A in KiB (`Renderer::set_stage_memory`;
    /// default: the renderer's), to compare tile sizes with one shader tree.
    #[arg(long)]
    a_stage_kib: Option<u64>,
    /// Stage memory bound of side B in KiB.
    #[arg(long)]
    b_stage_kib: Option<u64>,
    /// Side A runs the shadow stage even where the hit stage could trace
    /// the shadow rays (`Renderer::set_fused_shadows(false)`).
    #[arg(long)]
    a_unfused: bool,
    /// Side B runs the shadow stage even where the hit stage could trace them.
    #[arg(long)]
    b_unfused: bool,
    /// Side A's stages write their records with texel stores even where
    /// they could write words (`Renderer::set_stage_words(false)`).
    #[arg(long)]
    a_texel_stores: bool,
    /// Side B's stages write their records with texel stores.
    #[arg(long)]
    b_texel_stores: bool,
}

fn main() -> anyhow::Result<()> {
    let args = Args::parse();
    anyhow::ensure!(args.pairs > 0, "--pairs: must be at least 1");
    let device = args.device.selector()?;
    let mut scene = loaders::load_scene(&args.scene, &LoadOptions::default())?.scene;
    if args.subdivide > 0 {
        scene = common::meshes::subdivided_bunny(&scene, args.subdivide);
    }
    let source = |d: &Option<PathBuf>| match d {
        Some(p) => ShaderSource::Directory(p.clone()),
        None => ShaderSource::Embedded,
    };
    let mut sides = Vec::new();
    let a = (args.a_unfused, args.a_texel_stores, args.a_traversal);
    let b = (args.b_unfused, args.b_texel_stores, args.b_traversal);
    let sides_in = [
        ("A", source(&args.a), args.a_stage_kib, a),
        ("B", source(&args.b), args.b_stage_kib, b),
    ];
    for (name, dir, stage_kib, (unfused, texel_stores, traversal)) in sides_in {
        let mut r = Renderer::new(&RendererOptions {
            device: device.clone(),
            shaders: dir,
            kernel: KernelOptions {
                traversal,
                ..Default::default()
            },
            ..Default::default()
        })?;
        if let Some(kib) = stage_kib {
            r.set_stage_memory(kib.saturating_mul(1024));
        }
        r.set_fused_shadows(!unfused);
        r.set_stage_words(!texel_stores);
        let up = r.upload(&scene)?;
        let (w, h) = up.size();
        let t0 = Instant::now();
        // Compile (first frame), then one warm-up frame.
        r.render(&up, penumbra::render::RenderRequest::new(w, h))
            .map(|r| r.frame)
            .with_context(|| format!("shader tree {name}"))?;
        let warm = r
            .render(&up, penumbra::render::RenderRequest::new(w, h))
            .map(|r| r.frame)?;
        eprintln!(
            "{name}: compiled and warmed up in {:.0} ms; {} tiles of {:.2} MiB stage memory",
            ms(t0.elapsed()),
            warm.stats.tiles,
            warm.stats.stage_bytes as f64 / 1048576.0
        );
        sides.push((r, up));
    }
    let (mut ta, mut tb, mut ratio) = (Vec::new(), Vec::new(), Vec::new());
    let mut rays = [0u64; 2];
    for _ in 0..args.pairs {
        let mut t = [0.0; 2];
        for (i, (r, up)) in sides.iter_mut().enumerate() {
            let (w, h) = up.size();
            let cpu0 = if args.cpu_time { worker_cpu_ns()? } else { 0 };
            let f = r
                .render(up, penumbra::render::RenderRequest::new(w, h))
                .map(|r| r.frame)?;
            t[i] = if args.cpu_time {
                (worker_cpu_ns()? - cpu0) as f64 / 1e6
            } else {
                ms(f.stats.timings.render)
            };
            rays[i] = f.stats.rays();
        }
        ta.push(t[0]);
        tb.push(t[1]);
        ratio.push(t[1] / t[0]);
    }
    for (name, v, n) in [("A", &ta, rays[0]), ("B", &tb, rays[1])] {
        let (m, lo, hi) = median_min_max(v);
        if args.cpu_time {
            println!("{name}: {m:.1} [{lo:.1}–{hi:.1}] ms of worker CPU time per frame");
        } else {
            println!(
                "{name}: {m:.1} [{lo:.1}–{hi:.1}] ms/frame, {:.1} Mrays/s",
                n as f64 / m / 1e3
            );
        }
    }
    let (m, lo, hi) = median_min_max(&ratio);
    println!("B/A: {m:.3} [{lo:.3}–{hi:.3}] over {} pairs", args.pairs);
    if rays[0] != rays[1] {
        println!(
            "note: the trees traced different ray counts ({} vs {})",
            rays[0], rays[1]
        );
    }
    Ok(())
}
