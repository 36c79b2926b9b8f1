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
//!
//! The Duck (Sony's, under the SCEA Shared Source License) renders its
//! texture through its own camera: the same agreement with the reference,
//! and the texture's yellow body and orange beak where its white material
//! alone would be grey.
//!
//! TextureCoordinateTest shows each labelled corner of its texture on the
//! quad named after it, upright: the test checks the render against its own
//! decoding of the PNG at the uv the model's README prescribes, and against
//! the same corner flipped (see the test's docs).
//!
//! TextureSettingsTest's wrap rows (repeat, mirrored repeat, clamp to edge,
//! along S and T) show its green check marks and no red crosses, as its
//! Sample quads do.

use crate::support;

use std::collections::HashSet;
use std::path::Path;

use penumbra::loaders::{self, LoadOptions};
use penumbra::scene::Shader;

/// Loads the committed model `rel` at `width`×`height` (its own camera, or
/// the framing one), checks that its one texture is the `size` sRGB image
/// its material's base colour reads, and renders it on the GPU,
/// which must agree with the f64 reference (an independent implementation
/// of the same sampling, tests/gpu/reference.rs's rule: 99.5 % of pixels
/// within 2e-3). Returns the GPU's hit pixels.
fn render_textured_model(rel: &str, width: u32, height: u32, size: (u32, u32)) -> Vec<[f32; 4]> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(rel);
    let opts = LoadOptions {
        width: Some(width),
        height: Some(height),
        ..Default::default()
    };
    let loaded = loaders::load_scene(&path, &opts).unwrap_or_else(|e| panic!("{e}"));
    let scene = loaded.scene;
    assert_eq!(scene.textures.len(), 1, "{rel}");
    assert_eq!(
        (scene.textures[0].width, scene.textures[0].height),
        size,
        "{rel}"
    );
    assert!(scene.textures[0].srgb, "{rel}");
    let Shader::MetallicRoughness(m) = &scene.shaders[scene.objects[0].shader] else {
        panic!("glTF materials are glTF's metallic-roughness model");
    };
    assert!(m.textures.base_colour.is_some(), "{rel}");

    let kernel = support::renderer().kernel();
    let sampling = penumbra::render::Sampling::default();
    let gpu = support::render_with(&scene, kernel, sampling);
    let reference = penumbra::reference::render(&scene, &sampling, kernel.sampler);
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
        "{rel}: {over} of {n} pixels differ from the reference by more than 2e-3"
    );
    gpu.image
        .pixels
        .iter()
        .filter(|p| p[3] > 0.0)
        .copied()
        .collect()
}

/// Distinct colours (to 1/256) among `pixels`.
fn distinct_colours(pixels: &[[f32; 4]]) -> usize {
    let colours: HashSet<[u8; 3]> = pixels
        .iter()
        .map(|p| std::array::from_fn(|c| (p[c].clamp(0.0, 1.0) * 255.0) as u8))
        .collect();
    colours.len()
}

#[test]
fn box_textured_renders_its_texture() {
    let hits = render_textured_model(
        "tests/data/khronos/BoxTextured/BoxTextured.gltf",
        96,
        72,
        (211, 211),
    );
    // A flat-shaded cube has at most one colour per visible face (three).
    let colours = distinct_colours(&hits);
    assert!(colours > 50, "only {colours} distinct colours");
}

/// The Duck, through its own camera (the file has no lights, so the
/// default lights follow that camera), shows its texture: a yellow body
/// with an orange beak and a dark eye. Its material's baseColorFactor is
/// the default white, so without the texture every lit pixel would be a
/// shade of grey (red = green = blue); with it, most are yellow (red and
/// green well above blue), and some are orange (red well above green).
#[test]
fn duck_renders_its_texture_through_its_own_camera() {
    let hits = render_textured_model("tests/data/khronos/Duck/Duck.gltf", 180, 120, (512, 512));
    assert!(hits.len() > 500, "{} hit pixels", hits.len());
    let colours = distinct_colours(&hits);
    assert!(colours > 50, "only {colours} distinct colours");
    let lit: Vec<_> = hits.iter().filter(|p| p[0] > 0.05).collect();
    let yellow = lit
        .iter()
        .filter(|p| p[1] > 0.4 * p[0] && p[2] < 0.2 * p[1])
        .count();
    let orange = lit
        .iter()
        .filter(|p| p[1] < 0.4 * p[0] && p[2] < 0.2 * p[0])
        .count();
    eprintln!(
        "{} hits, {} lit, {yellow} yellow, {orange} orange",
        hits.len(),
        lit.len()
    );
    assert!(
        yellow * 10 >= lit.len() * 7,
        "{yellow} of {} lit pixels yellow",
        lit.len()
    );
    assert!(
        orange * 100 >= lit.len(),
        "{orange} of {} lit pixels orange",
        lit.len()
    );
}

/// One quad of TextureCoordinateTest as the model's README and accessor names
/// describe it, seen from −z (the side its quads face): the quad covers
/// `x ∈ [x0, x0 + 1]`, `y ∈ [y0, y0 + 1]` and shows the texture's corner
/// `[u0, u0 + 0.4] × [v0, v0 + 0.4]` upright, with uv (0, 0) at the image's
/// top-left as glTF defines it. Seen from −z, +x is on the left, so the
/// quad's top-left corner (x0 + 1, y0 + 1) shows (u0, v0).
struct TctQuad {
    name: &'static str,
    x0: f64,
    y0: f64,
    u0: f64,
    v0: f64,
    /// The colour channel that the material's baseColorFactor passes at 1.
    channel: usize,
}

const TCT_QUADS: [TctQuad; 4] = [
    TctQuad {
        name: "TopLeft",
        x0: 0.2,
        y0: 0.2,
        u0: 0.0,
        v0: 0.0,
        channel: 0,
    },
    TctQuad {
        name: "TopRight",
        x0: -1.2,
        y0: 0.2,
        u0: 0.6,
        v0: 0.0,
        channel: 0,
    },
    TctQuad {
        name: "BottomLeft",
        x0: 0.2,
        y0: -1.2,
        u0: 0.0,
        v0: 0.6,
        channel: 2,
    },
    TctQuad {
        name: "BottomRight",
        x0: -1.2,
        y0: -1.2,
        u0: 0.6,
        v0: 0.6,
        channel: 1,
    },
];

/// Fraction of the variance of `y` that the least-squares line `a + b·x`
/// explains (the coefficient of determination R²), and the slope b.
fn r_squared(x: &[f64], y: &[f64]) -> (f64, f64) {
    let n = x.len() as f64;
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let sxy: f64 = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = x.iter().map(|a| (a - mx) * (a - mx)).sum();
    let syy: f64 = y.iter().map(|b| (b - my) * (b - my)).sum();
    (sxy * sxy / (sxx * syy), sxy / sxx)
}

/// TextureCoordinateTest (Khronos): four quads, each showing one labelled
/// corner of a 512² texture ("Top Left", …, with checkered brackets and
/// crosses), must show it upright: the glTF uv origin is the image's
/// top-left. Each quad is rendered head-on through an orthographic camera
/// framing uv `[u0 + 0.05, u0 + 0.35] × [v0 + 0.05, v0 + 0.35]` of its
/// corner at 1.3 pixels per texel, under one directional light. The texture
/// is magnified there, so the lookup is glTF's linear magFilter at mip
/// level 0, and normal, light and view are constant over the quad: in the
/// channel that the quad's baseColorFactor passes, a pixel is an affine
/// function of the texture bilinearly interpolated at the pixel's uv. The
/// test decodes the PNG itself and interpolates it (in linear colour, after
/// sRGB decoding) at the uv that the README prescribes; the render must
/// follow that, R² ≥ 0.99 (what 16-bit texels and f32 arithmetic leave),
/// and must not follow the corner flipped in u, in v or in both (each R²
/// below 0.5): a flipped or mirrored convention in the loader fails. Each
/// render also agrees with the f64 reference like BoxTextured.
#[test]
fn texture_coordinate_test_is_upright() {
    use glam::{DVec3, Vec3};
    use penumbra::scene::{Camera, Light, LightKind, Projection};

    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/khronos/TextureCoordinateTest/TextureCoordinateTest.gltf");
    const SIZE: u32 = 200;
    // Half the window: 0.15 of uv, 0.375 world units (a quad's 0.4 of uv spans 1).
    const HALF: f64 = 0.375;
    let opts = LoadOptions {
        width: Some(SIZE),
        height: Some(SIZE),
        ..Default::default()
    };
    let mut scene = loaders::load_scene(&path, &opts)
        .unwrap_or_else(|e| panic!("{e}"))
        .scene;
    assert_eq!(scene.textures.len(), 1);
    scene.lights = vec![Light {
        kind: LightKind::Directional {
            direction: DVec3::new(0.2, 0.3, 1.0).normalize(),
        },
        intensity: 1.0,
        ambient: Vec3::splat(0.05),
        diffuse: Vec3::ONE,
        specular: Vec3::ONE,
    }];

    // The texture, decoded here from the file's data URI, in linear colour.
    let text = std::fs::read_to_string(&path).expect("read");
    let json: serde_json::Value = serde_json::from_str(&text).expect("json");
    let uri = json["images"][0]["uri"].as_str().expect("image uri");
    let png = crate::base64::decode(uri.strip_prefix("data:image/png;base64,").expect("png uri"));
    let tex = image::load_from_memory(&png).expect("png").to_rgba8();
    assert_eq!(tex.dimensions(), (512, 512));
    let linear: Vec<f64> = tex
        .pixels()
        .map(|p| penumbra::scene::texture::srgb_to_linear(p[0]))
        .collect();
    // Bilinear interpolation between texel centres, repeating (the sampler's wrap).
    let bilinear = |u: f64, v: f64| -> f64 {
        let (s, t) = (u * 512.0 - 0.5, v * 512.0 - 0.5);
        let (i, j) = (s.floor(), t.floor());
        let (fs, ft) = (s - i, t - j);
        let at = |i: f64, j: f64| {
            linear[(j.rem_euclid(512.0) as usize) * 512 + i.rem_euclid(512.0) as usize]
        };
        (1.0 - ft) * ((1.0 - fs) * at(i, j) + fs * at(i + 1.0, j))
            + ft * ((1.0 - fs) * at(i, j + 1.0) + fs * at(i + 1.0, j + 1.0))
    };

    let kernel = support::renderer().kernel();
    let sampling = penumbra::render::Sampling::default();
    for q in &TCT_QUADS {
        let centre = DVec3::new(q.x0 + 0.5, q.y0 + 0.5, 0.0);
        let eye = centre - DVec3::new(0.0, 0.0, 5.0);
        scene.camera = Camera {
            position: eye,
            orientation: Camera::look_at(eye, centre, DVec3::Y).expect("orientation"),
            projection: Projection::Orthographic { half_height: HALF },
            width: SIZE,
            height: SIZE,
        };
        let gpu = support::render_with(&scene, kernel, sampling);
        let reference = penumbra::reference::render(&scene, &sampling, kernel.sampler);
        let n = gpu.image.pixels.len();
        let over = gpu
            .image
            .pixels
            .iter()
            .zip(&reference.image.pixels)
            .filter(|(a, b)| (0..3).any(|c| (f64::from(a[c]) - f64::from(b[c])).abs() > 2e-3))
            .count();
        assert!(
            over as f64 <= 0.005 * n as f64,
            "{}: {over} of {n} pixels differ from the reference by more than 2e-3",
            q.name
        );

        let (mut rendered, mut upright) = (Vec::new(), Vec::new());
        let mut flipped: [Vec<f64>; 3] = Default::default();
        for row in 0..SIZE {
            for col in 0..SIZE {
                // Seen from −z the camera's right is −x.
                let x = centre.x + HALF - (f64::from(col) + 0.5) * 2.0 * HALF / f64::from(SIZE);
                let y = centre.y + HALF - (f64::from(row) + 0.5) * 2.0 * HALF / f64::from(SIZE);
                let du = (q.x0 + 1.0 - x) * 0.4;
                let dv = (q.y0 + 1.0 - y) * 0.4;
                rendered.push(f64::from(
                    gpu.image.pixels[(row * SIZE + col) as usize][q.channel],
                ));
                upright.push(bilinear(q.u0 + du, q.v0 + dv));
                flipped[0].push(bilinear(q.u0 + 0.4 - du, q.v0 + dv));
                flipped[1].push(bilinear(q.u0 + du, q.v0 + 0.4 - dv));
                flipped[2].push(bilinear(q.u0 + 0.4 - du, q.v0 + 0.4 - dv));
            }
        }
        let (r2, slope) = r_squared(&upright, &rendered);
        let wrong: Vec<f64> = flipped.iter().map(|f| r_squared(f, &rendered).0).collect();
        eprintln!(
            "{}: R² upright {r2:.4} (slope {slope:.3}), flipped in u, v, both {:.3?}",
            q.name, wrong
        );
        assert!(
            r2 >= 0.99 && slope > 0.0,
            "{}: R² {r2:.4}, slope {slope:.3}",
            q.name
        );
        for (which, w) in ["u", "v", "u and v"].iter().zip(&wrong) {
            assert!(
                *w < 0.5,
                "{}: the corner flipped in {which} fits too: R² {w:.3}",
                q.name
            );
        }
    }
}

/// TextureSettingsTest (Khronos): rows of two quads, a "Test" quad whose
/// texture coordinates run outside [0, 1] under a sampler's wrap mode, and
/// a "Sample pass" quad beside it that shows what it must look like. The
/// textures are white with green check marks and red crosses placed so
/// that a wrong wrap mode shows a cross (or solid red) where the right one
/// shows a check mark (or solid green, the clamp rows). The model's README
/// states the criterion: every Test quad looks like its Sample, green and
/// never red. Each of the six wrap rows (mirror, repeat and clamp, along S
/// and along T) is rendered head-on and its quads' pixels are classed as
/// green or red by their linear colour; each Test quad must have no red
/// pixel and as much green as its Sample (within a fifth), and neither may
/// be blank. (The model's two doubleSided rows are not checked: penumbra's
/// surfaces are two-sided.)
#[test]
fn texture_settings_test_wrap_rows_pass() {
    use glam::{DVec3, Vec3};
    use penumbra::scene::{Camera, Light, LightKind, Projection};

    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/khronos/TextureSettingsTest/TextureSettingsTest.gltf");
    // The rows, by their meshes' local z range: the root node maps local
    // (x, y, z) to world (−x, z, y), so a row spans world y = local z, the
    // Test quads world x ∈ [−0.9048, −0.0048] and the Samples world
    // x ∈ [−3.0508, −2.1508], all at world z ≈ 0 facing −z.
    let rows: [(&str, f64, f64); 6] = [
        ("mirror T", -5.165, -4.265),
        ("mirror S", -4.128, -3.228),
        ("repeat T", -3.091, -2.191),
        ("repeat S", -2.054, -1.154),
        ("clamp T", -1.020, -0.120),
        ("clamp S", 0.017, 0.917),
    ];
    const PX: f64 = 0.01; // world units a pixel
    const W: u32 = 320;
    const H: u32 = 100;
    let opts = LoadOptions {
        width: Some(W),
        height: Some(H),
        ..Default::default()
    };
    let mut scene = loaders::load_scene(&path, &opts)
        .unwrap_or_else(|e| panic!("{e}"))
        .scene;
    assert_eq!(scene.textures.len(), 3);
    scene.lights = vec![Light {
        kind: LightKind::Directional {
            direction: DVec3::new(0.1, 0.2, 1.0).normalize(),
        },
        intensity: 1.0,
        ambient: Vec3::splat(0.2),
        diffuse: Vec3::ONE,
        specular: Vec3::ZERO,
    }];
    let cx = -1.5278;
    for (name, y0, y1) in rows {
        let cy = 0.5 * (y0 + y1);
        let centre = DVec3::new(cx, cy, 0.0);
        let eye = centre - DVec3::new(0.0, 0.0, 10.0);
        scene.camera = Camera {
            position: eye,
            orientation: Camera::look_at(eye, centre, DVec3::Y).expect("orientation"),
            projection: Projection::Orthographic {
                half_height: 0.5 * PX * f64::from(H),
            },
            width: W,
            height: H,
        };
        let frame = support::render(&scene);
        // (pixels, green, red) inside quad x ∈ [x0, x1], 0.04 from its edges.
        let count = |x0: f64, x1: f64| {
            let (mut n, mut green, mut red) = (0, 0, 0);
            for row in 0..H {
                for col in 0..W {
                    // Seen from −z the camera's right is −x.
                    let x = cx + 0.5 * PX * f64::from(W) - (f64::from(col) + 0.5) * PX;
                    let y = cy + 0.5 * PX * f64::from(H) - (f64::from(row) + 0.5) * PX;
                    if x < x0 + 0.04 || x > x1 - 0.04 || y < y0 + 0.04 || y > y1 - 0.04 {
                        continue;
                    }
                    let p = frame.image.pixels[(row * W + col) as usize];
                    n += 1;
                    if p[1] > 0.1 && p[1] > 3.0 * p[0] {
                        green += 1;
                    }
                    if p[0] > 0.1 && p[0] > 3.0 * p[1] {
                        red += 1;
                    }
                }
            }
            (n, green, red)
        };
        let (nt, gt, rt) = count(-0.9048, -0.0048);
        let (ns, gs, rs) = count(-3.0508, -2.1508);
        eprintln!("{name}: test {gt} green, {rt} red of {nt}; sample {gs} green, {rs} red of {ns}");
        assert!(nt > 5000 && ns > 5000, "{name}: {nt} and {ns} pixels");
        assert_eq!(rs, 0, "{name}: the Sample quad shows red");
        assert!(gs > 100, "{name}: the Sample quad shows no green");
        assert_eq!(rt, 0, "{name}: the Test quad shows {rt} red pixels");
        assert!(
            (gt as f64 - gs as f64).abs() <= 0.2 * gs as f64,
            "{name}: the Test quad shows {gt} green pixels, its Sample {gs}"
        );
    }
}

/// The f32 RGBA pixels of `path` rendered at 180×120 with `camera`.
fn render_file(path: &Path, camera: loaders::gltf::CameraChoice) -> Vec<[f32; 4]> {
    let opts = LoadOptions {
        width: Some(180),
        height: Some(120),
        camera,
        ..Default::default()
    };
    let loaded = loaders::load_scene(path, &opts).unwrap_or_else(|e| panic!("{e}"));
    support::render(&loaded.scene).image.pixels
}

/// Pixels of `a` and `b` whose colour differs by more than 2e-3.
fn differing(a: &[[f32; 4]], b: &[[f32; 4]]) -> usize {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .filter(|(a, b)| (0..3).any(|c| (a[c] - b[c]).abs() > 2e-3))
        .count()
}

/// gltfpack's and Draco's variants of the Duck
/// (tests/data/khronos/Duck/README.md), through the Duck's own camera: the
/// quantized one renders as the plain file (99.5 % of pixels within 2e-3:
/// positions, normals and uvs rounded to 8 to 16 bits), and so do the
/// meshopt-compressed one (lossless, but its index codec may rotate a
/// triangle's corners, which changes the order of the intersection's
/// arithmetic, so not bit for bit) and the Draco-compressed one (Draco's
/// quantization: 14 bits for positions, 10 for normals, 12 for uvs).
#[test]
fn quantized_meshopt_and_draco_ducks_render_as_the_plain_duck() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/khronos/Duck");
    let file = loaders::gltf::CameraChoice::File;
    let plain = render_file(&dir.join("Duck.gltf"), file.clone());
    let quantized = render_file(&dir.join("Duck_quantized.glb"), file.clone());
    let meshopt = render_file(&dir.join("Duck_meshopt.glb"), file.clone());
    let draco = render_file(&dir.join("Duck_draco.glb"), file);
    for (name, variant) in [
        ("quantized", &quantized),
        ("meshopt", &meshopt),
        ("draco", &draco),
    ] {
        assert_alike(&plain, name, variant);
    }
}

/// `variant` renders as `plain` within the tolerance: 99.5 % of
/// pixels within 2e-3; `plain` must show the model.
fn assert_alike(plain: &[[f32; 4]], name: &str, variant: &[[f32; 4]]) {
    let hits = plain.iter().filter(|p| p[3] > 0.0).count();
    assert!(hits > 500, "{hits} hit pixels");
    let over = differing(plain, variant);
    eprintln!(
        "{name}: {over} of {} pixels differ by more than 2e-3",
        plain.len()
    );
    assert!(
        over as f64 <= 0.005 * plain.len() as f64,
        "{name}: {over} of {} pixels differ by more than 2e-3",
        plain.len()
    );
}

/// BoxTextured with its texture as a KTX2/Basis Universal UASTC image
/// (KHR_texture_basisu, tests/data/khronos/BoxTextured/README.md) renders
/// as the PNG original: 99.5 % of pixels within 2e-3.
#[test]
fn a_basisu_textured_box_renders_as_the_png_textured_box() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/khronos/BoxTextured");
    let file = loaders::gltf::CameraChoice::File;
    let plain = render_file(&dir.join("BoxTextured.gltf"), file.clone());
    let basisu = render_file(&dir.join("BoxTextured_basisu_uastc.gltf"), file);
    assert_alike(&plain, "uastc", &basisu);
}

/// BoxTextured drawn three times by EXT_mesh_gpu_instancing renders
/// exactly as the same three boxes written out as nodes (the framing
/// camera of both frames the same bounds).
#[test]
fn instanced_boxes_render_as_the_boxes_written_as_nodes() {
    use serde_json::{json, Value};
    let data = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/khronos/BoxTextured/BoxTextured.gltf");
    let base: Value = serde_json::from_slice(&std::fs::read(data).unwrap()).unwrap();
    let offsets = [[0f32, 0.0, 0.0], [2.5, 0.0, 0.0], [0.0, 0.0, 2.5]];
    let dir = tempfile::tempdir().unwrap();

    let mut nodes = base.clone();
    let first = nodes["nodes"].as_array().unwrap().len();
    for t in offsets {
        nodes["nodes"]
            .as_array_mut()
            .unwrap()
            .push(json!({ "mesh": 0, "translation": t }));
    }
    nodes["nodes"][0]["children"] = json!([first, first + 1, first + 2]);
    let nodes_path = dir.path().join("nodes.gltf");
    std::fs::write(&nodes_path, serde_json::to_vec(&nodes).unwrap()).unwrap();

    let mut instanced = base;
    let bytes: Vec<u8> = offsets
        .iter()
        .flatten()
        .flat_map(|x| x.to_le_bytes())
        .collect();
    let b64 = crate::base64::encode(&bytes);
    instanced["buffers"].as_array_mut().unwrap().push(
        json!({ "byteLength": 36, "uri": format!("data:application/octet-stream;base64,{b64}") }),
    );
    instanced["bufferViews"]
        .as_array_mut()
        .unwrap()
        .push(json!({ "buffer": 1, "byteLength": 36 }));
    instanced["accessors"]
        .as_array_mut()
        .unwrap()
        .push(json!({ "bufferView": 3, "componentType": 5126, "count": 3, "type": "VEC3" }));
    instanced["extensionsUsed"] = json!(["EXT_mesh_gpu_instancing"]);
    instanced["nodes"][2]["extensions"] =
        json!({ "EXT_mesh_gpu_instancing": { "attributes": { "TRANSLATION": 4 } } });
    let instanced_path = dir.path().join("instanced.gltf");
    std::fs::write(&instanced_path, serde_json::to_vec(&instanced).unwrap()).unwrap();

    let framing = loaders::gltf::CameraChoice::Framing;
    let a = render_file(&nodes_path, framing.clone());
    let b = render_file(&instanced_path, framing);
    assert!(a.iter().filter(|p| p[3] > 0.0).count() > 1000);
    assert_eq!(differing(&a, &b), 0);
}
