//! Section 4's part: the kernel specialised to the scene's features against
//! the general kernel and against specialisation by WGSL text: SPIR-V size,
//! cold compile phases in two rounds of alternating order, interleaved
//! frames, and the cost of the area-light sampling code for a scene without
//! area lights.

use common::ms;
use penumbra::render::KernelOptions;

use crate::measure::{frame, interleave, renderer, upload};
use crate::schema::{KernelCompile, SpecialisePart};
use crate::Args;

/// The part: compiles, then the interleaved comparisons.
pub fn run(args: &Args) -> anyhow::Result<SpecialisePart> {
    let mut r = renderer(args)?;
    let bunny = common::meshes::bunny_scene(&common::repo_root())?;
    let spec = KernelOptions::default();
    let general = KernelOptions {
        specialise: false,
        ..spec
    };
    let text = KernelOptions {
        text_specialise: true,
        ..spec
    };
    let src = penumbra::render::ShaderSource::Embedded.assemble()?;
    let features = bunny.features();
    let mut out = SpecialisePart {
        specialised: KernelCompile {
            spirv_bytes: src.compile_frame(&features, &spec)?.len() * 4,
            ..Default::default()
        },
        general: KernelCompile {
            spirv_bytes: src.compile_frame(&features, &general)?.len() * 4,
            ..Default::default()
        },
        text: KernelCompile {
            spirv_bytes: src.compile_frame(&features, &text)?.len() * 4,
            ..Default::default()
        },
        ..Default::default()
    };
    let up = upload(&mut r, &bunny, spec)?;
    let (w, h) = up.size();
    // Two rounds of cold compiles (the driver's cache is disabled by the
    // parent), the order swapped in the second.
    for order in [[0, 1, 2], [2, 1, 0]] {
        r.clear_pipeline_cache();
        for which in order {
            let (k, c) = match which {
                0 => (spec, &mut out.specialised),
                1 => (general, &mut out.general),
                _ => (text, &mut out.text),
            };
            let t = frame(&mut r, &up, k, 8, 8)?.stats.timings;
            c.naga_ms.push(ms(t.shader_compile));
            c.pipeline_ms.push(ms(t.pipeline_creation));
            c.driver_compile_ms.push(ms(t.driver_compile));
        }
    }
    let reps = if args.quick { 2 } else { 5 };
    out.frames = interleave(
        &mut r,
        "general vs specialised kernel",
        ("general", &up, general),
        ("specialised", &up, spec),
        (w, h),
        reps,
    )?;
    out.text_frames = interleave(
        &mut r,
        "specialised by WGSL text vs by overrides",
        ("text", &up, text),
        ("overrides", &up, spec),
        (w, h),
        reps,
    )?;
    // The cost of the sampling code for a scene that does not need it.
    let path = common::repo_root().join("scenes/showcase.json");
    let showcase = penumbra::loaders::load_scene(&path, &Default::default())?.scene;
    let sampling = KernelOptions {
        with_sampling: true,
        ..spec
    };
    let up = upload(&mut r, &showcase, spec)?;
    let (w, h) = up.size();
    out.sampling = interleave(
        &mut r,
        "showcase with and without the sampling code",
        ("with sampling code", &up, sampling),
        ("without (specialised)", &up, spec),
        (w, h),
        reps,
    )?;
    Ok(out)
}
