//! `penumbra render --batch LIST -o DIR`: every scene of the list with one
//! renderer (one device, one kernel cache), a line per scene, and one
//! `error:` line at the end naming every scene that failed.

use std::path::Path;
use std::time::Instant;

use penumbra::farm::batch::{self, BatchSettings, Outcome};
use penumbra::render::Renderer;
use penumbra::terminal;

use super::RenderArgs;
use crate::cli::{calibrate, exit_leaving_the_device, ms};

pub fn run(list: &Path, dir: &Path, args: &RenderArgs) -> anyhow::Result<()> {
    // Before the Vulkan driver loads (Renderer::new): lavapipe reads it then.
    let lavapipe = calibrate::settings(args.vector_width, args.job(), args.device.as_ref(), true)?;
    let settings = BatchSettings {
        load: args
            .limits
            .load_options(args.width, args.height, args.lighting),
        sampling: args.sampling(),
        area_samples: args.area_samples,
        display: args.display.display(),
    };
    let t0 = Instant::now();
    if !dir.is_dir() {
        anyhow::bail!(
            "{}: -o: the output folder of a batch must exist",
            dir.display()
        );
    }
    let mut entries = batch::read_list(list, dir)?;
    if let Some(t) = args.batch_task {
        entries = batch::task_share(entries, t);
    }
    let mut renderer = Renderer::new(&args.renderer_options())?;
    lavapipe.check_driver(renderer.device());
    let total = entries.len();
    let results = batch::run(&mut renderer, &entries, &settings, &mut |e, o| match o {
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
    if failed.is_empty() {
        drop(renderer);
        lavapipe.calibrate_if_due();
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
