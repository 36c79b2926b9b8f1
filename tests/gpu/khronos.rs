//! Real assets: the Khronos glTF sample models committed in
//! tests/data/khronos (see its README), loaded by the glTF loader and
//! rendered on the GPU.
//!
//! BoxTextured is a cube with the Cesium logo as its base colour texture
//! (PNG, embedded as a data URI, trilinear and repeating, texture
//! coordinates up to 6 along u). It must render its texture: the render
//! agrees with the f64 reference (an independent implementation of the same
//! sampling, tests/gpu/reference.rs's rule: 99.5 % of pixels within 2e-3),
//! and its lit faces show the logo's colours, many distinct ones, where an
//! untextured cube would show one flat colour per face.

use crate::support;

use std::collections::HashSet;
use std::path::Path;

use penumbra::loaders::{self, LoadOptions};
use penumbra::scene::Shader;

#[test]
fn box_textured_renders_its_texture() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/khronos/BoxTextured/BoxTextured.gltf");
    let opts = LoadOptions {
        width: Some(96),
        height: Some(72),
        ..Default::default()
    };
    let loaded = loaders::load_scene(&path, &opts).unwrap_or_else(|e| panic!("{e}"));
    let scene = loaded.scene;
    assert_eq!(scene.textures.len(), 1);
    assert_eq!(
        (scene.textures[0].width, scene.textures[0].height),
        (211, 211)
    );
    assert!(scene.textures[0].srgb);
    let Shader::Phong(p) = &scene.shaders[scene.objects[0].shader] else {
        panic!("glTF materials are Phong");
    };
    assert!(p.textures.diffuse.is_some());

    let kernel = support::renderer().kernel();
    let sampling = penumbra::render::Sampling::default();
    let gpu = support::render_with(&scene, kernel, sampling);
    let reference = penumbra::reference::render(&scene, &sampling, &kernel);
    let mut over = 0;
    for (a, b) in gpu.image.pixels.iter().zip(&reference.image.pixels) {
        let d = (0..3)
            .map(|c| (f64::from(a[c]) - f64::from(b[c])).abs())
            .fold(0.0, f64::max);
        if d > 2e-3 {
            over += 1;
        }
    }
    let n = gpu.image.pixels.len();
    assert!(
        over as f64 <= 0.005 * n as f64,
        "{over} of {n} pixels differ from the reference by more than 2e-3"
    );
    // Distinct colours (to 1/256) among the hit pixels: a flat-shaded cube
    // has at most one per visible face (three).
    let colours: HashSet<[u8; 3]> = gpu
        .image
        .pixels
        .iter()
        .filter(|p| p[3] > 0.0)
        .map(|p| std::array::from_fn(|c| (p[c].clamp(0.0, 1.0) * 255.0) as u8))
        .collect();
    assert!(
        colours.len() > 50,
        "only {} distinct colours",
        colours.len()
    );
}
