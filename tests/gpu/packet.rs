//! The packet traversal (issue 40, `render::Traversal::Packet`): the lanes
//! of a subgroup walk the BVH together, one node at a time. It tests every
//! primitive the per-lane walk tests (and more), so its nearest hits and its
//! shadows are the same, and the image must be the per-lane image bit for
//! bit: primary rays on thousands of triangles, shadow rays to a directional
//! light, a point light, and spheres and planes beside the BVH, traced in
//! the hit stage (fused) and in the shadow stage.

use crate::support::{self, repo_scene as scene};

use penumbra::render::{Frame, KernelOptions, Sampling, Traversal};
use penumbra::scene::Scene;

fn render(scene: &Scene, traversal: Traversal) -> Frame {
    let kernel = KernelOptions {
        traversal,
        ..Default::default()
    };
    support::render_with(scene, kernel, Sampling::default())
}

/// How many pixels of two frames differ in any bit.
fn differing_pixels(a: &Frame, b: &Frame) -> usize {
    let bits = |p: &[f32; 4]| p.map(f32::to_bits);
    let (a, b) = (&a.image.pixels, &b.image.pixels);
    assert_eq!(a.len(), b.len());
    a.iter().zip(b).filter(|(x, y)| bits(x) != bits(y)).count()
}

fn assert_same_image(file: &str, scene: &Scene) {
    let per_lane = render(scene, Traversal::PerLane);
    let packet = render(scene, Traversal::Packet);
    // The packet upload carries the BVH again as storage buffers: the
    // variant ran, not a silent per-lane fallback.
    assert!(
        packet.stats.bvh_bytes > per_lane.stats.bvh_bytes,
        "{file}: {} vs {} BVH bytes",
        packet.stats.bvh_bytes,
        per_lane.stats.bvh_bytes
    );
    assert!(per_lane.stats.shadow_rays > 0, "{file}: no shadow rays");
    assert_eq!(
        per_lane.stats.shadow_rays, packet.stats.shadow_rays,
        "{file}"
    );
    let hits = per_lane.image.pixels.iter().filter(|p| p[3] == 1.0).count();
    assert!(hits > 1000, "{file}: {hits} pixels hit something");
    let differ = differing_pixels(&per_lane, &packet);
    assert_eq!(
        differ, 0,
        "{file}: {differ} pixels differ with the packet traversal"
    );
}

#[test]
fn packet_traversal_gives_the_per_lane_image_on_the_bunny() {
    // 3,676 triangles with vertex normals on a ground, a directional light.
    assert_same_image("bunny_scene.glb", &scene("bunny_scene.glb", 256, 256));
}

#[test]
fn packet_traversal_gives_the_per_lane_image_with_spheres_and_a_point_light() {
    // Spheres in the BVH beside planes, checkers, point lights.
    assert_same_image("showcase.json", &scene("showcase.json", 200, 150));
}

#[test]
fn packet_traversal_gives_the_per_lane_image_in_the_shadow_stage() {
    // 65 + 8 samples of two area lights: more than one chunk, so the shadow
    // stage, not the hit stage, traces the shadow rays.
    let mut s = scene("area_lights.json", 64, 48);
    s.lights[0].kind.set_samples(65);
    assert_same_image("area_lights.json, 73 samples", &s);
}
