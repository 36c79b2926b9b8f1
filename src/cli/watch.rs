//! `penumbra watch`: render, then re-render on every change (hot reload).

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

use anyhow::Context as _;

use penumbra::render::{KernelOptions, ShaderSource};
use penumbra::vector_width;
use penumbra::vulkan::DeviceSelector;
use penumbra::watch::preview;

use super::look::{DisplayArgs, LightingArgs};
use super::{exit_leaving_the_device, renderer_options, side_parser, LimitArgs, Seconds};

#[derive(clap::Args)]
pub struct WatchArgs {
    /// The scene file.
    pub scene: PathBuf,
    /// Output image, rewritten atomically after every stage (.png or .exr).
    #[arg(short, long, default_value = "out.png")]
    output: PathBuf,
    /// The WGSL directory to watch (default: shaders/ of the source checkout
    /// if there is one, else the shaders built into the binary, unwatched).
    #[arg(long)]
    shaders: Option<PathBuf>,
    /// Serve a live preview page at ADDR (HOST:PORT or PORT; default
    /// 127.0.0.1:8737, loopback only unless you name another address).
    #[arg(long, value_name = "ADDR", num_args = 0..=1, default_missing_value = "127.0.0.1:8737", value_parser = penumbra::watch::server::parse_addr)]
    serve: Option<std::net::SocketAddr>,
    /// Image width in pixels (overrides the scene's).
    #[arg(long, value_parser = side_parser())]
    width: Option<u32>,
    /// Image height in pixels (overrides the scene's).
    #[arg(long, value_parser = side_parser())]
    height: Option<u32>,
    /// The preview renders at 1/N of the resolution before the full image (1: no preview).
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..=64))]
    preview: u32,
    /// Writes closer together than this many milliseconds give one reload (a save that
    /// closes the file or renames it into place reloads 3 ms after it instead).
    #[arg(long, default_value_t = 30)]
    debounce_ms: u64,
    /// Vulkan device: an index from `penumbra devices`, or part of its name.
    #[arg(long)]
    device: Option<DeviceSelector>,
    /// Enable the Khronos validation layer (errors are reported per reload).
    #[arg(long)]
    validate: bool,
    /// lavapipe's SIMD width in bits: `auto` takes this machine's calibration
    /// (`penumbra calibrate`; 256-bit settings only, for compile latency),
    /// else 256; LP_NATIVE_VECTOR_WIDTH in the environment takes precedence.
    #[arg(long, default_value = "auto", value_name = "auto|128|256|512")]
    vector_width: vector_width::Request,
    /// Longest, in seconds, that one submission of work may run on the device
    /// (a band of the image, 64 rows at the full size): a watchdog for shader
    /// code that does not end. Past it, watch reports the error naming the
    /// shader file, restarts itself (the device cannot stop the shader) and
    /// renders the next save.
    #[arg(long, value_name = "SECONDS", allow_hyphen_values = true,
          default_value_t = Seconds(penumbra::watch::DEFAULT_TIME_LIMIT))]
    time_limit: Seconds,
    /// Render the preview in a second process whose driver compiles quickly
    /// (lavapipe without LLVM's optimisation passes, at 128 bits): `auto` on a
    /// CPU device, where the compile is most of an edit's wait; `on` on any
    /// device; `off`: this process renders the preview.
    #[arg(long, value_enum, default_value_t = PreviewProcess::Auto)]
    preview_process: PreviewProcess,
    #[command(flatten)]
    limits: LimitArgs,
    #[command(flatten)]
    lighting: LightingArgs,
    #[command(flatten)]
    display: DisplayArgs,
}

/// `--preview-process`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
enum PreviewProcess {
    Auto,
    On,
    Off,
}

pub fn run(args: WatchArgs) -> anyhow::Result<()> {
    // Before the Vulkan driver loads: this machine's calibration if there is
    // one; watch never calibrates (an edit must not wait for it).
    let settings = super::calibrate::settings(
        args.vector_width,
        vector_width::Job::Watch,
        args.device.as_ref(),
        false,
    )?;
    if matches!(
        settings.choice.reason,
        vector_width::Reason::Calibrated { .. } | vector_width::Reason::CalibratedDefault
    ) {
        eprintln!("note: {}", settings.choice);
    }
    let shaders = match args.shaders {
        Some(dir) => ShaderSource::Directory(dir),
        None => match penumbra::render::compile::checkout_shader_dir() {
            Some(dir) => ShaderSource::Directory(dir),
            None => {
                eprintln!("note: no shader directory: using the built-in shaders (not watched)");
                ShaderSource::Embedded
            }
        },
    };
    let mut opts = penumbra::watch::WatchOptions::new(args.scene, args.output);
    opts.renderer = renderer_options(
        args.device,
        args.validate,
        shaders,
        KernelOptions::default(),
        args.time_limit,
    );
    opts.load = args
        .limits
        .load_options(args.width, args.height, args.lighting);
    opts.display = args.display.display();
    opts.serve = args.serve;
    opts.preview_divisor = args.preview;
    opts.debounce = Duration::from_millis(args.debounce_ms);
    opts.resume = penumbra::watch::restart::Resume::take_from_env();
    if preview::is_worker() {
        // The loop's preview process (src/watch/preview.rs): the same
        // options, no loop, no page; it ends when the loop closes its input.
        return preview::serve(&opts);
    }
    if args.preview_process != PreviewProcess::Off {
        opts.preview_process = Some(
            preview::WorkerCommand::this_process(args.preview_process == PreviewProcess::On)
                .context("finding this program for the preview process")?,
        );
    }
    let stop = Arc::new(AtomicBool::new(false));
    {
        let stop = stop.clone();
        ctrlc::set_handler(move || {
            stop.store(true, Ordering::Relaxed);
            // The loop sees `stop` between reloads; a render in flight (up to
            // --time-limit per submission, or one that never ends) would keep
            // it longer. Every output is written atomically: end the process
            // if it has not ended by itself well within a second.
            std::thread::sleep(WATCH_STOP_GRACE);
            exit_leaving_the_device(0);
        })
        .context("installing the Ctrl-C handler")?;
    }
    match penumbra::watch::run_printing(&opts, stop)? {
        None => Ok(()),
        Some(restart) => {
            let e = restart.exec();
            eprintln!("error: watch: cannot restart after the device hung: {e}");
            exit_leaving_the_device(1)
        }
    }
}

/// How long Ctrl-C lets `watch` end by itself before ending it.
const WATCH_STOP_GRACE: Duration = Duration::from_millis(300);
