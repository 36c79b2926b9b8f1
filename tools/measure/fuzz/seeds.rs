//! The seeds: the project's scenes, the sample files under tests/data, the
//! shading WGSL, and generated documents that reach the parts of the
//! loaders the files do not (every camera and light kind, strips and fans,
//! sparse accessors, node trees, binary GLB chunks).

use std::path::{Path, PathBuf};

use serde_json::{json, Value};

use super::targets::Target;

/// One seed input.
#[derive(Clone, Debug)]
pub struct Seed {
    /// Which loader it feeds.
    pub target: Target,
    /// Where it came from, for the report.
    pub name: String,
    /// The file's bytes.
    pub data: Vec<u8>,
}

/// The repository root (this program runs from anywhere inside it).
pub fn root() -> PathBuf {
    common::repo_root()
}

fn file(target: Target, path: &Path) -> Option<Seed> {
    let data = std::fs::read(path).ok()?;
    let name = path
        .strip_prefix(root())
        .unwrap_or(path)
        .display()
        .to_string();
    Some(Seed { target, name, data })
}

/// Every seed, in a fixed order so that a run is reproducible from its seed number.
pub fn all() -> Vec<Seed> {
    let r = root();
    let mut seeds = Vec::new();
    for name in ["showcase.json", "area_lights.json"] {
        seeds.extend(file(Target::Json, &r.join("scenes").join(name)));
    }
    for (i, scene) in generated_scenes().into_iter().enumerate() {
        seeds.push(Seed {
            target: Target::Json,
            name: format!("generated scene {i}"),
            data: serde_json::to_vec_pretty(&scene).unwrap_or_default(),
        });
    }
    let mut gltf_files: Vec<_> = std::fs::read_dir(r.join("tests/data/fuzz/seeds"))
        .into_iter()
        .flatten()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "gltf"))
        .collect();
    gltf_files.sort();
    for p in &gltf_files {
        seeds.extend(file(Target::Gltf, p));
    }
    for (i, doc) in generated_gltf().into_iter().enumerate() {
        let data = serde_json::to_vec(&doc).unwrap_or_default();
        seeds.push(Seed {
            target: Target::Gltf,
            name: format!("generated glTF {i}"),
            data: data.clone(),
        });
        if let Some(glb) = to_glb(&doc, &quad_buffer()) {
            seeds.push(Seed {
                target: Target::Glb,
                name: format!("generated GLB {i}"),
                data: glb,
            });
        }
    }
    for name in ["bunny.glb", "bunny_scene.glb"] {
        seeds.extend(file(Target::Glb, &r.join("scenes").join(name)));
    }
    // A Draco-compressed mesh (KHR_draco_mesh_compression): the decoder
    // reads untrusted bytes too.
    seeds.extend(file(
        Target::Glb,
        &r.join("tests/data/khronos/Duck/Duck_draco.glb"),
    ));
    // KTX2 images of Basis Universal (KHR_texture_basisu), both codecs.
    for name in ["CesiumLogoFlat_uastc.ktx2", "CesiumLogoFlat_etc1s.ktx2"] {
        seeds.extend(file(
            Target::Texture,
            &r.join("tests/data/khronos/BoxTextured").join(name),
        ));
    }
    for name in shading_files() {
        seeds.extend(file(Target::Wgsl, &r.join("shaders/shading").join(name)));
    }
    seeds.extend(
        super::texture::seeds()
            .into_iter()
            .map(|(name, data)| Seed {
                target: Target::Texture,
                name,
                data,
            }),
    );
    seeds.extend(shader_seeds(&r));
    // Tile 0 of 2; the harness merges each mutated copy with a valid tile 1.
    let (name, data) = part(0);
    seeds.push(Seed {
        target: Target::Part,
        name,
        data,
    });
    seeds.extend(super::request::seeds());
    seeds
}

/// Tile `index` of 2 of a 16x32 render with 4 passes, as `penumbra render
/// --tile` writes it (`farm::part::write`): the seed of the part target.
pub fn part(index: u32) -> (String, Vec<u8>) {
    use penumbra::farm::part::{self, PartInfo};
    use penumbra::farm::split::{Passes, Tile};
    let info = PartInfo {
        render: "0123456789abcdef".repeat(4),
        scene: "fuzz.json".into(),
        tile: Tile { index, count: 2 },
        passes: Passes { start: 0, end: 4 },
        spp: 4,
        width: 16,
        height: 32,
        rows: 16 * index..16 * index + 16,
    };
    let pixels = (0..16 * 16)
        .map(|i| [i as f32 * 0.25, 1.0, 2.0, 1.0])
        .collect();
    let image = penumbra::render::Image {
        width: 16,
        height: 16,
        pixels,
    };
    let dir = tempfile::tempdir().expect("a temporary folder");
    let path = dir.path().join("part.exr");
    part::write(&path, &info, &image).expect("a valid part file");
    let data = std::fs::read(&path).expect("the part file just written");
    (format!("generated part {index}/2"), data)
}

/// Little-endian bytes of `f32` values, base64-encoded in a data URI.
fn data_uri(bytes: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::from("data:application/octet-stream;base64,");
    for c in bytes.chunks(3) {
        let n = (u32::from(c[0]) << 16)
            | (u32::from(*c.get(1).unwrap_or(&0)) << 8)
            | u32::from(*c.get(2).unwrap_or(&0));
        for k in 0..4 {
            if k <= c.len() {
                s.push(A[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                s.push('=');
            }
        }
    }
    s
}

/// A buffer of four positions (a quad), six u16 indices and four normals.
fn quad_buffer() -> Vec<u8> {
    let mut b = Vec::new();
    for p in [[0f32, 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 0.]] {
        p.iter().for_each(|x| b.extend(x.to_le_bytes()));
    }
    for i in [0u16, 1, 2, 0, 2, 3] {
        b.extend(i.to_le_bytes());
    }
    for _ in 0..4 {
        [0f32, 0., 1.]
            .iter()
            .for_each(|x| b.extend(x.to_le_bytes()));
    }
    b
}

/// glTF documents covering what the sample files do not.
fn generated_gltf() -> Vec<Value> {
    let buf = quad_buffer();
    let base = json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0, 1, 2]}],
        "nodes": [
            {"mesh": 0, "children": [3]},
            {"camera": 0, "translation": [0.5, 0.5, 3.0]},
            {"extensions": {"KHR_lights_punctual": {"light": 0}}, "rotation": [-0.383, 0.0, 0.0, 0.924]},
            {"mesh": 1, "scale": [1.0, -1.0, 1.0], "translation": [2.0, 0.0, 0.0]}
        ],
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"type": "directional", "color": [1.0, 0.9, 0.8], "intensity": 2.0},
            {"type": "point", "intensity": 5.0, "range": 10.0},
            {"type": "spot", "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.6}}
        ]}},
        "cameras": [
            {"type": "perspective", "perspective": {"yfov": 0.7, "aspectRatio": 1.5, "znear": 0.01}},
            {"type": "orthographic", "orthographic": {"xmag": 1.0, "ymag": 1.0, "znear": 0.01, "zfar": 100.0}}
        ],
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.2, 0.1, 1.0]}}],
        "meshes": [
            {"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 2}, "indices": 1, "material": 0}]},
            {"primitives": [
                {"attributes": {"POSITION": 0}, "mode": 5},
                {"attributes": {"POSITION": 0}, "mode": 6},
                {"attributes": {"POSITION": 0}, "mode": 1},
                {"attributes": {"POSITION": 3}, "indices": 1}
            ]}
        ],
        "buffers": [{"byteLength": buf.len(), "uri": data_uri(&buf)}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 48, "byteStride": 12},
            {"buffer": 0, "byteOffset": 48, "byteLength": 12},
            {"buffer": 0, "byteOffset": 60, "byteLength": 48}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR"},
            {"bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC3"},
            {"componentType": 5126, "count": 4, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0],
             "sparse": {"count": 1, "indices": {"bufferView": 1, "componentType": 5123},
                        "values": {"bufferView": 0}}}
        ]
    });
    let mut ortho = base.clone();
    ortho["nodes"][1]["camera"] = json!(1);
    let mut spot = base.clone();
    spot["nodes"][2]["extensions"]["KHR_lights_punctual"]["light"] = json!(2);
    let mut external = base.clone();
    external["buffers"][0]["uri"] = json!("missing.bin");
    vec![base, ortho, spot, external]
}

/// The document as a GLB with `bin` as the BIN chunk, in place of its first buffer's URI.
fn to_glb(doc: &Value, bin: &[u8]) -> Option<Vec<u8>> {
    let mut doc = doc.clone();
    doc["buffers"][0].as_object_mut()?.remove("uri");
    let mut chunk = bin.to_vec();
    while !chunk.len().is_multiple_of(4) {
        chunk.push(0);
    }
    let mut rest = (chunk.len() as u32).to_le_bytes().to_vec();
    rest.extend(b"BIN\0");
    rest.extend(chunk);
    Some(glb(serde_json::to_vec(&doc).ok()?, &rest))
}

/// A GLB container: the header, `json` as the JSON chunk (padded with
/// spaces to 4 bytes), then `rest` as it is (further chunks, or bytes).
pub fn glb(mut json: Vec<u8>, rest: &[u8]) -> Vec<u8> {
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let total = 12 + 8 + json.len() + rest.len();
    let mut out = Vec::with_capacity(total);
    out.extend(b"glTF");
    out.extend(2u32.to_le_bytes());
    out.extend((total as u32).to_le_bytes());
    out.extend((json.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(json);
    out.extend(rest);
    out
}

/// The engine's shading files (`shaders/shading/`, from the renderer's own
/// table of shader files, so that a new one is fuzzed too), but the
/// interface that user shaders are written against.
pub fn shading_files() -> Vec<&'static str> {
    penumbra::render::stages::SHADER_FILES
        .iter()
        .filter_map(|(name, _)| name.strip_prefix("shading/"))
        .filter(|name| *name != "interface.wgsl")
        .collect()
}

/// JSON scenes with every object, light and shader kind.
fn generated_scenes() -> Vec<Value> {
    let all = json!({
        "camera": {"position": [0, 1, 5], "look_at": [0, 0, 0], "up": [0, 1, 0], "fov": 50, "width": 64, "height": 48},
        "background": [0.1, 0.1, 0.2],
        "shaders": {
            "red": {"type": "phong", "ambient": [0.1, 0, 0], "diffuse": [0.8, 0.1, 0.1], "specular": [1, 1, 1], "shininess": 20},
            "blue": {"type": "blinn_phong", "diffuse": [0.1, 0.1, 0.8], "shininess": 1},
            "gold": {"type": "metallic_roughness", "base_colour": [1, 0.77, 0.34], "metallic": 1, "roughness": 0.3},
            "satin": {"type": "specular_glossiness", "diffuse": [0.3, 0.5, 0.2], "specular": [0.1, 0.1, 0.1], "glossiness": 0.6},
            "board": {"type": "checker", "size": 0.5, "even": "red", "odd": "inner"},
            "inner": {"type": "checker", "size": 0.1, "even": "blue", "odd": "red"},
            "toon": {"type": "wgsl", "file": "shaders/toon.wgsl",
                     "params": {"base": [0.95, 0.45, 0.1], "bands": 4, "highlight": [1.0, 1.0, 0.9], "shininess": 40}}
        },
        "objects": [
            {"type": "plane", "point": [0, 0, 0], "normal": [0, 1, 0], "shader": "board"},
            {"type": "sphere", "center": [0, 1, 0], "radius": 0.5, "shader": "toon"},
            {"type": "triangle", "vertices": [[-1, 0, 0], [1, 0, 0], [0, 1, -1]], "shader": "blue"},
            {"type": "triangle", "vertices": [[-1, 0, 1], [0, 0, 1], [-0.5, 1, 1]], "shader": "gold"},
            {"type": "triangle", "vertices": [[0, 0, 1], [1, 0, 1], [0.5, 1, 1]], "shader": "satin"},
            {"type": "mesh", "file": "bunny.glb", "transform": {"translate": [1, 0, 0], "rotate": [0, 30, 0], "scale": [1, 2, 1]}}
        ],
        "lights": [
            {"type": "directional", "direction": [-1, -1, -1], "intensity": 1},
            {"type": "point", "position": [2, 3, 2], "intensity": 10, "diffuse": [1, 1, 1]},
            {"type": "spot", "position": [0, 4, 0], "direction": [0, -1, 0], "inner_angle": 10, "outer_angle": 30},
            {"type": "rect", "corner": [0, 3, 0], "edge1": [1, 0, 0], "edge2": [0, 0, 1], "samples": 4},
            {"type": "sphere", "center": [-2, 3, 0], "radius": 0.3, "samples": 2},
            {"type": "environment", "up": [0, 1, 0], "samples": 2, "intensity": 0.5}
        ]
    });
    let mut ortho = all.clone();
    ortho["camera"] = json!({"position": [0, 1, 5], "yaw": 10, "pitch": -5, "roll": 0,
        "projection": "orthographic", "half_height": 2, "width": 32, "height": 32});
    vec![all, ortho]
}

/// The user shader files of `scenes/shaders/`, and `toon.wgsl` with
/// multibyte characters in a block comment, a line comment and at its end:
/// the class that panicked the comment scan (issue 36) is in every case of
/// that seed that keeps them, so CI's short run meets it.
fn shader_seeds(root: &Path) -> Vec<Seed> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(root.join("scenes/shaders"))
        .into_iter()
        .flatten()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "wgsl"))
        .collect();
    files.sort();
    let mut seeds: Vec<Seed> = files
        .iter()
        .filter_map(|p| file(Target::Shader, p))
        .collect();
    if let Some(toon) = seeds.iter().find(|s| s.name.ends_with("toon.wgsl")) {
        let text = String::from_utf8_lossy(&toon.data);
        let data = format!("/* Tön-Shader: 日本語 🦀 /* ß */ é */\n// ä ö ü\n{text}// ende ✓");
        seeds.push(Seed {
            target: Target::Shader,
            name: "generated multibyte toon.wgsl".into(),
            data: data.into_bytes(),
        });
    }
    seeds
}
