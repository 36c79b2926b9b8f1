//! Image bands: an image larger than one storage-buffer binding renders in
//! bands of rows (`Renderer::set_image_band_bytes` lowers the cap so that a
//! small image shows it), and the banded image, its AOVs and a part of it
//! equal the image rendered as one band, bit for bit. A frame that reuses
//! its hit records keeps the pixels that hit nothing of its own last render,
//! also when a render of another size came between.

use crate::support;

use penumbra::render::{Frame, PartRange, Renderer, Sampling};
use penumbra::scene::Scene;

/// Puts the shared renderer's band cap back when the test ends, also when
/// it fails.
struct Capped<'a>(std::sync::MutexGuard<'a, Renderer>);

impl Drop for Capped<'_> {
    fn drop(&mut self) {
        self.0.set_image_band_bytes(u64::MAX);
    }
}

/// The showcase (checker floor, several shaders, background above the
/// horizon) at a size that is no multiple of 8 in either direction.
fn showcase() -> Scene {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/showcase.json");
    let mut scene = support::load(&path);
    scene.camera.width = 203;
    scene.camera.height = 141;
    scene.validate().expect("valid");
    scene
}

fn progressive(r: &mut Renderer, scene: &Scene, spp: u32) -> (Frame, penumbra::render::Aovs) {
    let uploaded = r.upload(scene).expect("upload");
    let sampling = Sampling {
        spp,
        ..Default::default()
    };
    let (w, h) = (scene.camera.width, scene.camera.height);
    r.render(
        &uploaded,
        penumbra::render::RenderRequest::with_aovs(w, h, &sampling, &mut |_| {}),
    )
    .map(|r| (r.frame, r.aovs.unwrap_or_default()))
    .expect("render")
}

#[test]
fn banded_images_and_aovs_equal_one_band() {
    let scene = showcase();
    let mut r = Capped(support::renderer());
    let (one, one_aovs) = progressive(&mut r.0, &scene, 3);
    // 24 rows of 203 AOVs (32 bytes each) a band: 6 bands.
    r.0.set_image_band_bytes(203 * 32 * 24);
    let (banded, banded_aovs) = progressive(&mut r.0, &scene, 3);
    assert_eq!(banded.stats.passes, 3);
    assert!(
        banded.image.pixels == one.image.pixels,
        "banded image differs"
    );
    assert_eq!(banded_aovs.depth.len(), 203 * 141);
    assert!(banded_aovs.depth == one_aovs.depth, "AOV depth differs");
    assert!(banded_aovs.normal == one_aovs.normal, "AOV normal differs");
    assert!(banded_aovs.object == one_aovs.object, "AOV object differs");
    // Some pixels hit nothing and show the background (alpha 0), some hit.
    assert!(banded.image.pixels.iter().any(|p| p[3] == 0.0));
    assert!(banded.image.pixels.iter().any(|p| p[3] == 1.0));

    // A part over rows 37..120 in bands is those rows of the whole image
    // (its pixels are sums of its 3 passes).
    let uploaded = r.0.upload_for_parts(&scene).expect("upload");
    let sampling = Sampling {
        spp: 3,
        ..Default::default()
    };
    let part = PartRange {
        rows: 37..120,
        passes: 0..3,
    };
    let got =
        r.0.render(
            &uploaded,
            penumbra::render::RenderRequest::part(uploaded.size(), &part, &sampling, &mut |_| {}),
        )
        .map(|r| r.frame)
        .expect("part");
    assert_eq!(got.image.height, 83);
    let want = &one.image.pixels[37 * 203..120 * 203];
    for (i, (g, w)) in got.image.pixels.iter().zip(want).enumerate() {
        let mean = g.map(|c| c * (1.0 / 3.0));
        assert!(mean == *w, "part pixel {i}: {mean:?} against {w:?}");
    }
}

#[test]
fn a_reused_frame_keeps_its_background_after_a_render_of_another_size() {
    let scene = showcase();
    let mut r = support::renderer();
    let mut uploaded = r.upload(&scene).expect("upload");
    let (w, h) = (scene.camera.width, scene.camera.height);
    let first = r
        .render(&uploaded, penumbra::render::RenderRequest::new(w, h))
        .map(|r| r.frame)
        .expect("render");
    // A preview of another size in between, as `watch` renders them.
    let preview = r
        .render(
            &uploaded,
            penumbra::render::RenderRequest::new(w / 2, h / 2),
        )
        .map(|r| r.frame)
        .expect("preview");
    assert_eq!(preview.image.width, w / 2);
    // No file changed: the reload recompiles nothing, and the next render of
    // the first size reuses its hit records (the hit stage, which writes
    // the background, does not run).
    r.reload_shaders(&mut uploaded, &Default::default())
        .expect("reload");
    let again = r
        .render(&uploaded, penumbra::render::RenderRequest::new(w, h))
        .map(|r| r.frame)
        .expect("render");
    assert!(again.stats.hits_reused, "the frame reuses its hit records");
    assert!(
        again.image.pixels == first.image.pixels,
        "the reused frame differs"
    );
}
