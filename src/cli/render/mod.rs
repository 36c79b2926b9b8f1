//! `penumbra render`: one scene to one image (this file), a part of a split
//! render (part.rs), a list of scenes (batch.rs), or the f64 CPU reference
//! (reference.rs); summary.rs writes the one summary line.

mod batch;
mod part;
mod reference;
mod summary;

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use penumbra::loaders::{self, Loaded};
use penumbra::output;
use penumbra::render::{
    Accel, KernelOptions, RenderError, Renderer, RendererOptions, Sampler, Sampling, ShaderSource,
    Traversal, TriangleTest,
};
use penumbra::terminal;
use penumbra::vector_width;
use penumbra::vulkan::DeviceSelector;

use super::calibrate;
use super::look::{DisplayArgs, LightingArgs};
use super::{parse_seconds, renderer_options, side_parser, spp_parser, LimitArgs, Seconds};

#[derive(clap::Args)]
pub struct RenderArgs {
    /// The scene file.
    #[arg(required_unless_present = "batch")]
    pub scene: Option<PathBuf>,
    /// Output image; the extension picks the format (.png or .exr); default
    /// out.png. With --batch, the folder the images go to.
    #[arg(short, long)]
    output: Option<PathBuf>,
    #[command(flatten)]
    lighting: LightingArgs,
    #[command(flatten)]
    display: DisplayArgs,
    /// Image width in pixels (overrides the scene's).
    #[arg(long, value_parser = side_parser())]
    width: Option<u32>,
    /// Image height in pixels (overrides the scene's).
    #[arg(long, value_parser = side_parser())]
    height: Option<u32>,
    /// A glTF file's camera: its index in `cameras`, its name, or `framing`
    /// for the framing view (docs/gltf.md).
    #[arg(long)]
    camera: Option<String>,
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
    /// How a SIMD group's lanes walk the BVH: `per-lane` (each its own
    /// ray's path) or `packet` (together, one node at a time; docs/stages.md
    /// measures it).
    #[arg(long, default_value = "per-lane")]
    traversal: Traversal,
    /// Ray/triangle test: `watertight` (Woop et al., u,v before t), or
    /// Möller–Trumbore `uv-first` (the seminar's) or `t-first`.
    #[arg(long, default_value = "watertight")]
    triangle_test: TriangleTest,
    /// Samples per pixel (one pass each): 1 goes through the pixel centre,
    /// more are stratified over the pixel (box filter).
    #[arg(long, default_value_t = 1, value_parser = spp_parser())]
    spp: u32,
    /// Light samples per pass for every area light (overrides the scene's `samples`).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=4096))]
    area_samples: Option<u32>,
    /// Seed of the sample pattern: the same seed gives the same image.
    #[arg(long, default_value_t = 0)]
    seed: u32,
    /// Stop after the pass in flight once this many seconds have passed, and
    /// write the mean of the passes done.
    #[arg(long, value_parser = parse_seconds, allow_hyphen_values = true)]
    time_budget: Option<Duration>,
    /// Sample placement: `stratified` (low-discrepancy) or `random`.
    #[arg(long, default_value = "stratified")]
    sampler: Sampler,
    /// Render with the f64 CPU reference instead of Vulkan (the ground truth
    /// for error figures; same image semantics and sample pattern, rows in
    /// parallel; --accel and --triangle-test do not apply).
    #[arg(long, conflicts_with_all = ["device", "shaders", "validate"])]
    reference: bool,
    /// Also write arbitrary output variables as channels of the .exr output:
    /// any of depth, normal, uv, id (comma-separated).
    #[arg(long)]
    aov: Option<output::AovSet>,
    /// lavapipe's SIMD width in bits: `auto` takes what `penumbra calibrate`
    /// measured fastest on this machine (a long render without calibration
    /// calibrates after it), else 256 on any CPU with AVX; LP_NATIVE_VECTOR_WIDTH in the
    /// environment takes precedence.
    #[arg(long, default_value = "auto", value_name = "auto|128|256|512")]
    vector_width: vector_width::Request,
    /// Render only tile I of N (bands of rows) into an OpenEXR part file
    /// for `penumbra merge`.
    #[arg(long, value_name = "I/N")]
    tile: Option<penumbra::farm::split::Tile>,
    /// Render only passes A..B (of --spp) into an OpenEXR part file holding
    /// their sum, for `penumbra merge`.
    #[arg(long, value_name = "A..B")]
    passes: Option<penumbra::farm::split::Passes>,
    /// Render every scene of a list file (one a line: SCENE [OUTPUT], relative
    /// to the list) into the folder -o, in one process; outputs already
    /// complete are skipped, so a rerun resumes.
    #[arg(long, value_name = "LIST", conflicts_with_all = ["scene", "tile", "passes", "reference", "aov"])]
    pub batch: Option<PathBuf>,
    /// With --batch: render only task I's share of K (every K-th scene from
    /// the I-th), for a job array.
    #[arg(long, value_name = "I/K", requires = "batch")]
    batch_task: Option<penumbra::farm::split::Tile>,
    /// Longest, in seconds, that one submission of work may run on the device
    /// (one pass over a band of the image): a watchdog for shader code that
    /// does not end. Past it, penumbra stops with an error naming the shader
    /// file, and writes nothing.
    #[arg(long, value_name = "SECONDS", allow_hyphen_values = true,
          default_value_t = Seconds(penumbra::vulkan::DEFAULT_TIME_LIMIT))]
    time_limit: Seconds,
    #[command(flatten)]
    limits: LimitArgs,
}

/// Every option structure of a render, assembled here from the arguments
/// and nowhere else.
impl RenderArgs {
    fn output(&self) -> PathBuf {
        self.output
            .clone()
            .unwrap_or_else(|| PathBuf::from("out.png"))
    }

    fn sampling(&self) -> Sampling {
        Sampling {
            spp: self.spp,
            seed: self.seed,
            time_budget: self.time_budget,
        }
    }

    fn kernel(&self) -> KernelOptions {
        KernelOptions {
            accel: self.accel,
            traversal: self.traversal,
            triangle_test: self.triangle_test,
            sampler: self.sampler,
            ..Default::default()
        }
    }

    fn shader_source(&self) -> ShaderSource {
        self.shaders
            .clone()
            .map(ShaderSource::Directory)
            .unwrap_or_default()
    }

    fn renderer_options(&self) -> RendererOptions {
        renderer_options(
            self.device.clone(),
            self.validate,
            self.shader_source(),
            self.kernel(),
            self.time_limit,
        )
    }

    /// What lavapipe's vector width is chosen for.
    fn job(&self) -> vector_width::Job {
        vector_width::Job::Render {
            pixels: self
                .width
                .zip(self.height)
                .map(|(w, h)| w as u64 * h as u64),
            passes: self.spp,
            time_budget: self.time_budget,
        }
    }

    /// Whether this render is a part of a split one (`--tile`, `--passes`).
    fn is_part(&self) -> bool {
        self.tile.is_some() || self.passes.is_some()
    }
}

pub fn run(args: RenderArgs) -> anyhow::Result<()> {
    let out = args.output();
    let scene = match (&args.scene, &args.batch) {
        (Some(s), _) => s.clone(),
        (None, Some(list)) => return batch::run(list, &out, &args),
        (None, None) => anyhow::bail!("render: a SCENE or --batch LIST is needed"),
    };
    if args.is_part() {
        part::check(&args, &out)?;
    }
    // Before the Vulkan driver loads (Renderer::new): lavapipe reads it then.
    // A long render with no calibration of this machine calibrates after it.
    let settings = match args.reference {
        true => None,
        false => Some(calibrate::settings(
            args.vector_width,
            args.job(),
            args.device.as_ref(),
            true,
        )?),
    };
    // Refuse an unwritable output before spending time on the render.
    let format = output::check_writable(&out)?;
    if args.aov.is_some() && format != output::Format::Exr {
        anyhow::bail!(
            "{}: --aov needs an .exr output (-o NAME.exr)",
            out.display()
        );
    }
    // The device first, so that the loader refuses a scene the device cannot
    // hold before expanding it.
    let mut renderer = match args.reference {
        true => None,
        false => Some(Renderer::new(&args.renderer_options())?),
    };
    if let (Some(s), Some(r)) = (&settings, &renderer) {
        s.check_driver(r.device());
    }
    let vector_width = settings.as_ref().map(|s| s.choice.clone());
    let (loaded, load) = load(&scene, &args, renderer.as_ref())?;
    match renderer.as_mut() {
        None => reference::run(&scene, &loaded, &args, &out, load),
        Some(r) if args.is_part() => part::run(r, &scene, &loaded, &args, &out, load),
        Some(r) => render_image(r, &scene, &loaded, &args, &out, load, vector_width),
    }?;
    // The device is closed before the calibration's probes open their own.
    drop(renderer);
    if let Some(s) = settings {
        s.calibrate_if_due();
    }
    Ok(())
}

/// Loads the scene within the device's limits and with the lighting flags,
/// prints the loader's notes and applies `--area-samples`.
fn load(
    scene: &Path,
    args: &RenderArgs,
    renderer: Option<&Renderer>,
) -> anyhow::Result<(Loaded, Duration)> {
    let mut options = args
        .limits
        .load_options(args.width, args.height, args.lighting);
    if let Some(c) = &args.camera {
        options.camera = loaders::gltf::CameraChoice::parse(c);
    }
    if let Some(r) = renderer {
        options.max_triangles = r.max_triangles();
        options.max_texture_bytes = r.texture_capacity();
    }
    let t0 = Instant::now();
    let mut loaded = loaders::load_scene(scene, &options)?;
    let load = t0.elapsed();
    for note in &loaded.notes {
        eprintln!("note: {}", terminal::diagnostic(note));
    }
    if let Some(n) = args.area_samples {
        for l in &mut loaded.scene.lights {
            l.kind.set_samples(n);
        }
    }
    Ok((loaded, load))
}

/// The whole image: upload, render with a progress bar, write, and print the
/// summary line.
fn render_image(
    renderer: &mut Renderer,
    scene: &Path,
    loaded: &Loaded,
    args: &RenderArgs,
    out: &Path,
    load: Duration,
    vector_width: Option<vector_width::Choice>,
) -> anyhow::Result<()> {
    let (frame, aovs) = summary::render_with_progress(
        renderer,
        &loaded.scene,
        &args.sampling(),
        args.aov.is_some(),
    )
    .map_err(|e| scene_error(e, scene, args))?;
    let t1 = Instant::now();
    match (args.aov, &aovs) {
        (Some(set), Some(a)) => output::write_exr_with_aovs(out, &frame.image, a, set)?,
        _ => write_shown(out, &frame.image, loaded, args)?,
    }
    let write = t1.elapsed();
    println!(
        "{}",
        summary::gpu_line(renderer, &loaded.scene, &frame, load, write, vector_width)
    );
    Ok(())
}

/// Writes `image` to `out` as its format shows it: a PNG exposed and
/// tone-mapped (`--exposure`, `--tonemap` or the scene's default), an EXR
/// linear.
fn write_shown(
    out: &Path,
    image: &penumbra::frame::Image,
    loaded: &Loaded,
    args: &RenderArgs,
) -> anyhow::Result<()> {
    let format = output::Format::from_path(out)?;
    let display = args.display.display();
    let shown = display.for_format(image, format, loaded.lit_by_default);
    Ok(output::write_image(out, &shown)?)
}

/// A device limit names a scene field: say which file, or which option where
/// the option set the field.
fn scene_error(e: RenderError, scene: &Path, args: &RenderArgs) -> anyhow::Error {
    match e {
        RenderError::Scene { field, message } => {
            let field = match (field.as_str(), args.width.is_some(), args.height.is_some()) {
                ("camera.width", true, _) => "--width".to_string(),
                ("camera.height", _, true) => "--height".to_string(),
                ("camera.width/camera.height", true, _)
                | ("camera.width/camera.height", _, true) => "--width/--height".to_string(),
                _ => field,
            };
            anyhow::anyhow!("{}: {field}: {message}", scene.display())
        }
        e => e.into(),
    }
}
