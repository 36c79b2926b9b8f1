//! Bounded stage memory (issue 13): hit records, colour sums and queued
//! light samples live in buffers sized for one tile, so that any image the
//! CLI allows, with any number of light samples, renders within the bound
//! set by `Renderer::set_stage_memory`, and the tiled image is the same, bit
//! for bit, as the image rendered in fewer, larger tiles.

use crate::support;

use penumbra::render::tiles::{self, TilePlan};
use penumbra::render::{Frame, Renderer};
use penumbra::scene::{Scene, MAX_IMAGE_SIDE};
use serde_json::json;

/// Restores the shared renderer's default bound when the test ends, also
/// when it fails, so that the other tests of this binary are not affected.
struct Bound<'a>(std::sync::MutexGuard<'a, Renderer>);

impl Drop for Bound<'_> {
    fn drop(&mut self) {
        self.0.set_stage_memory(tiles::DEFAULT_STAGE_MEMORY);
    }
}

impl Bound<'_> {
    fn render(&mut self, scene: &Scene, bound: u64) -> Frame {
        self.0.set_stage_memory(bound);
        assert_eq!(self.0.stage_memory(), bound);
        let frame = self.0.render_scene(scene).expect("render");
        let stats = &frame.stats;
        assert!(
            stats.stage_bytes <= bound,
            "bound {bound}: the tiles took {} bytes",
            stats.stage_bytes
        );
        frame
    }
}

/// 1024×768 with two rectangle lights of 36 samples each: 72 samples per
/// pixel are two chunks of `tiles::MAX_CHUNK` (64 + 8), and the second
/// light's samples straddle the chunk boundary. The upper part of the
/// image is background, which keeps the shadow rays (and the run time on
/// lavapipe) down. A built-in Phong checker
/// floor, a Blinn-Phong sphere and a sphere with a user shader (its file
/// lives in the returned folder, which the renderer reads).
fn big_soft_scene() -> (tempfile::TempDir, Scene) {
    let (w, h) = (1024, 768);
    let scene = json!({
        "camera": {"position": [0, 1.2, 6], "look_at": [0, 0.9, 0], "fov": 40, "width": w, "height": h},
        "background": [0.1, 0.2, 0.3],
        "shaders": {
            "light": {"type": "phong", "ambient": [0.8, 0.8, 0.8], "diffuse": [0.8, 0.8, 0.75]},
            "dark": {"type": "phong", "ambient": [0.3, 0.3, 0.35], "diffuse": [0.3, 0.3, 0.35]},
            "floor": {"type": "checker", "size": 1.0, "even": "light", "odd": "dark"},
            "blue": {"type": "blinn_phong", "ambient": [0.1, 0.2, 0.8], "diffuse": [0.1, 0.2, 0.8],
                     "specular": [0.5, 0.5, 0.5], "shininess": 20},
            "user": {"type": "wgsl", "file": "lambert.wgsl", "params": {"base": [0.9, 0.4, 0.2]}}
        },
        "objects": [
            {"type": "plane", "point": [0, 0, 0], "normal": [0, 1, 0], "shader": "floor"},
            {"type": "sphere", "center": [-1, 0.8, 0], "radius": 0.8, "shader": "blue"},
            {"type": "sphere", "center": [1.1, 0.6, 0.5], "radius": 0.6, "shader": "user"}
        ],
        "lights": [
            {"type": "rect", "corner": [-3, 3, -1], "edge1": [1.5, 0, 0], "edge2": [0, 0, 1.5],
             "intensity": 12, "samples": 36, "ambient": [0.05, 0.05, 0.05]},
            {"type": "rect", "corner": [2, 2.5, 1], "edge1": [0, 0, 1], "edge2": [1, 0, 0],
             "intensity": 6, "samples": 36, "diffuse": [0.6, 0.7, 1.0]}
        ]
    });
    let (dir, path) =
        support::write_scene(&serde_json::to_string_pretty(&scene).expect("scene JSON"));
    std::fs::write(
        dir.path().join("lambert.wgsl"),
        "struct Params { base: vec3<f32> }\n\
         fn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32> {\n\
         \x20   return p.base * l.diffuse * l.intensity * dot(l.to_light, s.normal);\n\
         }\n",
    )
    .expect("write shader");
    let scene = support::load(&path);
    scene.validate().expect("valid");
    (dir, scene)
}

/// The image's pixels as bits.
fn bits(f: &Frame) -> Vec<[u32; 4]> {
    f.image.pixels.iter().map(|p| p.map(f32::to_bits)).collect()
}

#[test]
fn many_area_light_samples_in_small_tiles_equal_the_larger_tiles() {
    let (_dir, scene) = big_soft_scene();
    let mut r = Bound(support::renderer());
    let large = r.render(&scene, tiles::DEFAULT_STAGE_MEMORY);
    // 1 MiB: tiles of under 1000 pixels (a record of 64 bytes, 16 more
    // with checkers, a colour sum of 16 and 64 queued samples of 16 each).
    let small = r.render(&scene, 1 << 20);
    eprintln!(
        "tiles: {} (default bound, {} bytes), {} (1 MiB, {} bytes); render {:?} / {:?}",
        large.stats.tiles,
        large.stats.stage_bytes,
        small.stats.tiles,
        small.stats.stage_bytes,
        large.stats.timings.render,
        small.stats.timings.render,
    );
    // 1024×768 with a full chunk does not fit 128 MiB in one tile (1.1 GB).
    assert!(large.stats.tiles > 1);
    assert!(small.stats.tiles > 10 * large.stats.tiles);
    // Every primary ray and every shadow ray is traced once, in any tiling.
    assert_eq!(large.stats.primary_rays, 1024 * 768);
    assert_eq!(small.stats.primary_rays, large.stats.primary_rays);
    assert_eq!(small.stats.shadow_rays, large.stats.shadow_rays);
    // Bit for bit the same image.
    let want = bits(&large);
    let differ = bits(&small)
        .iter()
        .zip(&want)
        .filter(|(a, b)| a != b)
        .count();
    assert_eq!(differ, 0, "{differ} pixels differ from the default bound");
    // Soft shadows: the picture has many distinct colours, so equality
    // means something.
    let mut reds: Vec<u32> = want.iter().map(|p| p[0]).collect();
    reds.sort_unstable();
    reds.dedup();
    assert!(reds.len() > 1000, "{} distinct reds", reds.len());
}

#[test]
fn the_minimum_bound_gives_8x8_tiles_and_the_image_of_one_tile() {
    // 150×90 with 72 samples fits the default bound in one tile; the
    // minimum bound holds one 8×8 tile with a full chunk, and the tiles at
    // the right and bottom edges are smaller (150 = 18·8 + 6, 90 = 11·8 + 2).
    let (_dir, mut scene) = big_soft_scene();
    scene.camera.width = 150;
    scene.camera.height = 90;
    let mut r = Bound(support::renderer());
    let one = r.render(&scene, tiles::DEFAULT_STAGE_MEMORY);
    assert_eq!(one.stats.tiles, 1);
    let many = r.render(&scene, tiles::MIN_STAGE_MEMORY);
    assert_eq!(many.stats.tiles, 19 * 12);
    assert_eq!(many.stats.stage_bytes, tiles::MIN_STAGE_MEMORY);
    assert_eq!(many.stats.shadow_rays, one.stats.shadow_rays);
    let differ = bits(&one)
        .iter()
        .zip(&bits(&many))
        .filter(|(a, b)| a != b)
        .count();
    assert_eq!(
        differ, 0,
        "{differ} pixels of 8×8 tiles differ from one tile"
    );
}

#[test]
fn the_bound_holds_for_the_largest_image_the_cli_allows() {
    let side = MAX_IMAGE_SIDE;
    let max_samples = penumbra::scene::MAX_LIGHT_SAMPLES;
    // Up to 64 area lights of the most samples each, and the buffer limits
    // of small and large devices.
    for samples in [0, 1, 63, 64, 65, max_samples, 64 * max_samples] {
        for bound in [
            tiles::MIN_STAGE_MEMORY,
            tiles::MIN_STAGE_MEMORY + 1,
            1 << 20,
            tiles::DEFAULT_STAGE_MEMORY,
            4 << 30,
        ] {
            for (max_buffer, resolved) in [128 << 20, u32::MAX as u64]
                .into_iter()
                .flat_map(|m| [(m, false), (m, true)])
            {
                let plan = TilePlan::new([side, side], samples, resolved, bound, max_buffer);
                let why = format!(
                    "{samples} samples, bound {bound}, max buffer {max_buffer}, resolved {resolved}"
                );
                assert!(plan.bytes() <= bound, "{why}: {} bytes", plan.bytes());
                assert!(plan.tile.iter().all(|t| t.is_multiple_of(8)), "{why}");
                assert!(plan.chunk >= 1 && plan.chunk <= tiles::MAX_CHUNK, "{why}");
                // No buffer of the plan is larger than the device allows:
                // hit records, and queued rays (16 bytes per sample).
                let largest = tiles::RECORD_BYTES.max(plan.chunk as u64 * 16);
                assert!(plan.pixels() * largest <= max_buffer, "{why}");
                let covered: u64 = plan
                    .tiles(side, 0..side)
                    .iter()
                    .map(|(_, s)| s[0] as u64 * s[1] as u64)
                    .sum();
                assert_eq!(covered, side as u64 * side as u64, "{why}");
                let chunked: u32 = plan.chunks().iter().map(|c| c.1).sum();
                assert_eq!(chunked, samples, "{why}");
            }
        }
    }
}
