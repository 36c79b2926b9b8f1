//! A glTF file without lights is lit wherever a camera looks: under glTF's
//! own materials by the default environment, which comes from every
//! direction; under the seminar's Phong mapping (`--gltf-materials phong`)
//! by default lights placed relative to the camera that renders it (a key
//! light over its shoulder and a fill from it). Either way the model files
//! without lights, seen through the framing camera and through cameras of
//! their own from every side, below included, have at least 90 % of their
//! hit pixels lit.
//!
//! "Lit" is a linear luminance of at least [`LIT`]. With the default
//! lights' ambient 0 and a black background, a hit pixel that no light
//! reaches is exactly 0; [`LIT`] = 0.005 is what the fill light alone
//! (intensity 0.35) gives a diffuse 0.8 surface at a cosine of 0.018,
//! i.e. it counts as lit any point that faces a light at all, and it is
//! sRGB 16/255 in the PNG, the darkest grey that stands out from the black
//! background. Points in shadow from both lights, and points seen so
//! obliquely that both lights graze them, are the unlit rest.

use std::path::{Path, PathBuf};

use penumbra::loaders::{self, GltfMaterials, LoadOptions};
use serde_json::{json, Value};

use crate::support;

/// Linear luminance at and above which a hit pixel is lit (module docs).
const LIT: f32 = 0.005;

/// Both material models: each lights a file without lights its own way.
const MATERIALS: [GltfMaterials; 2] = [GltfMaterials::MetallicRoughness, GltfMaterials::Phong];

/// The committed solid model files without lights.
fn models() -> Vec<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    vec![
        root.join("scenes/bunny.glb"),
        root.join("tests/data/khronos/BoxTextured/BoxTextured.gltf"),
        // The case: its own camera, lit from the far side before.
        root.join("tests/data/khronos/Duck/Duck.gltf"),
    ]
}

/// TextureCoordinateTest: flat quads in one plane, so only the framing
/// camera's view is tested (cameras on every side include views edge-on).
fn flat_models() -> Vec<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    vec![root.join("tests/data/khronos/TextureCoordinateTest/TextureCoordinateTest.gltf")]
}

/// (hit pixels, lit hit pixels) of a render of `path` at 200 pixels wide
/// with `materials`.
fn lit_fraction(path: &Path, materials: GltfMaterials) -> (usize, usize) {
    let opts = LoadOptions {
        width: Some(200),
        gltf_materials: materials,
        ..Default::default()
    };
    let loaded = loaders::load_scene(path, &opts).unwrap_or_else(|e| panic!("{e}"));
    let note = match materials {
        GltfMaterials::MetallicRoughness => "lit by the default environment",
        GltfMaterials::Phong => "relative to the camera",
    };
    assert!(
        loaded.notes.iter().any(|n| n.contains(note)),
        "{:?}",
        loaded.notes
    );
    let frame = support::render(&loaded.scene);
    let hits: Vec<_> = frame.image.pixels.iter().filter(|p| p[3] == 1.0).collect();
    let lum = |p: &[f32; 4]| 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
    let lit = hits.iter().filter(|p| lum(p) >= LIT).count();
    (hits.len(), lit)
}

/// At least `min_hits` hit pixels of `path`, 90 % of them lit, under both
/// material models (`label` names the view in messages).
fn check_lit(path: &Path, label: &str, min_hits: usize) {
    for materials in MATERIALS {
        let (hits, lit) = lit_fraction(path, materials);
        eprintln!("{label} ({materials:?}): {lit} of {hits} hit pixels lit");
        assert!(hits > min_hits, "{label}: {hits} hits");
        assert!(
            lit * 10 >= hits * 9,
            "{label} ({materials:?}): {lit} of {hits} lit"
        );
    }
}

/// The JSON and BIN chunks of a GLB file (a `.gltf` file: its JSON and no
/// BIN chunk; its buffers are data URIs or files).
fn split_glb(bytes: &[u8]) -> (Value, Vec<u8>) {
    if !bytes.starts_with(b"glTF") {
        return (serde_json::from_slice(bytes).unwrap(), Vec::new());
    }
    let word = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap()) as usize;
    let json_len = word(12);
    let json = serde_json::from_slice(&bytes[20..20 + json_len]).unwrap();
    let at = 20 + json_len;
    let bin = if at < bytes.len() {
        bytes[at + 8..at + 8 + word(at)].to_vec()
    } else {
        Vec::new()
    };
    (json, bin)
}

/// A GLB file from a JSON root and a BIN chunk.
fn glb(json: &Value, bin: &[u8]) -> Vec<u8> {
    let mut text = serde_json::to_vec(json).unwrap();
    while !text.len().is_multiple_of(4) {
        text.push(b' ');
    }
    let mut bin = bin.to_vec();
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let total = 12 + 8 + text.len() + 8 + bin.len();
    let mut out = Vec::new();
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(text.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&text);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&bin);
    out
}

/// A glTF node rotation (x, y, z, w) that makes a camera at `eye` look at
/// `target` with +Y up (or +Z up when looking straight along Y).
fn look_rotation(eye: glam::DVec3, target: glam::DVec3) -> [f64; 4] {
    let back = (eye - target).normalize();
    let up = if back.y.abs() > 0.99 {
        glam::DVec3::Z
    } else {
        glam::DVec3::Y
    };
    let right = up.cross(back).normalize();
    let up = back.cross(right);
    let q = glam::DQuat::from_mat3(&glam::DMat3::from_cols(right, up, back));
    q.to_array()
}

#[test]
fn model_files_without_lights_are_lit_where_their_framing_camera_looks() {
    for path in models().into_iter().chain(flat_models()) {
        check_lit(&path, &path.display().to_string(), 1000);
    }
}

#[test]
fn model_files_without_lights_are_lit_from_cameras_on_every_side() {
    let dir = tempfile::tempdir().unwrap();
    for path in models() {
        let (mut json, bin) = split_glb(&std::fs::read(&path).unwrap());
        let loaded = loaders::load_scene(&path, &LoadOptions::default()).unwrap();
        let bounds = loaded.scene.objects.iter().filter_map(|o| match &o.shape {
            penumbra::scene::Shape::Mesh(m) => m.bounds(),
            _ => None,
        });
        let (lo, hi) = bounds
            .reduce(|(a, b), (c, d)| (a.min(c), b.max(d)))
            .unwrap();
        let (centre, radius) = ((lo + hi) * 0.5, (hi - lo).length() * 0.5);
        // Behind, below, above, and the two sides, each from 3 radii.
        let sides = [
            glam::DVec3::new(0.0, 0.2, -1.0),
            glam::DVec3::new(0.3, -1.0, 0.2),
            glam::DVec3::new(0.0, 1.0, 0.1),
            glam::DVec3::new(1.0, 0.0, 0.0),
            glam::DVec3::new(-1.0, -0.3, 0.2),
        ];
        // The model's own cameras give way to the test's one.
        for node in json["nodes"].as_array_mut().unwrap() {
            node.as_object_mut().unwrap().remove("camera");
        }
        json["cameras"] = json!([{ "type": "perspective",
            "perspective": { "yfov": 0.7, "znear": 0.01, "aspectRatio": 1.0 } }]);
        let camera_node = json["nodes"].as_array().unwrap().len();
        json["nodes"]
            .as_array_mut()
            .unwrap()
            .push(json!({ "camera": 0 }));
        let scene = json["scene"].as_u64().unwrap_or(0) as usize;
        json["scenes"][scene]["nodes"]
            .as_array_mut()
            .unwrap()
            .push(json!(camera_node));
        for (k, side) in sides.iter().enumerate() {
            let eye = centre + side.normalize() * 3.0 * radius;
            json["nodes"][camera_node]["translation"] = json!(eye.to_array());
            json["nodes"][camera_node]["rotation"] = json!(look_rotation(eye, centre));
            let file = if bin.is_empty() {
                let file = dir.path().join(format!("view{k}.gltf"));
                std::fs::write(&file, serde_json::to_vec(&json).unwrap()).unwrap();
                file
            } else {
                let file = dir.path().join(format!("view{k}.glb"));
                std::fs::write(&file, glb(&json, &bin)).unwrap();
                file
            };
            check_lit(&file, &format!("{} from {side}", path.display()), 500);
        }
    }
}
