//! The `penumbra` command line: render a scene, list Vulkan devices.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use anyhow::Context as _;
use clap::{Parser, Subcommand};

use penumbra::loaders::{self, LoadOptions};
use penumbra::output;
use penumbra::render::{
    Accel, KernelOptions, RenderError, Renderer, RendererOptions, ShaderSource, TriangleTest,
};
use penumbra::vulkan::{Context, DeviceSelector};

#[derive(Parser)]
#[command(
    name = "penumbra",
    version,
    about = "Headless ray tracer in Vulkan compute shaders (lavapipe or any Vulkan GPU)"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene (.json, .gltf or .glb) to a PNG (sRGB, 8 bit) or OpenEXR (linear float) file.
    Render(RenderArgs),
    /// List the Vulkan devices with their type and driver version.
    Devices,
}

#[derive(clap::Args)]
struct RenderArgs {
    /// The scene file.
    scene: PathBuf,
    /// Output image; the extension picks the format (.png or .exr).
    #[arg(short, long, default_value = "out.png")]
    output: PathBuf,
    /// Image width in pixels (overrides the scene's).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=16384))]
    width: Option<u32>,
    /// Image height in pixels (overrides the scene's).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=16384))]
    height: Option<u32>,
    /// Vulkan device: an index from `penumbra devices`, or part of its name.
    #[arg(long)]
    device: Option<DeviceSelector>,
    /// Read the WGSL from this directory instead of the copy built into the binary.
    #[arg(long)]
    shaders: Option<PathBuf>,
    /// Enable the Khronos validation layer and fail on any error it reports.
    #[arg(long)]
    validate: bool,
    /// How rays find spheres and triangles: `bvh` or `brute-force`.
    #[arg(long, default_value = "bvh")]
    accel: Accel,
    /// Ray/triangle test order: `uv-first` (the seminar's) or `t-first`.
    #[arg(long, default_value = "uv-first")]
    triangle_test: TriangleTest,
}

fn ms(d: std::time::Duration) -> String {
    format!("{:.1} ms", d.as_secs_f64() * 1e3)
}

fn render(args: RenderArgs) -> anyhow::Result<()> {
    let RenderArgs {
        scene,
        output: out,
        width,
        height,
        device,
        shaders,
        validate,
        accel,
        triangle_test,
    } = args;
    // Refuse an unwritable output before spending time on the render.
    output::check_writable(&out)?;
    let t0 = Instant::now();
    let loaded = loaders::load_scene(&scene, &LoadOptions { width, height })?;
    let load = t0.elapsed();
    for note in &loaded.notes {
        eprintln!("note: {note}");
    }
    let shaders = shaders.map(ShaderSource::Directory).unwrap_or_default();
    let kernel = KernelOptions {
        accel,
        triangle_test,
        ..Default::default()
    };
    let mut renderer = Renderer::new(&RendererOptions {
        device,
        validation: validate,
        shaders,
        kernel,
    })?;
    let frame = renderer.render(&loaded.scene).map_err(|e| match e {
        // Device limits name a scene field: say which file.
        RenderError::Scene { field, message } => {
            let field = match (field.as_str(), width.is_some(), height.is_some()) {
                ("camera.width", true, _) => "--width".to_string(),
                ("camera.height", _, true) => "--height".to_string(),
                ("camera.width/camera.height", true, _)
                | ("camera.width/camera.height", _, true) => "--width/--height".to_string(),
                _ => field,
            };
            anyhow::anyhow!("{}: {field}: {message}", scene.display())
        }
        e => e.into(),
    })?;
    let t1 = Instant::now();
    output::write_image(&out, &frame.image)?;
    let write = t1.elapsed();
    let s = &frame.stats;
    let t = &s.timings;
    let dev = renderer.device();
    println!(
        "{} ({}): {}x{}, {} rays ({} primary + {} shadow) | load {}, shader compile {}, pipeline creation {}, driver compile {}, BVH build {}, upload {}, GPU render {}, readback {}, write {} | {:.1} Mrays/s",
        dev.name,
        dev.device_type,
        frame.image.width,
        frame.image.height,
        s.rays(),
        s.primary_rays,
        s.shadow_rays,
        ms(load),
        ms(t.shader_compile),
        ms(t.pipeline_creation),
        ms(t.driver_compile),
        ms(t.accel_build),
        ms(t.upload),
        ms(t.render),
        ms(t.readback),
        ms(write),
        s.mrays_per_second()
    );
    Ok(())
}

fn devices() -> anyhow::Result<()> {
    let list = Context::list_devices().context("listing Vulkan devices")?;
    for d in list {
        println!(
            "{}: {} ({}), Vulkan {}, driver {} {}",
            d.index, d.name, d.device_type, d.api_version, d.driver_name, d.driver_info
        );
    }
    Ok(())
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Render(args) => render(args),
        Command::Devices => devices(),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
