//! The textures part: the cost of texturing the bunny scene (the bunny and
//! a tiled ground, trilinear) against the untextured scene, and of making
//! one of its materials a cut-out (alpha mask, compiled into traversal)
//! against the textured scene, in interleaved frames of one process.

use penumbra::render::KernelOptions;

use crate::measure::{device, interleave, renderer, upload};
use crate::schema::TexturesPart;
use crate::Args;

/// The part.
pub fn run(args: &Args) -> anyhow::Result<TexturesPart> {
    let mut r = renderer(args)?;
    let root = common::repo_root();
    let k = KernelOptions::default();
    let plain = common::meshes::bunny_scene(&root)?;
    let textured = common::meshes::textured_bunny_scene(&root, false)?;
    let masked = common::meshes::textured_bunny_scene(&root, true)?;
    let texture_bytes: u64 = textured.textures.iter().map(|t| t.device_bytes()).sum();
    let up_plain = upload(&mut r, &plain, k)?;
    let up_textured = upload(&mut r, &textured, k)?;
    let up_masked = upload(&mut r, &masked, k)?;
    let size = up_plain.size();
    let reps = if args.quick { 2 } else { 7 };
    let texturing = interleave(
        &mut r,
        "textured vs untextured bunny scene",
        ("textured", &up_textured, k),
        ("untextured", &up_plain, k),
        size,
        reps,
    )?;
    let mask = interleave(
        &mut r,
        "masked bunny vs textured bunny",
        ("masked", &up_masked, k),
        ("textured", &up_textured, k),
        size,
        reps,
    )?;
    Ok(TexturesPart {
        texturing,
        mask,
        texture_bytes,
        device: device(&r),
    })
}
