//! How far honest work stays from the watchdog's time limits
//! (`--time-limit`): renders every scene in scenes/ as `penumbra render`
//! does (one submission per pass over a band of the image) and as `watch`
//! does (bands of rows, the quarter-resolution preview first), and prints,
//! per scene, the longest single submission, cold (the first render: the
//! driver compiles at a pipeline's first dispatch, which has its own limit)
//! and warm, beside the defaults. docs/watchdog.md holds its output.
//!
//! `cargo run -p penumbra-tools --bin watchdog_margin` (the host build does
//! not matter: the time is the device's)

use std::path::{Path, PathBuf};
use std::time::Duration;

use clap::Parser;
use penumbra::loaders::{self, LoadOptions};

#[derive(Parser)]
struct Args {
    /// The scenes (default: every .json and .glb in scenes/).
    scenes: Vec<PathBuf>,
    #[command(flatten)]
    device: common::device::DeviceArg,
    /// Renders per scene and mode; the longest submission of all is shown.
    #[arg(long, default_value_t = 3)]
    repeats: u32,
}

fn ms(d: Duration) -> String {
    format!("{:.0} ms", d.as_secs_f64() * 1e3)
}

fn default_scenes() -> anyhow::Result<Vec<PathBuf>> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
    let mut scenes: Vec<PathBuf> = std::fs::read_dir(&dir)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.extension()
                .is_some_and(|e| e == "json" || e == "glb" || e == "gltf")
        })
        .collect();
    scenes.sort();
    Ok(scenes)
}

fn main() -> anyhow::Result<()> {
    let args = Args::parse();
    let scenes = match args.scenes.is_empty() {
        true => default_scenes()?,
        false => args.scenes.clone(),
    };
    let cpu = common::machine::CpuInfo::read();
    println!("CPU: {}", cpu.describe());
    println!(
        "defaults: render --time-limit {} s, watch --time-limit {} s, a pipeline's first dispatch (driver compile) {} s",
        penumbra::vulkan::DEFAULT_TIME_LIMIT.as_secs_f64(),
        penumbra::watch::DEFAULT_TIME_LIMIT.as_secs_f64(),
        penumbra::vulkan::DRIVER_COMPILE_LIMIT.as_secs_f64()
    );
    println!();
    println!("| scene | size | first render (compile included) | render: longest submission | watch: longest submission | render limit / longest | watch limit / longest |");
    println!("|---|---|---|---|---|---|---|");
    for path in &scenes {
        // A fresh renderer per scene: its first render compiles.
        let mut renderer = args.device.renderer()?;
        let opts = LoadOptions {
            max_triangles: renderer.max_triangles(),
            ..LoadOptions::default()
        };
        let scene = loaders::load_scene(path, &opts)?.scene;
        let uploaded = renderer.upload(&scene)?;
        let (w, h) = uploaded.size();
        renderer.take_longest_wait();
        renderer
            .render(&uploaded, penumbra::render::RenderRequest::new(w, h))
            .map(|r| r.frame)?;
        let cold = renderer.take_longest_wait();
        let (mut render, mut watch) = (Duration::ZERO, Duration::ZERO);
        for _ in 0..args.repeats {
            renderer
                .render(&uploaded, penumbra::render::RenderRequest::new(w, h))
                .map(|r| r.frame)?;
            render = render.max(renderer.take_longest_wait());
            for (pw, ph) in [((w / 4).max(1), (h / 4).max(1)), (w, h)] {
                renderer.render(
                    &uploaded,
                    penumbra::render::RenderRequest::cancellable(pw, ph, &mut || false),
                )?;
            }
            watch = watch.max(renderer.take_longest_wait());
        }
        let name = path.file_name().unwrap_or_default().to_string_lossy();
        let ratio = |limit: Duration, d: Duration| limit.as_secs_f64() / d.as_secs_f64().max(1e-9);
        println!(
            "| {name} | {w}×{h} | {} | {} | {} | {:.0}× | {:.0}× |",
            ms(cold),
            ms(render),
            ms(watch),
            ratio(penumbra::vulkan::DEFAULT_TIME_LIMIT, render),
            ratio(penumbra::watch::DEFAULT_TIME_LIMIT, watch),
        );
    }
    Ok(())
}
