//! Section 2's part: the seminar's claim that the u,v-first triangle test
//! beats the t-first one, with brute force and with the BVH, the BVH's
//! speed-up over brute force, and the default watertight test against the
//! seminar's; every comparison a run of interleaved pairs.

use penumbra::render::{Accel, TriangleTest};

use crate::measure::{interleave, kernel, renderer, upload};
use crate::schema::SeminarPart;
use crate::Args;

/// The part: four interleaved comparisons on the bunny scene.
pub fn run(args: &Args) -> anyhow::Result<SeminarPart> {
    let mut r = renderer(args)?;
    let bunny = common::meshes::bunny_scene(&common::repo_root())?;
    let (uv, tf) = (TriangleTest::UvFirst, TriangleTest::TFirst);
    let brute = upload(&mut r, &bunny, kernel(Accel::BruteForce, uv))?;
    let bvh = upload(&mut r, &bunny, kernel(Accel::Bvh, uv))?;
    let small = if args.quick { (64, 64) } else { (256, 256) };
    let full = bvh.size();
    let (brute_reps, reps) = if args.quick { (1, 2) } else { (3, 5) };
    let uv_vs_t_brute = interleave(
        &mut r,
        "brute force, u,v-first vs t-first",
        ("u,v-first", &brute, kernel(Accel::BruteForce, uv)),
        ("t-first", &brute, kernel(Accel::BruteForce, tf)),
        small,
        brute_reps,
    )?;
    let uv_vs_t_bvh = interleave(
        &mut r,
        "BVH, u,v-first vs t-first",
        ("u,v-first", &bvh, kernel(Accel::Bvh, uv)),
        ("t-first", &bvh, kernel(Accel::Bvh, tf)),
        full,
        reps,
    )?;
    let bvh_vs_brute = interleave(
        &mut r,
        "brute force vs BVH (u,v-first)",
        ("brute force", &brute, kernel(Accel::BruteForce, uv)),
        ("BVH", &bvh, kernel(Accel::Bvh, uv)),
        small,
        brute_reps,
    )?;
    let watertight_vs_uv_bvh = interleave(
        &mut r,
        "BVH, watertight (the default) vs u,v-first",
        (
            "watertight",
            &bvh,
            kernel(Accel::Bvh, TriangleTest::Watertight),
        ),
        ("u,v-first", &bvh, kernel(Accel::Bvh, uv)),
        full,
        reps,
    )?;
    Ok(SeminarPart {
        uv_vs_t_brute,
        uv_vs_t_bvh,
        bvh_vs_brute,
        watertight_vs_uv_bvh,
    })
}
