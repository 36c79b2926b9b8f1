//! Where a staged frame's time goes: renders a scene with every pipeline
//! submitted and timed on its own (`Renderer::set_profile_stages`), several
//! frames, and prints each pipeline's median with the machine it ran on.
//!
//! ```sh
//! cargo run --release -p penumbra-tools --bin stage_times -- scenes/bunny_scene.glb [FRAMES] [WxH]
//! ```
//!
//! With `WxH` the scene renders at that size (its field of view kept):
//! the tile count and stage memory then show how the memory bound tiles
//! large images.

use std::time::Duration;

use common::ms;
use common::stats::upper_median;
use penumbra::loaders::{self, LoadOptions};
use penumbra::render::tiles::{TilePlan, DEFAULT_STAGE_MEMORY};
use penumbra::render::{Renderer, RendererOptions};

fn main() -> anyhow::Result<()> {
    let mut args = std::env::args().skip(1);
    let path = args
        .next()
        .unwrap_or_else(|| "scenes/bunny_scene.glb".to_string());
    let frames: usize = match args.next() {
        Some(n) => n.parse()?,
        None => 7,
    };
    let mut load = LoadOptions::default();
    if let Some(size) = args.next() {
        let (w, h) = size
            .split_once('x')
            .ok_or_else(|| anyhow::anyhow!("size: expected WxH, got {size}"))?;
        load.width = Some(w.parse()?);
        load.height = Some(h.parse()?);
    }
    let scene = loaders::load_scene(std::path::Path::new(&path), &load)?.scene;
    // The stage memory of the scene's light samples at 1024² and 4096²:
    // untiled, and tiled within the default bound.
    let samples: u32 = scene
        .lights
        .iter()
        .map(|l| l.kind.samples().unwrap_or(1))
        .sum();
    let mib = |b: u64| b as f64 / 1048576.0;
    let checker = scene.features().checker;
    for side in [1024u32, 4096] {
        let untiled = TilePlan::new([side, side], samples, checker, u64::MAX / 2, u64::MAX / 2);
        let plan = TilePlan::new(
            [side, side],
            samples,
            checker,
            DEFAULT_STAGE_MEMORY,
            128 << 20,
        );
        println!(
            "{side}x{side}, {samples} light samples per pixel: {:.0} MiB of hit records and queue untiled; {} tiles of {:.1} MiB within the {:.0} MiB bound ({} sample chunks)",
            mib(untiled.bytes()),
            plan.tiles(side, 0..side).len(),
            mib(plan.bytes()),
            mib(DEFAULT_STAGE_MEMORY),
            plan.chunks().len()
        );
    }
    let mut r = Renderer::new(&RendererOptions::default())?;
    r.set_profile_stages(true);
    let up = r.upload(&scene)?;
    let (w, h) = up.size();
    // The first frame compiles the pipelines.
    let first = r
        .render(&up, penumbra::render::RenderRequest::new(w, h))
        .map(|r| r.frame)?;
    let mut times: Vec<Vec<Duration>> = vec![Vec::new(); first.stage_times.len()];
    let mut totals = Vec::new();
    for _ in 0..frames {
        let f = r
            .render(&up, penumbra::render::RenderRequest::new(w, h))
            .map(|r| r.frame)?;
        for (i, (_, t)) in f.stage_times.iter().enumerate() {
            times[i].push(*t);
        }
        totals.push(f.stats.timings.render);
    }
    let median = |v: &[Duration]| upper_median(v).expect("at least one frame");
    println!(
        "{path} at {w}x{h}, {} tiles of {:.1} MiB stage memory, {frames} frames",
        first.stats.tiles,
        first.stats.stage_bytes as f64 / 1048576.0
    );
    println!(
        "machine: {}; device: {}",
        common::machine::CpuInfo::read().describe(),
        r.device().name
    );
    for (i, (name, _)) in first.stage_times.iter().enumerate() {
        println!("  {name:<40} {:>8.1} ms", ms(median(&times[i])));
    }
    println!(
        "  {:<40} {:>8.1} ms (median of the frames' render phase)",
        "all",
        ms(median(&totals))
    );
    Ok(())
}
