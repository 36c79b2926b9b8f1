//! `penumbra diff`: error metrics between two renders.

use std::path::PathBuf;

#[derive(clap::Args)]
pub struct DiffArgs {
    /// The reference image (.png, read as sRGB; .exr, read as linear).
    a: PathBuf,
    /// The image to compare with it.
    pub b: PathBuf,
    /// Write the per-pixel FLIP difference in false colour (magma) here, atomically.
    #[arg(short, long)]
    output: Option<PathBuf>,
}

pub fn run(args: DiffArgs) -> anyhow::Result<()> {
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
