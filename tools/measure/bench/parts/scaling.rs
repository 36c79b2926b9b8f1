//! Section 3's part: frame time against triangles (procedural bumpy spheres
//! from a thousand to a million triangles, with repeated BVH builds of the
//! largest), against image size, and against the number of lights.

use std::time::Instant;

use common::{ms, Stat};
use penumbra::render::layout::GpuScene;
use penumbra::render::KernelOptions;

use crate::measure::{frames, renderer, upload};
use crate::schema::{LightPoint, ScalingPart, SizePoint, TrianglePoint};
use crate::Args;

/// The part: the three scalings in turn, in one process.
pub fn run(args: &Args) -> anyhow::Result<ScalingPart> {
    let mut r = renderer(args)?;
    let bunny = common::meshes::bunny_scene(&common::repo_root())?;
    let k = KernelOptions::default();
    let targets: &[u64] = if args.quick {
        &[1_000, 10_000, 100_000]
    } else {
        &[1_000, 3_000, 10_000, 30_000, 100_000, 300_000, 1_000_000]
    };
    let mut triangles = Vec::new();
    for &t in targets {
        let t0 = Instant::now();
        let scene = common::meshes::sphere_scene(&bunny, t);
        let scene_build = t0.elapsed();
        let up = upload(&mut r, &scene, k)?;
        let (bvh_build, upload_t) = up.upload_timings();
        let reps = if args.quick {
            2
        } else if t >= 300_000 {
            3
        } else {
            5
        };
        let (render, last) = frames(&mut r, &up, k, up.size(), 1, reps)?;
        let bvh_rebuild_ms = if Some(&t) == targets.last() {
            let mut builds = vec![ms(bvh_build)];
            for _ in 0..if args.quick { 2 } else { 6 } {
                let mut g = GpuScene::new(&scene);
                let t0 = Instant::now();
                g.build_bvh();
                builds.push(ms(t0.elapsed()));
            }
            Some(Stat::of(&builds))
        } else {
            None
        };
        eprintln!(
            "  scaling: {} triangles: build {:.0} ms, render {:.1} ms",
            scene.triangle_count(),
            ms(bvh_build),
            Stat::of(&render).median
        );
        triangles.push(TrianglePoint {
            triangles: scene.triangle_count(),
            scene_build_ms: ms(scene_build),
            bvh_build_ms: ms(bvh_build),
            upload_ms: ms(upload_t),
            bvh_nodes: last.stats.bvh_nodes,
            bvh_depth: last.stats.bvh_depth,
            bvh_bytes: last.stats.bvh_bytes,
            rays: last.stats.rays(),
            render_ms: Stat::of(&render),
            bvh_rebuild_ms,
        });
    }
    let reps = if args.quick { 2 } else { 5 };
    let up = upload(&mut r, &bunny, k)?;
    let mut pixels = Vec::new();
    for side in [128u32, 256, 512, 1024] {
        let (render, last) = frames(&mut r, &up, k, (side, side), 1, reps)?;
        pixels.push(SizePoint {
            width: side,
            height: side,
            rays: last.stats.rays(),
            render_ms: Stat::of(&render),
        });
    }
    drop(up);
    let mut lights = Vec::new();
    for count in [1usize, 2, 4, 8] {
        let scene = common::meshes::with_lights(&bunny, count);
        let up = upload(&mut r, &scene, k)?;
        let (render, last) = frames(&mut r, &up, k, up.size(), 1, reps)?;
        lights.push(LightPoint {
            lights: count,
            rays: last.stats.rays(),
            render_ms: Stat::of(&render),
        });
    }
    eprintln!("  scaling: pixels and lights done");
    Ok(ScalingPart {
        triangles,
        pixels,
        lights,
    })
}
