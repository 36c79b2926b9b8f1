//! `penumbra farm slurm`: a render split over a Slurm job array, and its merge.

use std::path::{Path, PathBuf};
use std::time::Instant;

use penumbra::loaders::{self, LoadOptions};
use penumbra::output;
use penumbra::render::{KernelOptions, ShaderSource};

use super::look::{DisplayArgs, LightingArgs};
use super::{ms, side_parser, spp_parser};

#[derive(clap::Subcommand)]
pub enum FarmCommand {
    /// Write an sbatch script (OUT.farm/job.sh): a job array with one task per
    /// part and a merge job after it; --submit submits it, waits and reports.
    Slurm(SlurmArgs),
}

#[derive(clap::Args)]
pub struct SlurmArgs {
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
    #[arg(long, default_value_t = 1, value_parser = spp_parser())]
    spp: u32,
    /// Seed of the sample pattern.
    #[arg(long, default_value_t = 0)]
    seed: u32,
    /// Image width (overrides the scene's).
    #[arg(long, value_parser = side_parser())]
    width: Option<u32>,
    /// Image height (overrides the scene's).
    #[arg(long, value_parser = side_parser())]
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
    #[command(flatten)]
    lighting: LightingArgs,
    #[command(flatten)]
    display: DisplayArgs,
}

impl FarmCommand {
    /// The file a panic's `error:` line names.
    pub fn output(&self) -> PathBuf {
        match self {
            FarmCommand::Slurm(a) => PathBuf::from(&a.output),
        }
    }
}

pub fn run(command: FarmCommand) -> anyhow::Result<()> {
    match command {
        FarmCommand::Slurm(a) => slurm(a),
    }
}

fn slurm(a: SlurmArgs) -> anyhow::Result<()> {
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
    let mut job = slurm::Job {
        work,
        out: a.output.clone(),
        spp: a.spp,
        seed: a.seed,
        width: a.width,
        height: a.height,
        partition: a.partition.clone(),
        time: a.time.clone(),
        render_flags: a.lighting.forwarded(),
        merge_flags: Vec::new(),
    };
    if let slurm::Work::Batch { .. } = job.work {
        // A batch's renders write the images themselves.
        job.render_flags.extend(a.display.forwarded());
    }
    // Check the split against the scene now, not in every task.
    let mut render_id = None;
    if let slurm::Work::Split {
        scene,
        tiles,
        splits,
    } = &job.work
    {
        output::Format::from_path(Path::new(&job.out))?;
        if *splits > a.spp {
            anyhow::bail!(
                "--sample-splits: {splits} splits of --spp {} passes: at most one split a pass",
                a.spp
            );
        }
        let loaded = loaders::load_scene(
            Path::new(scene),
            &LoadOptions {
                width: a.width,
                height: a.height,
                lighting: a.lighting.lighting(),
                ..Default::default()
            },
        )?;
        // The merge knows no scene: it gets the scene's tone mapping.
        job.merge_flags = a.display.forwarded_to_merge(loaded.lit_by_default);
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
            lighting: a.lighting.lighting(),
            gltf_materials: Default::default(),
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
            let entries = batch::read_list(Path::new(list), Path::new(&job.out))?;
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
