//! Uploaded scenes: rendered again and at preview sizes, they give exactly
//! what a fresh render at that size gives.

mod support;

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
