//! glTF materials through the loader and the metallic-roughness shader: a
//! chart of quads (metal and dielectric at three roughnesses, a
//! metallicRoughnessTexture, an occlusion texture and emission) built here as
//! a glTF file, seen by an orthographic camera along −Z and lit by a
//! directional light travelling along −Z.
//!
//! There n = v = l = h, so glTF 2.0's Appendix B reduces to closed forms:
//! D = α²/(π(α² − 1 + 1)²) = 1/(πα²), V = 1/((1 + 1)(1 + 1)) = 1/4, and
//! the Schlick term (1 − v·h)⁵ = 0, so
//!   metal      = c·D·V            = c/(4πα²)
//!   dielectric = 0.96·c/π + 0.04/(4πα²)
//! each times the light's illuminance (n·l = 1). Tolerance: the quads are
//! flat and head-on, so the only error is f32 rounding of a few operations
//! on values up to ~25: 1e-4 relative is far above it and far below any
//! wrong term.

use crate::support;

use glam::DVec3;
use std::f64::consts::PI;

const BASE: [f64; 3] = [0.9, 0.6, 0.3];
const ILLUMINANCE: f64 = 3.0;
const TOL: f64 = 1e-4;
const WIDTH: u32 = 160;
const HEIGHT: u32 = 80;

/// A 1×1 RGBA PNG of `rgba`.
fn png(rgba: [u8; 4]) -> Vec<u8> {
    let mut out = Vec::new();
    image::RgbaImage::from_pixel(1, 1, image::Rgba(rgba))
        .write_to(&mut std::io::Cursor::new(&mut out), image::ImageFormat::Png)
        .unwrap();
    out
}

/// The texel of the metallic-roughness and occlusion texture: R (occlusion)
/// 0, G (roughness) 128, B (metallic) 191.
const TEXEL: [u8; 4] = [0, 128, 191, 255];

/// Quad centres: two rows of four (metal row on top).
fn centre(i: usize) -> (f64, f64) {
    (-3.6 + 2.4 * (i % 4) as f64, if i < 4 { 1.2 } else { -1.2 })
}

/// The chart as a glTF file: quads 0–2 metals at roughness 0.3, 0.5, 1;
/// quad 3 metallic and roughness factors 1 scaled by the texture; quads
/// 4–6 dielectrics at 0.3, 0.5, 1; quad 7 a dielectric at roughness 0.5
/// with the texture as its occlusion and an emission.
fn chart() -> String {
    // A unit quad facing +Z, its uv, two triangles.
    let mut buffer = Vec::new();
    for [x, y] in [[-0.5f32, -0.5], [0.5, -0.5], [0.5, 0.5], [-0.5, 0.5]] {
        for v in [x, y, 0.0] {
            buffer.extend(v.to_le_bytes());
        }
    }
    for [u, v] in [[0.0f32, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]] {
        buffer.extend(u.to_le_bytes());
        buffer.extend(v.to_le_bytes());
    }
    for i in [0u16, 1, 2, 0, 2, 3] {
        buffer.extend(i.to_le_bytes());
    }
    let texture = r#"{"index": 0}"#;
    let material = |metallic: f64, roughness: f64, extra: &str| {
        format!(
            r#"{{"pbrMetallicRoughness": {{"baseColorFactor": [{}, {}, {}, 1], "metallicFactor": {metallic}, "roughnessFactor": {roughness}{extra}}}}}"#,
            BASE[0], BASE[1], BASE[2]
        )
    };
    let mut materials = Vec::new();
    for metallic in [1.0, 0.0] {
        for roughness in [0.3, 0.5, 1.0] {
            materials.push(material(metallic, roughness, ""));
        }
        if metallic == 1.0 {
            materials.push(material(
                1.0,
                1.0,
                &format!(r#", "metallicRoughnessTexture": {texture}"#),
            ));
        }
    }
    let mut last = material(0.0, 0.5, "");
    last.pop();
    last.push_str(&format!(
        r#", "occlusionTexture": {texture}, "emissiveFactor": [0.2, 0.1, 0.05]}}"#
    ));
    materials.push(last);
    let meshes: Vec<String> = (0..8)
        .map(|m| {
            format!(
                r#"{{"primitives": [{{"attributes": {{"POSITION": 0, "TEXCOORD_0": 1}}, "indices": 2, "material": {m}}}]}}"#
            )
        })
        .collect();
    let mut nodes: Vec<String> = (0..8)
        .map(|i| {
            let (x, y) = centre(i);
            format!(r#"{{"mesh": {i}, "translation": [{x}, {y}, 0]}}"#)
        })
        .collect();
    nodes.push(r#"{"camera": 0, "translation": [0, 0, 5]}"#.into());
    nodes.push(r#"{"extensions": {"KHR_lights_punctual": {"light": 0}}}"#.into());
    format!(
        r#"{{
  "asset": {{"version": "2.0"}},
  "extensionsUsed": ["KHR_lights_punctual"],
  "extensions": {{"KHR_lights_punctual": {{"lights": [{{"type": "directional", "intensity": {ILLUMINANCE}}}]}}}},
  "scene": 0,
  "scenes": [{{"nodes": [0, 1, 2, 3, 4, 5, 6, 7, 8, 9]}}],
  "nodes": [{}],
  "cameras": [{{"type": "orthographic", "orthographic": {{"xmag": 4.8, "ymag": 2.4, "znear": 0.1, "zfar": 100}}}}],
  "meshes": [{}],
  "materials": [{}],
  "textures": [{{"source": 0}}],
  "images": [{{"uri": "data:image/png;base64,{}"}}],
  "buffers": [{{"byteLength": {}, "uri": "data:application/octet-stream;base64,{}"}}],
  "bufferViews": [
    {{"buffer": 0, "byteOffset": 0, "byteLength": 48}},
    {{"buffer": 0, "byteOffset": 48, "byteLength": 32}},
    {{"buffer": 0, "byteOffset": 80, "byteLength": 12}}
  ],
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [-0.5, -0.5, 0], "max": [0.5, 0.5, 0]}},
    {{"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2"}},
    {{"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"}}
  ]
}}"#,
        nodes.join(", "),
        meshes.join(", "),
        materials.join(", "),
        crate::base64::encode(&png(TEXEL)),
        buffer.len(),
        crate::base64::encode(&buffer)
    )
}

fn metal(roughness: f64, c: DVec3) -> DVec3 {
    let a2 = roughness.powi(4);
    c / (4.0 * PI * a2)
}

fn dielectric(roughness: f64, c: DVec3) -> DVec3 {
    let a2 = roughness.powi(4);
    0.96 * c / PI + DVec3::splat(0.04 / (4.0 * PI * a2))
}

/// The colour at each quad's centre, from the closed forms above.
fn expected() -> [DVec3; 8] {
    let c = DVec3::from(BASE);
    // Linear texture channels: metallic = 191/255, roughness = 128/255.
    let (m, r) = (191.0 / 255.0, 128.0 / 255.0);
    let textured = dielectric(r, c) * (1.0 - m) + metal(r, c) * m;
    [
        metal(0.3, c),
        metal(0.5, c),
        metal(1.0, c),
        textured,
        dielectric(0.3, c),
        dielectric(0.5, c),
        dielectric(1.0, c),
        // Occlusion does not touch punctual light; emission adds.
        dielectric(0.5, c) + DVec3::new(0.2, 0.1, 0.05) / ILLUMINANCE,
    ]
    .map(|f| f * ILLUMINANCE)
}

/// Renders the glTF text `gltf` at WIDTH×HEIGHT.
fn render(gltf: &str) -> penumbra::render::Image {
    support::render(&load(gltf)).image
}

/// Loads the glTF text `gltf` at WIDTH×HEIGHT.
fn load(gltf: &str) -> penumbra::scene::Scene {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("chart.gltf");
    std::fs::write(&path, gltf).unwrap();
    let opts = penumbra::loaders::LoadOptions {
        width: Some(WIDTH),
        height: Some(HEIGHT),
        ..Default::default()
    };
    penumbra::loaders::load_scene(&path, &opts)
        .unwrap_or_else(|e| panic!("{e}"))
        .scene
}

/// The pixel at quad `i`'s centre.
fn at_quad(img: &penumbra::render::Image, i: usize) -> [f32; 4] {
    let (x, y) = centre(i);
    let px = ((x + 4.8) / 9.6 * WIDTH as f64) as u32;
    let py = ((2.4 - y) / 4.8 * HEIGHT as f64) as u32;
    img.at(px, py)
}

/// KHR_materials_unlit: the base colour is the colour, whatever the light
/// (here the chart's metal at roughness 0.3, which lit would be ~2.5).
#[test]
fn an_unlit_material_shows_its_base_colour() {
    for intensity in [ILLUMINANCE, 0.0] {
        let mut gltf: serde_json::Value = serde_json::from_str(&chart()).unwrap();
        gltf["materials"][0]["extensions"] = serde_json::json!({"KHR_materials_unlit": {}});
        gltf["extensionsUsed"] = serde_json::json!(["KHR_lights_punctual", "KHR_materials_unlit"]);
        gltf["extensions"]["KHR_lights_punctual"]["lights"][0]["intensity"] =
            serde_json::json!(intensity);
        let img = render(&gltf.to_string());
        support::assert_rgb(at_quad(&img, 0), BASE, 1e-6);
        // The others are lit as before (or dark without light).
        let lit = expected()[1] * (intensity / ILLUMINANCE);
        support::assert_rgb(
            at_quad(&img, 1),
            lit.to_array(),
            TOL * lit.max_element().max(1.0),
        );
    }
}

#[test]
fn a_metal_roughness_chart_matches_the_closed_forms() {
    let img = render(&chart());
    for (i, want) in expected().iter().enumerate() {
        let got = at_quad(&img, i);
        for k in 0..3 {
            assert!(
                (got[k] as f64 - want[k]).abs() <= TOL * want[k].max(1.0),
                "quad {i}: got {:?}, want {want:?}",
                &got[..3]
            );
        }
    }
}

/// sRGB's decoding (IEC 61966-2-1) of an 8-bit code.
fn srgb(code: u8) -> f64 {
    let c = f64::from(code) / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// KHR_materials_pbrSpecularGlossiness head-on (v·h = 1, so F = F0):
/// c_diff = diffuse·(1 − max F0), α = (1 − glossiness)², and
/// f = (1 − F0)·c_diff/π + F0·D·V with D·V = 1/(4πα²). Quad 1 has factors
/// only; quad 2 the texture as its diffuseTexture (sRGB) and its
/// specularGlossinessTexture (specular sRGB RGB, glossiness linear A).
#[test]
fn specular_glossiness_materials_match_their_formulas() {
    let mut gltf: serde_json::Value = serde_json::from_str(&chart()).unwrap();
    gltf["materials"][1]["extensions"] = serde_json::json!({"KHR_materials_pbrSpecularGlossiness": {
        "diffuseFactor": [0.5, 0.4, 0.3, 1], "specularFactor": [0.2, 0.3, 0.1], "glossinessFactor": 0.6}});
    gltf["materials"][2]["extensions"] = serde_json::json!({"KHR_materials_pbrSpecularGlossiness": {
        "diffuseTexture": {"index": 0}, "specularGlossinessTexture": {"index": 0}, "glossinessFactor": 0.5}});
    gltf["extensionsUsed"] =
        serde_json::json!(["KHR_lights_punctual", "KHR_materials_pbrSpecularGlossiness"]);
    let scene = load(&gltf.to_string());
    let img = support::render(&scene).image;
    // The f64 reference renders the same image.
    let reference = penumbra::reference::render(&scene, &Default::default(), Default::default());
    for (a, b) in img.pixels.iter().zip(&reference.image.pixels) {
        let want = [b[0], b[1], b[2]].map(f64::from);
        let scale = want.iter().fold(1.0f64, |m, &x| m.max(x));
        support::assert_rgb(*a, want, 2e-3 * scale);
    }
    let f = |diffuse: DVec3, f0: DVec3, glossiness: f64| {
        let a2 = (1.0 - glossiness).powi(4);
        let c_diff = diffuse * (1.0 - f0.max_element());
        ((DVec3::ONE - f0) * c_diff / PI + f0 / (4.0 * PI * a2)) * ILLUMINANCE
    };
    let quad1 = f(DVec3::new(0.5, 0.4, 0.3), DVec3::new(0.2, 0.3, 0.1), 0.6);
    let t = DVec3::new(srgb(TEXEL[0]), srgb(TEXEL[1]), srgb(TEXEL[2]));
    let quad2 = f(t, t, 0.5 * f64::from(TEXEL[3]) / 255.0);
    for (i, want) in [(1, quad1), (2, quad2)] {
        let got = at_quad(&img, i);
        support::assert_rgb(got, want.to_array(), TOL * want.max_element().max(1.0));
    }
    // The others keep glTF's metallic-roughness model.
    let want = expected()[0];
    support::assert_rgb(at_quad(&img, 0), want.to_array(), TOL * want.max_element());
}
