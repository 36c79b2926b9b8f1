//! Uploaded scenes: rendered again and at preview sizes, they give exactly
//! what a fresh render at that size gives.

use penumbra::render::{RenderError, RenderRequest};

use crate::support;

#[test]
fn preview_equals_a_render_at_that_size_and_reuse_is_exact() {
    let scene = support::load(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/showcase.json"),
    );
    let mut small = scene.clone();
    small.camera.width = 240;
    small.camera.height = 135;
    let want = support::render(&small);
    let mut r = support::renderer();
    let up = r.upload(&scene).expect("upload");
    assert_eq!(up.size(), (960, 540));
    let preview = r
        .render(&up, RenderRequest::new(240, 135))
        .map(|r| r.frame)
        .expect("preview");
    assert_eq!(preview.image, want.image);
    assert_eq!(preview.stats.primary_rays, 240 * 135);
    assert_eq!(preview.stats.shadow_rays, want.stats.shadow_rays);
    // Rendering the same upload again counts its own rays only.
    let again = r
        .render(&up, RenderRequest::new(240, 135))
        .map(|r| r.frame)
        .expect("again");
    assert_eq!(again.image, want.image);
    assert_eq!(again.stats.primary_rays, 240 * 135);
    // Larger than uploaded: a clear error.
    let err = r
        .render(&up, RenderRequest::new(961, 540))
        .map(|r| r.frame)
        .unwrap_err()
        .to_string();
    assert!(err.contains("uploaded size 960x540"), "{err}");
}

#[test]
fn cancellable_render_matches_and_stops_between_bands() {
    let scene = support::load(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/showcase.json"),
    );
    let mut r = support::renderer();
    let up = r.upload(&scene).expect("upload");
    let want = r
        .render(&up, RenderRequest::new(960, 540))
        .map(|r| r.frame)
        .expect("render");
    // Never cancelled: the same image and ray counts, asked once per band
    // of 64 rows.
    let mut asked = 0;
    let got = r
        .render(
            &up,
            RenderRequest::cancellable(960, 540, &mut || {
                asked += 1;
                false
            }),
        )
        .expect("render, not cancelled")
        .frame;
    assert_eq!(got.image, want.image);
    assert_eq!(got.stats.primary_rays, want.stats.primary_rays);
    assert_eq!(got.stats.shadow_rays, want.stats.shadow_rays);
    assert_eq!(asked, 540usize.div_ceil(64));
    // Cancelled after two bands: nothing comes back.
    let mut asked = 0;
    let got = r.render(
        &up,
        RenderRequest::cancellable(960, 540, &mut || {
            asked += 1;
            asked > 2
        }),
    );
    assert!(
        matches!(got, Err(RenderError::Cancelled)),
        "{:?}",
        got.err()
    );
    assert_eq!(asked, 3);
}
