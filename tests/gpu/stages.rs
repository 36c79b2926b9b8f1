//! The stages of a frame (issue 13): when one chunk holds every light
//! sample of a pixel, the hit stage traces the shadow rays itself and the
//! shadow stage does not run (`render::Settings::fused_shadows`). The image
//! must be the one the shadow stage gives, bit for bit: both paths sample
//! the same lights with the same random numbers from the same hit. On
//! lavapipe the stages write their records as storage-buffer words over the
//! memory of the texel images the next stage reads
//! (`render::Settings::stage_words`); that image must equal the one written
//! with texel stores, bit for bit. There, too, an invocation finds its pixel
//! by its subgroup and lane (`render::Settings::lane_pixels`); that image
//! must equal the one placed by the invocation's index, bit for bit.

use crate::support::{self, repo_scene as scene};

use penumbra::render::{Frame, Renderer};
use penumbra::scene::Scene;

/// Restores fusion and unprofiled frames when the test ends, also when it
/// fails, so that the other tests of this binary are not affected.
struct Restore<'a>(std::sync::MutexGuard<'a, Renderer>);

impl Drop for Restore<'_> {
    fn drop(&mut self) {
        self.0.set_fused_shadows(true);
        self.0.set_stage_words(true);
        self.0.set_lane_pixels(true);
        self.0.set_profile_stages(false);
    }
}

/// Renders `scene` with fusion on or off, each dispatch timed so that the
/// frame names the pipelines that ran.
fn render(r: &mut Restore, scene: &Scene, fused: bool) -> Frame {
    r.0.set_fused_shadows(fused);
    r.0.set_profile_stages(true);
    r.0.render_scene(scene).expect("render")
}

/// Renders `scene` with the records written as words or with texel stores.
fn render_words(r: &mut Restore, scene: &Scene, words: bool) -> Frame {
    r.0.set_stage_words(words);
    assert_eq!(
        r.0.stage_words(),
        words,
        "words where the device allows them"
    );
    let frame = r.0.render_scene(scene).expect("render");
    r.0.set_stage_words(true);
    frame
}

fn stages(f: &Frame) -> Vec<&str> {
    f.stage_times
        .iter()
        .map(|(name, _)| name.as_str())
        .collect()
}

/// How many pixels of two frames differ in any bit.
fn differing_pixels(a: &Frame, b: &Frame) -> usize {
    let bits = |p: &[f32; 4]| p.map(f32::to_bits);
    let (a, b) = (&a.image.pixels, &b.image.pixels);
    assert_eq!(a.len(), b.len());
    a.iter().zip(b).filter(|(x, y)| bits(x) != bits(y)).count()
}

#[test]
fn fused_shadow_rays_give_the_shadow_stages_image() {
    // Triangles with vertex normals and a point light; planes, spheres,
    // checkers and point lights; two area lights of 16 and 8 samples;
    // textures, normal maps and alpha cut-outs; user shaders.
    let cases = [
        "bunny_scene.glb",
        "showcase.json",
        "area_lights.json",
        "textured.json",
        "shaders.json",
    ];
    let mut r = Restore(support::renderer());
    for file in cases {
        let scene = scene(file, 160, 120);
        let fused = render(&mut r, &scene, true);
        let staged = render(&mut r, &scene, false);
        let names = stages(&fused);
        assert_eq!(names[0], "hit", "{file}: {names:?}");
        assert!(!names.contains(&"shadow"), "{file} fused: {names:?}");
        assert_eq!(stages(&staged)[..2], ["hit", "shadow"], "{file}");
        assert_eq!(fused.stats.primary_rays, 160 * 120, "{file}");
        assert_eq!(fused.stats.shadow_rays, staged.stats.shadow_rays, "{file}");
        // Every case lights something, so the comparison covers shadow rays.
        assert!(fused.stats.shadow_rays > 0, "{file}: no shadow rays");
        let differ = differing_pixels(&fused, &staged);
        assert_eq!(
            differ, 0,
            "{file}: {differ} pixels differ without the shadow stage"
        );
    }
}

#[test]
fn more_samples_than_one_chunk_run_the_shadow_stage() {
    // 65 + 8 samples of the two area lights: two chunks, so the hit stage
    // cannot hold them and the shadow stage runs once per chunk.
    let mut scene = scene("area_lights.json", 64, 48);
    assert!(scene.lights[0].kind.is_area());
    scene.lights[0].kind.set_samples(65);
    let mut r = Restore(support::renderer());
    let frame = render(&mut r, &scene, true);
    assert_eq!(stages(&frame)[..2], ["hit", "shadow"]);
    assert!(frame.stats.shadow_rays > 0);
}

#[test]
fn records_written_as_words_give_the_texel_stores_image() {
    let mut r = Restore(support::renderer());
    // lavapipe's linear images alias buffers; the words are its default.
    let cpu = r.0.device().device_type == "CPU";
    assert_eq!(r.0.stage_words(), cpu, "{:?}", r.0.device());
    // Fused shadows (one chunk) and the shadow stage's queue (two chunks,
    // its second light's samples across the boundary), with checkers, user
    // shaders and textures.
    let mut two_chunks = scene("area_lights.json", 96, 64);
    two_chunks.lights[0].kind.set_samples(70);
    let cases = [
        ("showcase.json", scene("showcase.json", 160, 120)),
        ("area_lights.json, 78 samples", two_chunks),
        ("textured.json", scene("textured.json", 160, 120)),
        ("shaders.json", scene("shaders.json", 160, 120)),
    ];
    for (what, scene) in cases {
        let words = render_words(&mut r, &scene, cpu);
        let texels = render_words(&mut r, &scene, false);
        assert!(words.stats.shadow_rays > 0, "{what}: no shadow rays");
        let differ = differing_pixels(&words, &texels);
        assert_eq!(
            differ, 0,
            "{what}: {differ} pixels differ with texel stores"
        );
    }
}

#[test]
fn pixels_by_subgroup_and_lane_give_the_invocation_index_image() {
    let mut r = Restore(support::renderer());
    // lavapipe's subgroups fill a workgroup in order; its default.
    let cpu = r.0.device().device_type == "CPU";
    assert_eq!(r.0.lane_pixels(), cpu, "{:?}", r.0.device());
    // Every stage: fused shadows (one chunk) and the shadow stage (two
    // chunks), several shade programs, textures; sizes that are not whole
    // 8×8 blocks.
    let mut two_chunks = scene("area_lights.json", 93, 61);
    two_chunks.lights[0].kind.set_samples(70);
    let cases = [
        ("showcase.json", scene("showcase.json", 157, 118)),
        ("area_lights.json, 78 samples", two_chunks),
        ("textured.json", scene("textured.json", 160, 120)),
        ("shaders.json", scene("shaders.json", 101, 77)),
    ];
    for (what, scene) in cases {
        let mut frame = |lanes: bool| {
            r.0.set_lane_pixels(lanes);
            assert_eq!(r.0.lane_pixels(), lanes && cpu);
            r.0.render_scene(&scene).expect("render")
        };
        let lanes = frame(cpu);
        let index = frame(false);
        assert!(lanes.stats.shadow_rays > 0, "{what}: no shadow rays");
        assert!(lanes.image.pixels.iter().any(|p| p[3] > 0.0), "{what}");
        let differ = differing_pixels(&lanes, &index);
        assert_eq!(
            differ, 0,
            "{what}: {differ} pixels differ from the index's placement"
        );
    }
}

#[test]
fn without_checkers_the_shade_stage_finds_the_leaf_that_resolve_would() {
    // Without checkers the hit stage writes no resolved material and the
    // shade stage reads each hit's leaf from the shader table. Two scenes
    // shade every point alike: shaders.json (built-in and user shaders,
    // several programs) with its checker floor replaced by the checker's
    // even leaf, and with a checker whose cells are both that leaf, which
    // material resolve walks. Their images must agree, bit for bit.
    use penumbra::scene::Shader;
    let base = scene("shaders.json", 160, 120);
    let (at, checker) = base
        .shaders
        .iter()
        .enumerate()
        .find_map(|(i, s)| match s {
            Shader::Checker(c) => Some((i, *c)),
            _ => None,
        })
        .expect("shaders.json has a checker");
    assert!(
        base.objects.iter().any(|o| o.shader == at),
        "an object uses the checker"
    );
    let mut leaf = base.clone();
    leaf.shaders[at] = base.shaders[checker.even].clone();
    let mut walked = base.clone();
    walked.shaders[at] = Shader::Checker(penumbra::scene::Checker {
        odd: checker.even,
        ..checker
    });
    leaf.validate().expect("valid");
    walked.validate().expect("valid");
    assert!(!leaf.features().checker);
    assert!(walked.features().checker);
    let mut r = Restore(support::renderer());
    let a = render(&mut r, &leaf, true);
    let b = render(&mut r, &walked, true);
    assert!(a.stats.shadow_rays > 0, "no shadow rays");
    // Several shade programs, so a leaf's program decides which pipeline
    // shades a pixel.
    let shade = stages(&a).iter().filter(|n| n.starts_with("shade")).count();
    assert!(shade >= 3, "{:?}", stages(&a));
    let differ = differing_pixels(&a, &b);
    assert_eq!(differ, 0, "{differ} pixels differ between the two paths");
}
