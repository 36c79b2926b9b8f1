//! `penumbra merge`: the part files of a split render into one image.

use std::path::PathBuf;
use std::time::Instant;

use super::look::DisplayArgs;
use super::ms;

#[derive(clap::Args)]
pub struct MergeArgs {
    /// The part files (.exr), in any order.
    #[arg(required = true)]
    parts: Vec<PathBuf>,
    /// The merged image (.png or .exr), written atomically.
    #[arg(short, long)]
    pub output: PathBuf,
    #[command(flatten)]
    display: DisplayArgs,
}

pub fn run(args: MergeArgs) -> anyhow::Result<()> {
    let t0 = Instant::now();
    let plan = penumbra::farm::merge::plan(&args.parts)?;
    penumbra::farm::merge::write(&plan, &args.output, args.display.display())?;
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
