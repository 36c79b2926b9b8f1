//! The `penumbra` command line: one module per command, each with its
//! arguments and its `run`. What several commands share is here: the
//! loader's limits, durations in seconds, the options of a renderer, and the
//! exit that leaves a hung device alone.

mod calibrate;
mod devices;
mod diff;
mod farm;
mod look;
mod merge;
mod render;
mod watch;

use std::path::PathBuf;
use std::time::Duration;

use clap::{Parser, Subcommand};

use penumbra::loaders::{self, LoadOptions};
use penumbra::render::{KernelOptions, RendererOptions, ShaderSource};
use penumbra::vulkan::DeviceSelector;

#[derive(Parser)]
#[command(
    name = "penumbra",
    version,
    about = "Headless ray tracer in Vulkan compute kernels (lavapipe or any Vulkan GPU)"
)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene (.json, .gltf or .glb) to a PNG (sRGB, 8 bit) or OpenEXR (linear float) file.
    Render(render::RenderArgs),
    /// Time lavapipe's settings (vector width, AVX2 or AVX-512 code) on this
    /// machine and remember the fastest for later renders (docs/drivers.md).
    Calibrate(calibrate::CalibrateArgs),
    /// List the Vulkan devices with their type and driver version.
    Devices,
    /// Render a scene, then re-render whenever it, a file it references or a
    /// shader changes (hot reload), until Ctrl-C.
    Watch(watch::WatchArgs),
    /// Compare two renders (.png or .exr of the same size): print error metrics
    /// (`name: value`, one a line) and optionally write a FLIP false-colour map.
    Diff(diff::DiffArgs),
    /// Merge the part files of a split render (`render --tile`/`--passes`)
    /// into one image, after checking that they make up exactly one render.
    Merge(merge::MergeArgs),
    /// Render on a batch engine: write (and optionally submit) the job.
    #[command(subcommand)]
    Farm(farm::FarmCommand),
}

impl Cli {
    /// The file a panic's `error:` line names: the command's main input
    /// (or output, where it has no single input).
    pub fn subject(&self) -> Option<PathBuf> {
        match &self.command {
            Command::Render(a) => a.scene.clone().or(a.batch.clone()),
            Command::Watch(a) => Some(a.scene.clone()),
            Command::Diff(a) => Some(a.b.clone()),
            Command::Merge(a) => Some(a.output.clone()),
            Command::Farm(f) => Some(f.output()),
            Command::Devices | Command::Calibrate(_) => None,
        }
    }

    /// Runs the command.
    pub fn run(self) -> anyhow::Result<()> {
        match self.command {
            Command::Render(args) => render::run(args),
            Command::Devices => devices::run(),
            Command::Calibrate(args) => calibrate::run(args),
            Command::Watch(args) => watch::run(args),
            Command::Diff(args) => diff::run(args),
            Command::Merge(args) => merge::run(args),
            Command::Farm(args) => farm::run(args),
        }
    }
}

/// What a scene may make the loader read and hold (src/loaders/guard.rs).
#[derive(clap::Args, Clone, Copy)]
struct LimitArgs {
    /// Refuse every file the scene references outside the scene file's folder
    /// (after resolving `..` and symbolic links): for untrusted scenes.
    #[arg(long)]
    restrict_paths: bool,
    /// Most memory, in MiB, that the scene's files, its loaded geometry and its
    /// textures (decoded and uploaded) may take; checked before anything is
    /// expanded or decoded.
    #[arg(long, value_name = "MIB", default_value_t = loaders::guard::DEFAULT_MAX_SCENE_BYTES >> 20,
          value_parser = clap::value_parser!(u64).range(1..=1 << 30))]
    max_scene_memory: u64,
    /// The shader of glTF materials: glTF's own `metallic-roughness` model, or
    /// `phong`, the seminar's diffuse mapping of the base colour (renders made
    /// before issue 38; docs/materials.md).
    #[arg(long, value_name = "MODEL", default_value = "metallic-roughness",
          value_parser = |s: &str| s.parse::<loaders::GltfMaterials>())]
    gltf_materials: loaders::GltfMaterials,
}

impl LimitArgs {
    /// Load options with these limits, the size overrides and the lighting flags.
    fn load_options(
        self,
        width: Option<u32>,
        height: Option<u32>,
        lighting: look::LightingArgs,
    ) -> LoadOptions {
        LoadOptions {
            width,
            height,
            lighting: lighting.lighting(),
            restrict_paths: self.restrict_paths,
            max_scene_bytes: self.max_scene_memory << 20,
            gltf_materials: self.gltf_materials,
            ..Default::default()
        }
    }
}

/// The options of a renderer, put together in one place for every command
/// that opens one (render, render --batch, watch).
fn renderer_options(
    device: Option<DeviceSelector>,
    validation: bool,
    shaders: ShaderSource,
    kernel: KernelOptions,
    time_limit: Seconds,
) -> RendererOptions {
    RendererOptions {
        device,
        validation,
        shaders,
        kernel,
        time_limit: Some(time_limit.0),
    }
}

/// The samples-per-pixel range of every command, checked here at the edge
/// (the library checks its own callers against the same bound).
fn spp_parser() -> clap::builder::RangedI64ValueParser<u32> {
    clap::value_parser!(u32).range(1..=penumbra::frame::MAX_SPP as i64)
}

/// The range of `--width` and `--height`.
fn side_parser() -> clap::builder::RangedI64ValueParser<u32> {
    clap::value_parser!(u32).range(1..=16384)
}

/// A duration given in seconds on the command line (shown so in `--help`).
#[derive(Clone, Copy, Debug)]
struct Seconds(Duration);

impl std::fmt::Display for Seconds {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.0.as_secs_f64())
    }
}

impl std::str::FromStr for Seconds {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        parse_seconds(s).map(Seconds)
    }
}

fn parse_seconds(s: &str) -> Result<Duration, String> {
    let v: f64 = s
        .parse()
        .map_err(|_| format!("expected a number of seconds, got `{s}`"))?;
    if !(v > 0.0 && v <= 1e6) {
        return Err(format!("must be in (0, 1000000] seconds, got {s}"));
    }
    Ok(Duration::from_secs_f64(v))
}

fn ms(d: Duration) -> String {
    format!("{:.1} ms", d.as_secs_f64() * 1e3)
}

/// Ends the process at once with `code`, without running exit handlers: after
/// a time-out the device still runs the dispatch that never ends, and the
/// driver's exit handlers (Mesa's thread pools) would wait for it for ever.
/// Every output is written atomically, so nothing partial is left.
pub fn exit_leaving_the_device(code: i32) -> ! {
    use std::io::Write as _;
    let _ = std::io::stdout().flush();
    let _ = std::io::stderr().flush();
    // SAFETY: _exit ends the process; it touches no Rust state.
    unsafe { libc::_exit(code) }
}
