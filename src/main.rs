//! The `penumbra` command line: render a scene, list Vulkan devices.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use anyhow::Context as _;
use clap::{Parser, Subcommand};

use penumbra::loaders::{self, LoadOptions};
use penumbra::output;
use penumbra::render::{
    Accel, KernelOptions, RenderError, Renderer, RendererOptions, Sampler, Sampling, ShaderSource,
    TriangleTest,
};
use penumbra::terminal;
use penumbra::vector_width;
use penumbra::vulkan::{Context, DeviceSelector};

#[derive(Parser)]
#[command(
    name = "penumbra",
    version,
    about = "Headless ray tracer in Vulkan compute kernels (lavapipe or any Vulkan GPU)"
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
    /// Render a scene, then re-render whenever it, a file it references or a
    /// shader changes (hot reload), until Ctrl-C.
    Watch(WatchArgs),
    /// Compare two renders (.png or .exr of the same size): print error metrics
    /// (`name: value`, one a line) and optionally write a FLIP false-colour map.
    Diff(DiffArgs),
    /// Merge the part files of a split render (`render --tile`/`--passes`)
    /// into one image, after checking that they make up exactly one render.
    Merge(MergeArgs),
    /// Render on a batch engine: write (and optionally submit) the job.
    #[command(subcommand)]
    Farm(FarmCommand),
}

#[derive(Subcommand)]
enum FarmCommand {
    /// Write an sbatch script (OUT.farm/job.sh): a job array with one task per
    /// part and a merge job after it; --submit submits it, waits and reports.
    Slurm(SlurmArgs),
}

#[derive(clap::Args)]
struct SlurmArgs {
    /// The scene file (not with --batch).
    #[arg(required_unless_present = "batch")]
    scene: Option<String>,
    /// The merged image (.png or .exr); with --batch, the output folder.
    #[arg(short, long)]
    output: String,
    /// Split the image into N row bands, one task each.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=65536))]
    tiles: Option<u32>,
    /// Split the --spp passes into M ranges, one task each (times --tiles).
    #[arg(long, value_name = "M", value_parser = clap::value_parser!(u32).range(1..=65536))]
    sample_splits: Option<u32>,
    /// Render the scenes of a list file (see `render --batch`) instead.
    #[arg(long, value_name = "LIST", conflicts_with_all = ["scene", "tiles", "sample_splits"], requires = "tasks")]
    batch: Option<String>,
    /// With --batch: the number of array tasks sharing the list.
    #[arg(long, value_name = "K", requires = "batch", value_parser = clap::value_parser!(u32).range(1..=65536))]
    tasks: Option<u32>,
    /// Samples per pixel of the render.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=65536))]
    spp: u32,
    /// Seed of the sample pattern.
    #[arg(long, default_value_t = 0)]
    seed: u32,
    /// Image width (overrides the scene's).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=16384))]
    width: Option<u32>,
    /// Image height (overrides the scene's).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=16384))]
    height: Option<u32>,
    /// Slurm partition of the jobs.
    #[arg(long)]
    partition: Option<String>,
    /// Slurm time limit of each job (e.g. 00:30:00).
    #[arg(long)]
    time: Option<String>,
    /// Submit the jobs, wait for them and report each task's time.
    #[arg(long)]
    submit: bool,
    /// Submit only the tasks whose parts (or batch outputs) are missing or
    /// invalid, then the merge; wait and report as --submit does.
    #[arg(long, conflicts_with = "submit")]
    resume: bool,
}

fn farm_slurm(a: SlurmArgs) -> anyhow::Result<()> {
    use penumbra::farm::{batch, identity, slurm, split};
    let work = match (&a.batch, &a.scene) {
        (Some(list), _) => slurm::Work::Batch {
            list: list.clone(),
            tasks: a.tasks.unwrap_or(1),
        },
        (None, Some(scene)) => {
            if a.tiles.is_none() && a.sample_splits.is_none() {
                anyhow::bail!(
                    "farm slurm: give --tiles N, --sample-splits M or --batch LIST --tasks K"
                );
            }
            slurm::Work::Split {
                scene: scene.clone(),
                tiles: a.tiles.unwrap_or(1),
                splits: a.sample_splits.unwrap_or(1),
            }
        }
        (None, None) => anyhow::bail!("farm slurm: a SCENE or --batch LIST is needed"),
    };
    let job = slurm::Job {
        work,
        out: a.output.clone(),
        spp: a.spp,
        seed: a.seed,
        width: a.width,
        height: a.height,
        partition: a.partition.clone(),
        time: a.time.clone(),
    };
    // Check the split against the scene now, not in every task.
    let mut render_id = None;
    if let slurm::Work::Split {
        scene,
        tiles,
        splits,
    } = &job.work
    {
        output::Format::from_path(std::path::Path::new(&job.out))?;
        if *splits > a.spp {
            anyhow::bail!(
                "--sample-splits: {splits} splits of --spp {} passes: at most one split a pass",
                a.spp
            );
        }
        let loaded = loaders::load_scene(
            std::path::Path::new(scene),
            &LoadOptions {
                width: a.width,
                height: a.height,
                ..Default::default()
            },
        )?;
        let cam = &loaded.scene.camera;
        split::Tile {
            index: 0,
            count: *tiles,
        }
        .rows(cam.height)
        .map_err(|e| anyhow::anyhow!("--tiles: {e}"))?;
        let settings = identity::RenderSettings {
            width: cam.width,
            height: cam.height,
            spp: a.spp,
            seed: a.seed,
            area_samples: None,
            kernel: KernelOptions::default(),
        };
        render_id = Some(identity::render_id(
            &loaded.files,
            &ShaderSource::Embedded,
            &settings,
        )?);
    }
    let script = job.write_script()?;
    println!("wrote {} ({} tasks)", script.display(), job.tasks());
    if !(a.submit || a.resume) {
        return Ok(());
    }
    let tasks: Vec<u32> = match (&job.work, a.resume) {
        (_, false) => (0..job.tasks()).collect(),
        (slurm::Work::Split { .. }, true) => {
            slurm::invalid_parts(&job, render_id.as_deref().unwrap_or_default())
        }
        (slurm::Work::Batch { list, tasks }, true) => {
            let entries =
                batch::read_list(std::path::Path::new(list), std::path::Path::new(&job.out))?;
            (0..*tasks)
                .filter(|&i| {
                    batch::task_share(
                        entries.clone(),
                        split::Tile {
                            index: i,
                            count: *tasks,
                        },
                    )
                    .iter()
                    .any(|e| !batch::is_complete(&e.output))
                })
                .collect()
        }
    };
    if a.resume {
        let is_batch = matches!(job.work, slurm::Work::Batch { .. });
        if tasks.is_empty() && (is_batch || slurm::output_complete(&job)) {
            println!("resume: every part and the output are complete; nothing submitted");
            return Ok(());
        }
        println!("resume: resubmitting tasks {tasks:?}");
    }
    let t0 = Instant::now();
    let submitted = slurm::submit(&job, &tasks)?;
    println!(
        "submitted array job {} and merge job {}",
        submitted.array.as_deref().unwrap_or("(none)"),
        submitted.merge.as_deref().unwrap_or("(none)")
    );
    slurm::wait(&job, &submitted)?;
    let mut failed = Vec::new();
    for &i in &tasks {
        match slurm::recorded_time(&job, &format!("task-{i}")) {
            Some((t0, t1, 0)) => println!("task {i}: {:.2} s", t1 - t0),
            Some((t0, t1, rc)) => {
                println!("task {i}: failed (exit {rc}) after {:.2} s", t1 - t0);
                failed.push(i);
            }
            None => {
                println!("task {i}: did not run to the end");
                failed.push(i);
            }
        }
    }
    let merge_state = submitted.merge.as_ref().map(|m| (m, slurm::job_state(m)));
    if let Some((m, state)) = &merge_state {
        match slurm::recorded_time(&job, "merge") {
            Some((t0, t1, _)) if state == "COMPLETED" => {
                println!("merge job {m}: {:.2} s", t1 - t0)
            }
            _ => println!("merge job {m}: {state}"),
        }
    }
    println!("end to end: {}", ms(t0.elapsed()));
    let logs = job.work_dir().join("logs");
    if !failed.is_empty() {
        let list: Vec<String> = failed.iter().map(u32::to_string).collect();
        anyhow::bail!(
            "farm: task {} failed (logs in {}){}; rerun with --resume",
            list.join(", "),
            logs.display(),
            match &merge_state {
                Some((m, s)) => format!(", merge job {m} {s}"),
                None => String::new(),
            }
        );
    }
    if let Some((m, s)) = &merge_state {
        if s != "COMPLETED" {
            anyhow::bail!("farm: merge job {m} {s} (see {}/merge.log)", logs.display());
        }
    }
    Ok(())
}

#[derive(clap::Args)]
struct MergeArgs {
    /// The part files (.exr), in any order.
    #[arg(required = true)]
    parts: Vec<PathBuf>,
    /// The merged image (.png or .exr), written atomically.
    #[arg(short, long)]
    output: PathBuf,
}

fn merge(args: MergeArgs) -> anyhow::Result<()> {
    let t0 = Instant::now();
    let plan = penumbra::farm::merge::plan(&args.parts)?;
    penumbra::farm::merge::write(&plan, &args.output)?;
    println!(
        "merged {} parts ({} tiles, {} passes) into {} ({}x{}) in {}",
        args.parts.len(),
        plan.tiles.len(),
        plan.spp,
        args.output.display(),
        plan.width,
        plan.height,
        ms(t0.elapsed())
    );
    Ok(())
}

#[derive(clap::Args)]
struct DiffArgs {
    /// The reference image (.png, read as sRGB; .exr, read as linear).
    a: PathBuf,
    /// The image to compare with it.
    b: PathBuf,
    /// Write the per-pixel FLIP difference in false colour (magma) here, atomically.
    #[arg(short, long)]
    output: Option<PathBuf>,
}

fn diff(args: DiffArgs) -> anyhow::Result<()> {
    let m = penumbra::metrics::diff_files(&args.a, &args.b, args.output.as_deref())?;
    for line in m.lines() {
        println!("{line}");
    }
    // Depth AOVs (`--aov depth`), when both files have them.
    let depth = |p: &std::path::Path| {
        let exr = p.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr"));
        exr.then(|| penumbra::metrics::read_depth(p)).flatten()
    };
    if let (Some(za), Some(zb)) = (depth(&args.a), depth(&args.b)) {
        if let Some(d) = penumbra::metrics::depth_error(&za, &zb) {
            println!("depth_max_relative_error: {}", d.max_relative);
            println!("depth_mean_relative_error: {}", d.mean_relative);
            println!("depth_hit_mismatches: {}", d.hit_mismatches);
        }
    }
    Ok(())
}

#[derive(clap::Args)]
struct WatchArgs {
    /// The scene file.
    scene: PathBuf,
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
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=16384))]
    width: Option<u32>,
    /// Image height in pixels (overrides the scene's).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=16384))]
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
    /// lavapipe's SIMD width in bits: `auto` keeps 256 for compile latency;
    /// LP_NATIVE_VECTOR_WIDTH in the environment takes precedence.
    #[arg(long, default_value = "auto", value_name = "auto|128|256|512")]
    vector_width: vector_width::Request,
    /// Longest, in seconds, that one submission of work may run on the device
    /// (a band of the image, 64 rows at the full size): a watchdog for shader
    /// code that does not end. Past it, watch reports the error naming the
    /// shader file, restarts itself (the device cannot stop the shader) and
    /// renders the next save.
    #[arg(long, value_name = "SECONDS", value_parser = |s: &str| parse_seconds(s).map(Seconds), allow_hyphen_values = true,
          default_value_t = Seconds(penumbra::watch::DEFAULT_TIME_LIMIT))]
    time_limit: Seconds,
    #[command(flatten)]
    limits: LimitArgs,
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
}

/// A duration given in seconds on the command line (shown so in `--help`).
#[derive(Clone, Copy, Debug)]
struct Seconds(std::time::Duration);

impl std::fmt::Display for Seconds {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.0.as_secs_f64())
    }
}

impl LimitArgs {
    /// Load options with these limits and the size overrides.
    fn load_options(self, width: Option<u32>, height: Option<u32>) -> LoadOptions {
        LoadOptions {
            width,
            height,
            restrict_paths: self.restrict_paths,
            max_scene_bytes: self.max_scene_memory << 20,
            ..Default::default()
        }
    }
}

#[derive(clap::Args)]
struct RenderArgs {
    /// The scene file.
    #[arg(required_unless_present = "batch")]
    scene: Option<PathBuf>,
    /// Output image; the extension picks the format (.png or .exr); default
    /// out.png. With --batch, the folder the images go to.
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Image width in pixels (overrides the scene's).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=16384))]
    width: Option<u32>,
    /// Image height in pixels (overrides the scene's).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=16384))]
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
    /// Ray/triangle test: `watertight` (Woop et al., u,v before t), or
    /// Möller–Trumbore `uv-first` (the seminar's) or `t-first`.
    #[arg(long, default_value = "watertight")]
    triangle_test: TriangleTest,
    /// Samples per pixel (one pass each): 1 goes through the pixel centre,
    /// more are stratified over the pixel (box filter).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=65536))]
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
    time_budget: Option<std::time::Duration>,
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
    /// lavapipe's SIMD width in bits: `auto` takes 256 on any CPU with AVX
    /// (the current kernel runs slower at 512 even with AVX-512);
    /// LP_NATIVE_VECTOR_WIDTH in the environment takes precedence.
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
    batch: Option<PathBuf>,
    /// With --batch: render only task I's share of K (every K-th scene from
    /// the I-th), for a job array.
    #[arg(long, value_name = "I/K", requires = "batch")]
    batch_task: Option<penumbra::farm::split::Tile>,
    /// Longest, in seconds, that one submission of work may run on the device
    /// (one pass over a band of the image): a watchdog for shader code that
    /// does not end. Past it, penumbra stops with an error naming the shader
    /// file, and writes nothing.
    #[arg(long, value_name = "SECONDS", value_parser = |s: &str| parse_seconds(s).map(Seconds), allow_hyphen_values = true,
          default_value_t = Seconds(penumbra::vulkan::DEFAULT_TIME_LIMIT))]
    time_limit: Seconds,
    #[command(flatten)]
    limits: LimitArgs,
}

fn parse_seconds(s: &str) -> Result<std::time::Duration, String> {
    let v: f64 = s
        .parse()
        .map_err(|_| format!("expected a number of seconds, got `{s}`"))?;
    if !(v > 0.0 && v <= 1e6) {
        return Err(format!("must be in (0, 1000000] seconds, got {s}"));
    }
    Ok(std::time::Duration::from_secs_f64(v))
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
        camera,
        device,
        shaders,
        validate,
        accel,
        triangle_test,
        spp,
        area_samples,
        seed,
        time_budget,
        sampler,
        reference,
        aov,
        vector_width,
        tile,
        passes,
        batch,
        batch_task,
        time_limit,
        limits,
    } = args;
    let out = out.unwrap_or_else(|| PathBuf::from("out.png"));
    let job = vector_width::Job::Render {
        pixels: width.zip(height).map(|(w, h)| w as u64 * h as u64),
        passes: spp,
        time_budget,
    };
    let sampling = Sampling {
        spp,
        seed,
        time_budget,
    };
    let shaders = shaders.map(ShaderSource::Directory).unwrap_or_default();
    let kernel = KernelOptions {
        accel,
        triangle_test,
        sampler,
        ..Default::default()
    };
    let scene = match (scene, &batch) {
        (Some(s), _) => s,
        (None, Some(list)) => {
            vector_width::apply(vector_width, job);
            let settings = penumbra::farm::batch::BatchSettings {
                load: limits.load_options(width, height),
                sampling,
                area_samples,
            };
            let renderer = RendererOptions {
                device,
                validation: validate,
                shaders,
                kernel,
                time_limit: Some(time_limit.0),
            };
            return render_batch(list, &out, batch_task, &renderer, &settings);
        }
        (None, None) => anyhow::bail!("render: a SCENE or --batch LIST is needed"),
    };
    let split = tile.is_some() || passes.is_some();
    if split {
        let refuse =
            |what: &str| anyhow::anyhow!("--tile/--passes: cannot be combined with {what}");
        if reference {
            return Err(refuse("--reference"));
        }
        if aov.is_some() {
            return Err(refuse("--aov"));
        }
        if time_budget.is_some() {
            return Err(refuse("--time-budget (a part must render all its passes)"));
        }
        if output::Format::from_path(&out)? != output::Format::Exr {
            anyhow::bail!(
                "{}: a part of a split render is an OpenEXR file (-o NAME.exr)",
                out.display()
            );
        }
        if let Some(p) = passes {
            if p.end > spp {
                anyhow::bail!("--passes: {p} is not within the render's --spp {spp} passes");
            }
        }
    }
    // Before the Vulkan driver loads (Renderer::new): lavapipe reads it then.
    let vector_width = (!reference).then(|| vector_width::apply(vector_width, job));
    // Refuse an unwritable output before spending time on the render.
    let format = output::check_writable(&out)?;
    if aov.is_some() && format != output::Format::Exr {
        anyhow::bail!(
            "{}: --aov needs an .exr output (-o NAME.exr)",
            out.display()
        );
    }
    let shader_source = shaders.clone();
    // The device first, so that the loader refuses a scene the device cannot
    // hold before expanding it.
    let mut renderer = match reference {
        true => None,
        false => Some(Renderer::new(&RendererOptions {
            device,
            validation: validate,
            shaders,
            kernel,
            time_limit: Some(time_limit.0),
        })?),
    };
    let mut load_options = limits.load_options(width, height);
    if let Some(c) = &camera {
        load_options.camera = loaders::gltf::CameraChoice::parse(c);
    }
    if let Some(r) = &renderer {
        load_options.max_triangles = r.max_triangles();
        load_options.max_texture_bytes = r.texture_capacity();
    }
    let t0 = Instant::now();
    let loaded = loaders::load_scene(&scene, &load_options)?;
    let load = t0.elapsed();
    for note in &loaded.notes {
        eprintln!("note: {}", terminal::diagnostic(note));
    }
    let mut scene_data = loaded.scene;
    if let Some(n) = area_samples {
        for l in &mut scene_data.lights {
            l.kind.set_samples(n);
        }
    }
    let Some(renderer) = renderer.as_mut() else {
        penumbra::reference::supports(&scene_data)
            .map_err(|why| anyhow::anyhow!("{}: {why}", scene.display()))?;
        return render_reference(&scene_data, &sampling, &kernel, &out, load, aov);
    };
    if split {
        let settings = penumbra::farm::identity::RenderSettings {
            width: scene_data.camera.width,
            height: scene_data.camera.height,
            spp,
            seed,
            area_samples,
            kernel,
        };
        let render = penumbra::farm::identity::render_id(&loaded.files, &shader_source, &settings)?;
        let tile = tile.unwrap_or(penumbra::farm::split::Tile::WHOLE);
        let passes = passes.unwrap_or(penumbra::farm::split::Passes { start: 0, end: spp });
        let rows = tile
            .rows(settings.height)
            .map_err(|e| anyhow::anyhow!("--tile: {e}"))?;
        let info = penumbra::farm::part::PartInfo {
            render,
            scene: scene
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default(),
            tile,
            passes,
            spp,
            width: settings.width,
            height: settings.height,
            rows: rows.clone(),
        };
        let uploaded = renderer.upload_for_parts(&scene_data)?;
        let part = penumbra::render::PartRange {
            rows,
            passes: passes.start..passes.end,
        };
        let frame = renderer.render_part(&uploaded, &part, &sampling, &mut |_| {})?;
        let t1 = Instant::now();
        penumbra::farm::part::write(&out, &info, &frame.image)?;
        let t = &frame.stats.timings;
        println!(
            "part {} of {}: tile {tile}, rows {}..{}, passes {passes} of {spp} | load {}, shader compile {}, pipeline creation {}, driver compile {}, GPU render {}, readback {}, write {}",
            out.display(),
            scene.display(),
            part.rows.start,
            part.rows.end,
            ms(load),
            ms(t.shader_compile),
            ms(t.pipeline_creation),
            ms(t.driver_compile),
            ms(t.render),
            ms(t.readback),
            ms(t1.elapsed())
        );
        return Ok(());
    }
    let (frame, aovs) = render_with_progress(renderer, &scene_data, &sampling, aov.is_some())
        .map_err(|e| match e {
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
    match (aov, &aovs) {
        (Some(set), Some(a)) => output::write_exr_with_aovs(&out, &frame.image, a, set)?,
        _ => output::write_image(&out, &frame.image)?,
    }
    let write = t1.elapsed();
    let s = &frame.stats;
    let t = &s.timings;
    let dev = renderer.device();
    // The width matters to CPU devices (lavapipe) only.
    let width_note = match vector_width {
        Some(c) if dev.device_type == "CPU" => format!(" | {c}"),
        _ => String::new(),
    };
    println!(
        "{}",
        summary_line(
            &format!("{} ({})", dev.name, dev.device_type),
            &frame.image,
            s,
            &[
                ("load", load),
                ("shader compile", t.shader_compile),
                ("pipeline creation", t.pipeline_creation),
                ("driver compile", t.driver_compile),
                ("BVH build", t.accel_build),
                ("upload", t.upload),
                ("GPU render", t.render),
                ("readback", t.readback),
                ("write", write),
            ],
            &format!(
                "{}{width_note}{}",
                triangles_note(&scene_data),
                texture_note(s.texture_bytes)
            ),
        )
    );
    Ok(())
}

/// ` | textures N MiB (mip-maps included)` for a scene with textures.
fn texture_note(bytes: u64) -> String {
    if bytes == 0 {
        return String::new();
    }
    format!(
        " | textures {:.2} MiB (mip-maps included)",
        bytes as f64 / 1048576.0
    )
}

/// ` | N triangles`: the scene's, glTF instances expanded (issue 39).
fn triangles_note(scene: &penumbra::scene::Scene) -> String {
    format!(" | {} triangles", scene.triangle_count())
}

/// `penumbra render --batch LIST -o DIR`: every scene of the list with one
/// renderer (one device, one kernel cache), a line per scene, and one
/// `error:` line at the end naming every scene that failed.
fn render_batch(
    list: &std::path::Path,
    dir: &std::path::Path,
    task: Option<penumbra::farm::split::Tile>,
    renderer: &RendererOptions,
    settings: &penumbra::farm::batch::BatchSettings,
) -> anyhow::Result<()> {
    use penumbra::farm::batch::{self, Outcome};
    let t0 = Instant::now();
    if !dir.is_dir() {
        anyhow::bail!(
            "{}: -o: the output folder of a batch must exist",
            dir.display()
        );
    }
    let mut entries = batch::read_list(list, dir)?;
    if let Some(t) = task {
        entries = batch::task_share(entries, t);
    }
    let mut renderer = Renderer::new(renderer)?;
    let total = entries.len();
    let results = batch::run(&mut renderer, &entries, settings, &mut |e, o| match o {
        Outcome::Rendered(d) => println!(
            "rendered {} -> {} in {}",
            e.scene.display(),
            e.output.display(),
            ms(*d)
        ),
        Outcome::Skipped => println!(
            "skipped {} ({} is complete)",
            e.scene.display(),
            e.output.display()
        ),
        Outcome::Failed(m) => eprintln!("failed: {}", terminal::diagnostic(m)),
    });
    let failed: Vec<String> = results
        .iter()
        .filter(|(_, o)| matches!(o, Outcome::Failed(_)))
        .map(|(e, _)| e.scene.display().to_string())
        .collect();
    let skipped = results
        .iter()
        .filter(|(_, o)| matches!(o, Outcome::Skipped))
        .count();
    let rendered = results.len() - skipped - failed.len();
    println!(
        "batch {}: {} scenes, {} rendered, {} skipped, {} failed, {} not started in {}",
        list.display(),
        total,
        rendered,
        skipped,
        failed.len(),
        total - results.len(),
        ms(t0.elapsed())
    );
    if renderer.is_hung() {
        // The device still runs the shader that did not end: no exit handler
        // may wait for it.
        let last = failed.last().cloned().unwrap_or_default();
        eprintln!(
            "error: {}: {} ran past --time-limit; the device cannot stop it, so {} scene(s) after it were not started (a rerun resumes)",
            terminal::escape(&list.display().to_string()),
            terminal::escape(&last),
            total - results.len()
        );
        exit_leaving_the_device(1);
    }
    if !failed.is_empty() {
        anyhow::bail!(
            "{}: {} of {total} scenes failed: {}",
            list.display(),
            failed.len(),
            failed.join(", ")
        );
    }
    Ok(())
}

/// `penumbra render --reference`: the f64 CPU renderer, no Vulkan; the
/// summary line in the style of the GPU path's.
fn render_reference(
    scene: &penumbra::scene::Scene,
    sampling: &Sampling,
    kernel: &KernelOptions,
    out: &std::path::Path,
    load: std::time::Duration,
    aov: Option<output::AovSet>,
) -> anyhow::Result<()> {
    let t1;
    let frame = if let Some(set) = aov {
        let (frame, aovs) = penumbra::reference::render_with_aovs(scene, sampling, kernel.sampler);
        t1 = Instant::now();
        output::write_exr_with_aovs(out, &frame.image, &aovs, set)?;
        frame
    } else {
        let frame = penumbra::reference::render(scene, sampling, kernel.sampler);
        t1 = Instant::now();
        output::write_image(out, &frame.image)?;
        frame
    };
    let write = t1.elapsed();
    let s = &frame.stats;
    println!(
        "{}",
        summary_line(
            "CPU reference (f64)",
            &frame.image,
            s,
            &[
                ("load", load),
                ("BVH build", s.timings.accel_build),
                ("render", s.timings.render),
                ("write", write),
            ],
            &format!(
                "{}{}",
                triangles_note(scene),
                texture_note(scene.textures.iter().map(|t| t.device_bytes()).sum())
            ),
        )
    );
    Ok(())
}

/// The one summary line of `penumbra render`, on the GPU or the CPU
/// reference: `WHO: WxH, N spp, R rays (P primary + S shadow) | PHASE TIME,
/// … | X Mrays/s`, then `note` (empty, or ` | …`).
fn summary_line(
    who: &str,
    image: &penumbra::frame::Image,
    stats: &penumbra::frame::RenderStats,
    phases: &[(&str, std::time::Duration)],
    note: &str,
) -> String {
    let phases: Vec<String> = phases
        .iter()
        .map(|(name, d)| format!("{name} {}", ms(*d)))
        .collect();
    format!(
        "{who}: {}x{}, {} spp, {} rays ({} primary + {} shadow) | {} | {:.1} Mrays/s{note}",
        image.width,
        image.height,
        stats.passes,
        stats.rays(),
        stats.primary_rays,
        stats.shadow_rays,
        phases.join(", "),
        stats.mrays_per_second()
    )
}

/// Uploads and renders in passes, with a progress bar (passes and rays/s)
/// when there is more than one pass and stderr is a terminal.
fn render_with_progress(
    renderer: &mut Renderer,
    scene: &penumbra::scene::Scene,
    sampling: &Sampling,
    with_aovs: bool,
) -> Result<(penumbra::render::Frame, Option<penumbra::render::Aovs>), RenderError> {
    let uploaded = renderer.upload(scene)?;
    let bar = if sampling.spp > 1 {
        indicatif::ProgressBar::new(sampling.spp as u64)
    } else {
        indicatif::ProgressBar::hidden()
    };
    bar.set_style(
        indicatif::ProgressStyle::with_template("{bar:30} {pos}/{len} passes, {msg}, eta {eta}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let (w, h) = uploaded.size();
    let mut on_pass = |p: &penumbra::render::PassInfo| {
        bar.set_position(p.done as u64);
        let rate = p.rays as f64 / p.elapsed.as_secs_f64().max(1e-9) / 1e6;
        bar.set_message(format!("{rate:.1} Mrays/s"));
    };
    let result = if with_aovs {
        renderer
            .render_with_aovs(&uploaded, w, h, sampling, &mut on_pass)
            .map(|(f, a)| (f, Some(a)))
    } else {
        renderer
            .render_progressive(&uploaded, w, h, sampling, &mut on_pass)
            .map(|f| (f, None))
    };
    bar.finish_and_clear();
    let (mut frame, aovs) = result?;
    let (accel_build, upload) = uploaded.upload_timings();
    frame.stats.timings.accel_build = accel_build;
    frame.stats.timings.upload = upload;
    Ok((frame, aovs))
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

fn watch(args: WatchArgs) -> anyhow::Result<()> {
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::sync::Arc;
    // Before the Vulkan driver loads.
    vector_width::apply(args.vector_width, vector_width::Job::Watch);
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
    opts.renderer = RendererOptions {
        device: args.device,
        validation: args.validate,
        shaders,
        kernel: KernelOptions::default(),
        time_limit: Some(args.time_limit.0),
    };
    opts.load = args.limits.load_options(args.width, args.height);
    opts.serve = args.serve;
    opts.preview_divisor = args.preview;
    opts.debounce = std::time::Duration::from_millis(args.debounce_ms);
    opts.resume = penumbra::watch::restart::Resume::take_from_env();
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
const WATCH_STOP_GRACE: std::time::Duration = std::time::Duration::from_millis(300);

/// Ends the process at once with `code`, without running exit handlers: after
/// a time-out the device still runs the dispatch that never ends, and the
/// driver's exit handlers (Mesa's thread pools) would wait for it for ever.
/// Every output is written atomically, so nothing partial is left.
fn exit_leaving_the_device(code: i32) -> ! {
    use std::io::Write as _;
    let _ = std::io::stdout().flush();
    let _ = std::io::stderr().flush();
    // SAFETY: _exit ends the process; it touches no Rust state.
    unsafe { libc::_exit(code) }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    // A panic is a bug, not a way to report input: should one still happen,
    // one `error:` line names the file, the panic unwinds (removing any
    // temporary output file) and the exit status is 70 (EX_SOFTWARE).
    penumbra::panics::install_hook();
    match &cli.command {
        Command::Render(a) => {
            if let Some(s) = a.scene.clone().or(a.batch.clone()) {
                penumbra::panics::set_subject(s)
            }
        }
        Command::Watch(a) => penumbra::panics::set_subject(a.scene.clone()),
        Command::Diff(a) => penumbra::panics::set_subject(a.b.clone()),
        Command::Merge(a) => penumbra::panics::set_subject(a.output.clone()),
        Command::Farm(FarmCommand::Slurm(a)) => {
            penumbra::panics::set_subject(a.output.clone().into())
        }
        Command::Devices => {}
    }
    let run = std::panic::catch_unwind(|| match cli.command {
        Command::Render(args) => render(args),
        Command::Devices => devices(),
        Command::Watch(args) => watch(args),
        Command::Diff(args) => diff(args),
        Command::Merge(args) => merge(args),
        Command::Farm(FarmCommand::Slurm(args)) => farm_slurm(args),
    });
    match run {
        Ok(Ok(())) => ExitCode::SUCCESS,
        Ok(Err(e)) => {
            eprintln!("error: {}", terminal::diagnostic(&format!("{e:#}")));
            if penumbra::render::is_timeout(&e) {
                exit_leaving_the_device(1);
            }
            ExitCode::FAILURE
        }
        Err(_) => ExitCode::from(70),
    }
}
