//! `penumbra render --tile I/N --passes A..B`: one part of a split render,
//! written as an OpenEXR part file for `penumbra merge`.

use std::path::Path;
use std::time::{Duration, Instant};

use penumbra::farm::{identity, part, split};
use penumbra::loaders::Loaded;
use penumbra::output;
use penumbra::render::{PartRange, RenderRequest, Renderer};

use super::RenderArgs;
use crate::cli::ms;

/// Refuses what a part cannot be combined with, before the device opens.
pub fn check(args: &RenderArgs, out: &Path) -> anyhow::Result<()> {
    let refuse = |what: &str| anyhow::anyhow!("--tile/--passes: cannot be combined with {what}");
    if args.reference {
        return Err(refuse("--reference"));
    }
    if args.aov.is_some() {
        return Err(refuse("--aov"));
    }
    if args.time_budget.is_some() {
        return Err(refuse("--time-budget (a part must render all its passes)"));
    }
    if output::Format::from_path(out)? != output::Format::Exr {
        anyhow::bail!(
            "{}: a part of a split render is an OpenEXR file (-o NAME.exr)",
            out.display()
        );
    }
    if let Some(p) = args.passes {
        if p.end > args.spp {
            anyhow::bail!(
                "--passes: {p} is not within the render's --spp {} passes",
                args.spp
            );
        }
    }
    Ok(())
}

/// Renders the part's rows and passes and writes its file.
pub fn run(
    renderer: &mut Renderer,
    scene: &Path,
    loaded: &Loaded,
    args: &RenderArgs,
    out: &Path,
    load: Duration,
) -> anyhow::Result<()> {
    let camera = &loaded.scene.camera;
    let settings = identity::RenderSettings {
        width: camera.width,
        height: camera.height,
        spp: args.spp,
        seed: args.seed,
        area_samples: args.area_samples,
        kernel: args.kernel(),
        lighting: args.lighting.lighting(),
        gltf_materials: args.limits.gltf_materials,
    };
    let render = identity::render_id(&loaded.files, &args.shader_source(), &settings)?;
    let info = part::PartInfo::new(
        render,
        scene,
        args.tile.unwrap_or(split::Tile::WHOLE),
        args.passes.unwrap_or(split::Passes {
            start: 0,
            end: args.spp,
        }),
        &settings,
    )
    .map_err(|e| anyhow::anyhow!("--tile: {e}"))?;
    let uploaded = renderer.upload_for_parts(&loaded.scene)?;
    let range = PartRange {
        rows: info.rows.clone(),
        passes: info.passes.start..info.passes.end,
    };
    let frame = renderer
        .render(
            &uploaded,
            RenderRequest::part(uploaded.size(), &range, &args.sampling(), &mut |_| {}),
        )
        .map(|r| r.frame)?;
    let t1 = Instant::now();
    part::write(out, &info, &frame.image)?;
    let t = &frame.stats.timings;
    println!(
        "part {} of {}: tile {}, rows {}..{}, passes {} of {} | load {}, shader compile {}, pipeline creation {}, driver compile {}, GPU render {}, readback {}, write {}",
        out.display(),
        scene.display(),
        info.tile,
        range.rows.start,
        range.rows.end,
        info.passes,
        args.spp,
        ms(load),
        ms(t.shader_compile),
        ms(t.pipeline_creation),
        ms(t.driver_compile),
        ms(t.render),
        ms(t.readback),
        ms(t1.elapsed())
    );
    Ok(())
}
