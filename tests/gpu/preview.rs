//! Uploaded scenes: rendered again and at preview sizes, they give exactly
//! what a fresh render at that size gives.

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
    let preview = r.render_uploaded(&up, 240, 135).expect("preview");
    assert_eq!(preview.image, want.image);
    assert_eq!(preview.stats.primary_rays, 240 * 135);
    assert_eq!(preview.stats.shadow_rays, want.stats.shadow_rays);
    // Rendering the same upload again counts its own rays only.
    let again = r.render_uploaded(&up, 240, 135).expect("again");
    assert_eq!(again.image, want.image);
    assert_eq!(again.stats.primary_rays, 240 * 135);
    // Larger than uploaded: a clear error.
    let err = r.render_uploaded(&up, 961, 540).unwrap_err().to_string();
    assert!(err.contains("uploaded size 960x540"), "{err}");
}

#[test]
fn cancellable_render_matches_and_stops_between_bands() {
    let scene = support::load(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/showcase.json"),
    );
    let mut r = support::renderer();
    let up = r.upload(&scene).expect("upload");
    let want = r.render_uploaded(&up, 960, 540).expect("render");
    // Never cancelled: the same image and ray counts, asked once per band
    // of 64 rows.
    let mut asked = 0;
    let got = r
        .render_cancellable(&up, 960, 540, &mut || {
            asked += 1;
            false
        })
        .expect("render")
        .expect("not cancelled");
    assert_eq!(got.image, want.image);
    assert_eq!(got.stats.primary_rays, want.stats.primary_rays);
    assert_eq!(got.stats.shadow_rays, want.stats.shadow_rays);
    assert_eq!(asked, 540usize.div_ceil(64));
    // Cancelled after two bands: nothing comes back.
    let mut asked = 0;
    let got = r
        .render_cancellable(&up, 960, 540, &mut || {
            asked += 1;
            asked > 2
        })
        .expect("render");
    assert!(got.is_none());
    assert_eq!(asked, 3);
}
