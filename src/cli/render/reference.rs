//! `penumbra render --reference`: the f64 CPU renderer, no Vulkan, with the
//! summary line in the style of the GPU path's.

use std::path::Path;
use std::time::{Duration, Instant};

use penumbra::loaders::Loaded;
use penumbra::output;

use super::{summary, write_shown, RenderArgs};

pub fn run(
    file: &Path,
    loaded: &Loaded,
    args: &RenderArgs,
    out: &Path,
    load: Duration,
) -> anyhow::Result<()> {
    let scene = &loaded.scene;
    penumbra::reference::supports(scene)
        .map_err(|why| anyhow::anyhow!("{}: {why}", file.display()))?;
    let (sampling, sampler) = (args.sampling(), args.kernel().sampler);
    let t1;
    let frame = if let Some(set) = args.aov {
        let (frame, aovs) = penumbra::reference::render_with_aovs(scene, &sampling, sampler);
        t1 = Instant::now();
        output::write_exr_with_aovs(out, &frame.image, &aovs, set)?;
        frame
    } else {
        let frame = penumbra::reference::render(scene, &sampling, sampler);
        t1 = Instant::now();
        write_shown(out, &frame.image, loaded, args)?;
        frame
    };
    let write = t1.elapsed();
    let s = &frame.stats;
    println!(
        "{}",
        summary::line(
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
                summary::triangles_note(scene),
                summary::texture_note(scene.textures.iter().map(|t| t.device_bytes()).sum())
            ),
        )
    );
    Ok(())
}
