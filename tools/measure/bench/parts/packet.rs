//! The packet traversal's part (issue 40): the bunny rendered with the
//! lanes of a subgroup walking the BVH together
//! (`Traversal::Packet`, `PACKET_TRAVERSAL` in shaders/bvh.wgsl) against the
//! default per-lane walk, interleaved in one run. The variant is off by
//! default; this part reports its ratio every run (docs/stages.md says why
//! it is kept).

use penumbra::render::{KernelOptions, Traversal};

use crate::measure::{interleave, renderer, upload};
use crate::schema::PacketPart;
use crate::Args;

/// The part: one upload per traversal (the packet one carries the BVH as
/// storage buffers too), then interleaved frames.
pub fn run(args: &Args) -> anyhow::Result<PacketPart> {
    let mut r = renderer(args)?;
    let bunny = common::meshes::bunny_scene(&common::repo_root())?;
    let per_lane = KernelOptions::default();
    let packet = KernelOptions {
        traversal: Traversal::Packet,
        ..per_lane
    };
    let up_lane = upload(&mut r, &bunny, per_lane)?;
    let up_packet = upload(&mut r, &bunny, packet)?;
    let (w, h) = up_lane.size();
    let reps = if args.quick { 2 } else { 9 };
    let bunny = interleave(
        &mut r,
        "bunny, packet vs per-lane traversal",
        ("packet", &up_packet, packet),
        ("per-lane", &up_lane, per_lane),
        (w, h),
        reps,
    )?;
    Ok(PacketPart { bunny })
}
