//! The glTF loader's extensions and framing (issue 39), against small files
//! written here: KHR_mesh_quantization against the glTF formulas,
//! EXT_meshopt_compression against the same data uncompressed,
//! EXT_mesh_gpu_instancing against the instances written out as nodes,
//! static morph weights against the blend computed here, `texCoord` in a
//! normal map's KHR_texture_transform, `--camera`, and the framing camera
//! against its rule (docs/gltf.md): the projected bounding box spans 80–95 %
//! of the limiting dimension, and a flat chart is seen face-on.

use std::f64::consts::FRAC_1_SQRT_2;
use std::path::Path;

use glam::{DMat4, DQuat, DVec3};
use penumbra::loaders::gltf::{self, CameraChoice};
use penumbra::loaders::{self, LoadOptions, Loaded};
use penumbra::scene::{Camera, Shape};
use serde_json::{json, Value};
use tempfile::TempDir;

use crate::gltf_loader::{
    error_of, glb, load_doc, material_doc, notes_with, png_uri, read_doc, Container, Doc, TRI,
};

const BYTE: u32 = 5120;
const UNSIGNED_BYTE: u32 = 5121;
const SHORT: u32 = 5122;
const UNSIGNED_SHORT: u32 = 5123;

fn le16(v: &[i32]) -> Vec<u8> {
    v.iter().flat_map(|&x| (x as u16).to_le_bytes()).collect()
}

/// A POSITION accessor of integers, 4-byte aligned elements (padded).
fn int_positions(doc: &mut Doc, v: &[[i32; 3]], ty: u32, norm: bool) -> usize {
    let mut bytes = Vec::new();
    for p in v {
        let mut e = le16(p);
        e.extend([0, 0]);
        bytes.extend(e);
    }
    let view = doc.view(&bytes);
    doc.root["bufferViews"][view]["byteStride"] = json!(8);
    doc.push(
        "accessors",
        json!({ "bufferView": view, "componentType": ty, "count": v.len(), "type": "VEC3",
                "normalized": norm, "min": [-1e9, -1e9, -1e9], "max": [1e9, 1e9, 1e9] }),
    )
}

/// Sets the byteStride of accessor `acc`'s view.
fn strided(doc: &mut Doc, acc: usize, stride: usize) {
    let view = doc.root["accessors"][acc]["bufferView"].as_u64().unwrap() as usize;
    doc.root["bufferViews"][view]["byteStride"] = json!(stride);
}

fn positions(loaded: &gltf::GltfDocument, mesh: usize) -> Vec<DVec3> {
    loaded.meshes[mesh].mesh.positions.clone()
}

#[test]
fn quantized_attributes_are_dequantized_as_the_extension_specifies() {
    let mut doc = Doc::new();
    doc.root["extensionsUsed"] = json!(["KHR_mesh_quantization"]);
    doc.root["extensionsRequired"] = json!(["KHR_mesh_quantization"]);
    let signed = [[-32768, 0, 0], [32767, 0, 0], [0, 16384, 0]];
    let pos_norm = int_positions(&mut doc, &signed, SHORT, true);
    let unsigned = [[0, 0, 0], [300, 0, 0], [0, 65535, 7]];
    let pos_int = int_positions(&mut doc, &unsigned, UNSIGNED_SHORT, false);
    // Normals as normalized bytes (each element 4-byte aligned).
    let normal = doc.accessor(
        &[0, 0, 127, 0, 0, 0, 127, 0, 0, 0, 127, 0],
        BYTE,
        3,
        "VEC3",
        true,
    );
    strided(&mut doc, normal, 4);
    // TEXCOORD_0 as plain (non-normalized) unsigned bytes: 2 is 2.0.
    let uv = doc.accessor(
        &[2, 0, 0, 0, 0, 3, 0, 0, 255, 255, 0, 0],
        UNSIGNED_BYTE,
        3,
        "VEC2",
        false,
    );
    strided(&mut doc, uv, 4);
    doc.mesh_node(
        json!([{ "attributes": { "POSITION": pos_norm, "NORMAL": normal, "TEXCOORD_0": uv } }]),
        json!({}),
    );
    doc.mesh_node(
        json!([{ "attributes": { "POSITION": pos_int } }]),
        json!({ "scale": [0.5, 0.5, 0.5] }),
    );
    let (_dir, read) = read_doc(&doc, Container::Glb);
    // glTF: a normalized SHORT c stands for max(c / 32767, −1).
    let f = |c: i32| (f64::from(c) / 32767.0).max(-1.0);
    let want: Vec<DVec3> = signed
        .iter()
        .map(|p| DVec3::new(f(p[0]), f(p[1]), f(p[2])))
        .collect();
    assert_eq!(positions(&read, 0), want);
    // Not normalized: the integers themselves, then the node's scale.
    let want: Vec<DVec3> = unsigned
        .iter()
        .map(|p| DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64) * 0.5)
        .collect();
    assert_eq!(positions(&read, 1), want);
    let normals = read.meshes[0].mesh.normals.as_ref().unwrap();
    assert_eq!(normals, &vec![DVec3::Z; 3]);
    let uvs = &read.meshes[0].mesh.uvs[0];
    assert_eq!(
        uvs.iter().map(|v| v.to_array()).collect::<Vec<_>>(),
        vec![[2.0, 0.0], [0.0, 3.0], [255.0, 255.0]]
    );

    // Without the extension, the loader's checks stand, and say why.
    let mut plain = Doc {
        root: doc.root.clone(),
        bin: doc.bin.clone(),
    };
    plain.root.as_object_mut().unwrap().remove("extensionsUsed");
    plain
        .root
        .as_object_mut()
        .unwrap()
        .remove("extensionsRequired");
    let e = error_of(
        &plain,
        Container::Glb,
        "meshes[0].primitives[0].attributes.POSITION",
    );
    assert!(
        e.message.contains("is normalized SHORT, expected FLOAT"),
        "{e}"
    );
    assert!(e.message.contains("KHR_mesh_quantization allows it"), "{e}");
    // A type the extension does not allow either: NORMAL as unsigned bytes.
    let mut bad = Doc {
        root: doc.root.clone(),
        bin: doc.bin.clone(),
    };
    bad.root["accessors"][normal]["componentType"] = json!(UNSIGNED_BYTE);
    let e = error_of(
        &bad,
        Container::Glb,
        "meshes[0].primitives[0].attributes.NORMAL",
    );
    assert!(
        e.message
            .contains("is normalized UNSIGNED_BYTE, expected FLOAT, normalized BYTE"),
        "{e}"
    );
}

/// ToyCar's normal map: KHR_texture_transform's `texCoord` (here 1)
/// overrides the normalTexture's own (0); equal to it, it changes nothing.
#[test]
fn texture_transform_tex_coord_overrides_the_normal_maps() {
    for (set, want) in [(json!(1), 1), (json!(0), 0)] {
        let mut doc = material_doc(json!([{
            "normalTexture": { "index": 0, "texCoord": 0,
                "extensions": { "KHR_texture_transform": { "texCoord": set, "scale": [2, 2] } } }
        }]));
        doc.root["textures"] = json!([{ "source": 0 }]);
        doc.root["images"] = json!([{ "uri": png_uri(1, 1) }]);
        let uv = doc.root["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"].clone();
        doc.root["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_1"] = uv;
        let loaded = load_doc(&doc, &LoadOptions::default());
        let (normal, _) = loaded.scene.objects[0].maps.normal.unwrap();
        assert_eq!(normal.tex_coord, want);
        assert_eq!(normal.transform.scale.to_array(), [2.0, 2.0]);
    }
}

#[test]
fn static_morph_weights_blend_positions_and_normals() {
    let mut doc = Doc::new();
    let pos = doc.vec3(&TRI);
    let nrm = doc.vec3(&[[0.0, 0.0, 1.0]; 3]);
    let d0 = [[0.0, 0.0, 2.0], [1.0, 0.0, 0.0], [0.0, -4.0, 0.0]];
    let d1 = [[8.0, 0.0, 0.0], [0.0, 8.0, 0.0], [0.0, 0.0, 8.0]];
    let n0 = [[1.0, 0.0, 0.0]; 3];
    let (t0, t1, tn) = (doc.vec3(&d0), doc.vec3(&d1), doc.vec3(&n0));
    let mesh = doc.push(
        "meshes",
        json!({ "primitives": [{ "attributes": { "POSITION": pos, "NORMAL": nrm },
                                 "targets": [{ "POSITION": t0, "NORMAL": tn }, { "POSITION": t1 }] }],
                "weights": [0.5, 0.25] }),
    );
    // One node with the mesh's weights, one with its own.
    doc.root_node(json!({ "mesh": mesh }));
    doc.root_node(json!({ "mesh": mesh, "weights": [1.0, 0.0] }));
    let (_dir, read) = read_doc(&doc, Container::Glb);
    let v = |a: [f32; 3]| DVec3::from_array(a.map(f64::from));
    for (m, w) in [(0, [0.5, 0.25]), (1, [1.0, 0.0])] {
        let want: Vec<DVec3> = (0..3)
            .map(|i| v(TRI[i]) + w[0] * v(d0[i]) + w[1] * v(d1[i]))
            .collect();
        assert_eq!(positions(&read, m), want, "mesh {m}");
        let n = (DVec3::Z + w[0] * DVec3::X).normalize();
        let normals = read.meshes[m].mesh.normals.as_ref().unwrap();
        assert!(
            normals.iter().all(|x| (*x - n).length() < 1e-12),
            "{normals:?}"
        );
    }
    // Static weights are not an animation: no note.
    assert!(read.notes.is_empty(), "{:?}", read.notes);
}

/// A cube's corners, for instancing.
const CUBE: [[f32; 3]; 8] = [
    [-1.0, -1.0, -1.0],
    [1.0, -1.0, -1.0],
    [1.0, 1.0, -1.0],
    [-1.0, 1.0, -1.0],
    [-1.0, -1.0, 1.0],
    [1.0, -1.0, 1.0],
    [1.0, 1.0, 1.0],
    [-1.0, 1.0, 1.0],
];
const CUBE_INDICES: [u16; 36] = [
    0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4, 3, 7, 6, 3, 6, 2, 0, 4, 7, 0, 7, 3, 1, 2,
    6, 1, 6, 5,
];

/// An instance's translation, rotation and scale.
type Trs = ([f32; 3], [f32; 4], [f32; 3]);

/// `n` cubes' instance transforms.
fn instance_trs(n: usize) -> Vec<Trs> {
    (0..n)
        .map(|i| {
            let a = i as f32 * 0.7;
            let (s, c) = (a * 0.5).sin_cos();
            let t = [
                (i % 5) as f32 * 3.0,
                (i / 5 % 5) as f32 * 3.0,
                (i / 25) as f32 * 3.0,
            ];
            (t, [0.0, s, 0.0, c], [0.5 + 0.1 * (i % 3) as f32; 3])
        })
        .collect()
}

/// `n` cubes as one EXT_mesh_gpu_instancing node (`instanced`) or as
/// `n` child nodes, under a parent that moves them all.
pub(crate) fn cubes_doc(n: usize, instanced: bool) -> Doc {
    let mut doc = Doc::new();
    let pos = doc.vec3(&CUBE);
    let ix = doc.indices_u16(&CUBE_INDICES);
    let mesh = doc.push(
        "meshes",
        json!({ "primitives": [{ "attributes": { "POSITION": pos }, "indices": ix }] }),
    );
    let trs = instance_trs(n);
    let parent = json!({ "translation": [-6, -6, -6], "rotation": [0, 0, 0.3826834, 0.9238795] });
    if instanced {
        let floats = |f: &dyn Fn(&Trs) -> Vec<f32>| -> Vec<u8> {
            trs.iter()
                .flat_map(f)
                .flat_map(|x| x.to_le_bytes())
                .collect()
        };
        let mut acc = |bytes: Vec<u8>, kind: &str| doc.accessor(&bytes, 5126, n, kind, false);
        let t = acc(floats(&|x| x.0.to_vec()), "VEC3");
        let r = acc(floats(&|x| x.1.to_vec()), "VEC4");
        let s = acc(floats(&|x| x.2.to_vec()), "VEC3");
        doc.root["extensionsUsed"] = json!(["EXT_mesh_gpu_instancing"]);
        let mut node = parent;
        node["mesh"] = json!(mesh);
        node["extensions"] = json!({ "EXT_mesh_gpu_instancing": {
            "attributes": { "TRANSLATION": t, "ROTATION": r, "SCALE": s } } });
        doc.root_node(node);
    } else {
        let first = doc.root["nodes"].as_array().unwrap().len();
        let children: Vec<usize> = (0..n).map(|i| first + i).collect();
        for (t, r, s) in &trs {
            doc.push(
                "nodes",
                json!({ "mesh": mesh, "translation": t, "rotation": r, "scale": s }),
            );
        }
        let mut node = parent;
        node["children"] = json!(children);
        doc.root_node(node);
    }
    doc
}

#[test]
fn instancing_places_each_instance_as_the_same_cubes_written_as_nodes() {
    let n = 125;
    let (_d1, instanced) = read_doc(&cubes_doc(n, true), Container::Glb);
    let (_d2, nodes) = read_doc(&cubes_doc(n, false), Container::Glb);
    assert_eq!(instanced.meshes.len(), n);
    assert_eq!(nodes.meshes.len(), n);
    // Instance i: the node's transform times T · R · S, computed here.
    let (z, w) = (f64::from(0.3826834f32), f64::from(0.9238795f32));
    let node = DMat4::from_rotation_translation(
        DQuat::from_xyzw(0.0, 0.0, z, w).normalize(),
        DVec3::splat(-6.0),
    );
    for (i, (t, r, s)) in instance_trs(n).into_iter().enumerate() {
        let d = |a: [f32; 3]| DVec3::from_array(a.map(f64::from));
        let q = DQuat::from_array(r.map(f64::from)).normalize();
        let m = node * DMat4::from_scale_rotation_translation(d(s), q, d(t));
        for (k, p) in instanced.meshes[i].mesh.positions.iter().enumerate() {
            let want = m.transform_point3(d(CUBE[k]));
            assert!(
                (*p - want).length() < 1e-9,
                "instance {i} vertex {k}: {p} != {want}"
            );
            assert!((*p - nodes.meshes[i].mesh.positions[k]).length() < 1e-9);
        }
        assert_eq!(
            instanced.meshes[i].mesh.indices,
            nodes.meshes[i].mesh.indices
        );
    }
    // Charged before any is read: 125 cubes need more than 125 × 8 vertices.
    let dir = TempDir::new().unwrap();
    let path = cubes_doc(n, true).write(dir.path(), "m", Container::Glb);
    let opts = LoadOptions {
        max_scene_bytes: 60_000,
        ..Default::default()
    };
    let e = gltf::read_with(&path, &loaders::guard::Guard::new(&path, &opts)).unwrap_err();
    assert_eq!(
        e.field, "nodes[0].extensions.EXT_mesh_gpu_instancing",
        "{e}"
    );
    assert!(
        e.message
            .starts_with("125 instances of meshes[0].primitives[0]: "),
        "{e}"
    );
    assert!(e.message.contains("memory budget"), "{e}");
    let ok = LoadOptions {
        max_scene_bytes: 1 << 20,
        ..Default::default()
    };
    gltf::read_with(&path, &loaders::guard::Guard::new(&path, &ok)).unwrap();
}

/// Writes `doc` as a GLB whose buffers are `buffers` (the BIN chunk is
/// `doc.bin`, buffer 0).
fn write_glb(doc: &Doc, buffers: Value, dir: &Path) -> std::path::PathBuf {
    let mut root = doc.root.clone();
    root["buffers"] = buffers;
    let path = dir.join("m.glb");
    std::fs::write(
        &path,
        glb(serde_json::to_string(&root).unwrap().as_bytes(), &doc.bin),
    )
    .unwrap();
    path
}

/// The Duck-like mesh of `meshopt_views_decode_to_the_plain_data`: a grid
/// of vertices with positions and normals (stride 24) and its triangles.
fn grid() -> (Vec<[f32; 6]>, Vec<u32>) {
    let n = 12;
    let mut vertices = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let (x, y) = (i as f32 / 4.0, j as f32 / 4.0);
            let z = (x * 1.3).sin() * (y * 0.7).cos();
            vertices.push([x, y, z, 0.0, 0.0, 1.0]);
        }
    }
    let mut indices = Vec::new();
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let a = j * n + i;
            indices.extend([a, a + 1, a + n, a + 1, a + n + 1, a + n]);
        }
    }
    (vertices, indices)
}

/// The grid as a plain file, or with its two views compressed by the
/// reference encoder into buffer 0 and a fallback buffer 1 without data.
fn grid_doc(compressed: bool) -> (Doc, Value) {
    let (vertices, indices) = grid();
    let raw_v: Vec<u8> = vertices
        .iter()
        .flatten()
        .flat_map(|x| x.to_le_bytes())
        .collect();
    let raw_i: Vec<u8> = indices.iter().flat_map(|x| x.to_le_bytes()).collect();
    let mut doc = Doc::new();
    let (vview, iview) = if compressed {
        let enc_v = meshopt::encoding::encode_vertex_buffer(&vertices).unwrap();
        let enc_i = meshopt::encoding::encode_index_buffer(&indices, vertices.len()).unwrap();
        let a = doc.view(&enc_v);
        let b = doc.view(&enc_i);
        let ext = |view: usize, len: usize, stride: usize, count: usize, mode: &str| {
            let v = &doc.root["bufferViews"][view];
            json!({ "buffer": 1, "byteLength": stride * count, "byteStride": stride,
                    "extensions": { "EXT_meshopt_compression": {
                        "buffer": 0, "byteOffset": v["byteOffset"], "byteLength": len,
                        "byteStride": stride, "count": count, "mode": mode } } })
        };
        let va = ext(a, enc_v.len(), 24, vertices.len(), "ATTRIBUTES");
        let vb = ext(b, enc_i.len(), 4, indices.len(), "TRIANGLES");
        doc.root["bufferViews"][a] = va;
        doc.root["bufferViews"][b] = vb;
        doc.root["extensionsUsed"] = json!(["EXT_meshopt_compression"]);
        doc.root["extensionsRequired"] = json!(["EXT_meshopt_compression"]);
        (a, b)
    } else {
        (doc.view(&raw_v), doc.view(&raw_i))
    };
    doc.root["bufferViews"][vview]["byteStride"] = json!(24);
    let (lo, hi) = ([0.0, 0.0, -1.0], [11.0 / 4.0, 11.0 / 4.0, 1.0]);
    let p = doc.push(
        "accessors",
        json!({ "bufferView": vview, "componentType": 5126, "count": vertices.len(),
                "type": "VEC3", "min": lo, "max": hi }),
    );
    let n = doc.push(
        "accessors",
        json!({ "bufferView": vview, "byteOffset": 12, "componentType": 5126,
                "count": vertices.len(), "type": "VEC3" }),
    );
    let ix = doc.push(
        "accessors",
        json!({ "bufferView": iview, "componentType": 5125, "count": indices.len(),
                "type": "SCALAR" }),
    );
    doc.mesh_node(
        json!([{ "attributes": { "POSITION": p, "NORMAL": n }, "indices": ix }]),
        json!({}),
    );
    let len = doc.bin.len();
    let buffers = match compressed {
        true => json!([{ "byteLength": len }, { "byteLength": raw_v.len() + raw_i.len(),
            "extensions": { "EXT_meshopt_compression": { "fallback": true } } }]),
        false => json!([{ "byteLength": len }]),
    };
    (doc, buffers)
}

#[test]
fn meshopt_views_decode_to_the_plain_data() {
    let dir = TempDir::new().unwrap();
    let (plain, b) = grid_doc(false);
    let plain = gltf::read(&write_glb(&plain, b, dir.path())).unwrap();
    let dir2 = TempDir::new().unwrap();
    let (packed, b) = grid_doc(true);
    let path = write_glb(&packed, b.clone(), dir2.path());
    let read = gltf::read(&path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        read.meshes[0].mesh.positions,
        plain.meshes[0].mesh.positions
    );
    assert_eq!(read.meshes[0].mesh.normals, plain.meshes[0].mesh.normals);
    // The index codec may rotate a triangle's corners, keeping its winding.
    let rotated = |t: &[u32; 3]| {
        let k = (0..3).min_by_key(|&k| t[k]).unwrap();
        [t[k], t[(k + 1) % 3], t[(k + 2) % 3]]
    };
    let canonical = |m: &gltf::GltfDocument| -> Vec<[u32; 3]> {
        m.meshes[0].mesh.indices.iter().map(rotated).collect()
    };
    assert_eq!(canonical(&read), canonical(&plain));
    assert_eq!(read.meshes[0].mesh.indices.len(), 11 * 11 * 2);

    // A view into the fallback buffer that is not compressed has no data.
    let mut bad = packed.root.clone();
    bad["bufferViews"][1]
        .as_object_mut()
        .unwrap()
        .remove("extensions");
    let doc = Doc {
        root: bad,
        bin: packed.bin.clone(),
    };
    let e = gltf::read(&write_glb(&doc, b.clone(), dir2.path())).unwrap_err();
    assert_eq!(e.field, "bufferViews[1]", "{e}");
    assert!(e.message.contains("fallback buffer"), "{e}");

    // A bomb: a few bytes claiming 2^40 decoded bytes are refused from the
    // declared size, before anything is allocated.
    let mut bomb = packed.root.clone();
    let count = 1u64 << 32;
    bomb["bufferViews"][0]["byteLength"] = json!(count * 252);
    bomb["bufferViews"][0]["byteStride"] = json!(252);
    let ext = &mut bomb["bufferViews"][0]["extensions"]["EXT_meshopt_compression"];
    ext["count"] = json!(count);
    ext["byteStride"] = json!(252);
    let doc = Doc {
        root: bomb,
        bin: packed.bin.clone(),
    };
    let e = gltf::read(&write_glb(&doc, b.clone(), dir2.path())).unwrap_err();
    assert_eq!(
        e.field, "bufferViews[0].extensions.EXT_meshopt_compression.count",
        "{e}"
    );
    assert!(e.message.contains("memory budget"), "{e}");

    // Corrupt compressed bytes: the decoder's error, named.
    let mut corrupt = packed.bin.clone();
    corrupt[0] ^= 0xff;
    let doc = Doc {
        root: packed.root.clone(),
        bin: corrupt,
    };
    let e = gltf::read(&write_glb(&doc, b, dir2.path())).unwrap_err();
    assert_eq!(
        e.field, "bufferViews[0].extensions.EXT_meshopt_compression",
        "{e}"
    );
    assert!(e.message.contains("malformed"), "{e}");
}

/// Two cameras, the second under an animated node, and a triangle.
fn cameras_doc() -> Doc {
    let mut doc = Doc::new();
    let pos = doc.vec3(&TRI);
    doc.mesh_node(json!([{ "attributes": { "POSITION": pos } }]), json!({}));
    doc.root["cameras"] = json!([
        { "type": "perspective", "name": "Front", "perspective": { "yfov": 0.5, "znear": 0.1 } },
        { "type": "perspective", "name": "Top", "perspective": { "yfov": 0.7, "znear": 0.1 } }
    ]);
    doc.root_node(json!({ "camera": 0, "translation": [0, 0, 9] }));
    let parent = doc.root_node(json!({ "translation": [0, 5, 0] }));
    let child = doc.push(
        "nodes",
        json!({ "camera": 1, "translation": [0, 4, 0], "rotation": [-FRAC_1_SQRT_2, 0, 0, FRAC_1_SQRT_2] }),
    );
    doc.root["nodes"][parent]["children"] = json!([child]);
    let times = doc.view(&[0u8; 4]);
    let time = doc.push(
        "accessors",
        json!({ "bufferView": times, "componentType": 5126, "count": 1, "type": "SCALAR" }),
    );
    let values = doc.vec3(&[[0.0, 5.0, 0.0]]);
    doc.root["animations"] = json!([{
        "channels": [{ "sampler": 0, "target": { "node": parent, "path": "translation" } }],
        "samplers": [{ "input": time, "output": values }]
    }]);
    doc
}

fn load_with(doc: &Doc, camera: CameraChoice) -> Result<Loaded, penumbra::SceneError> {
    let dir = TempDir::new().unwrap();
    let path = doc.write(dir.path(), "model", Container::Glb);
    let opts = LoadOptions {
        camera,
        ..Default::default()
    };
    loaders::load_scene(&path, &opts)
}

#[test]
fn camera_option_picks_a_camera_by_index_or_name_or_the_framing_view() {
    let doc = cameras_doc();
    let first = load_with(&doc, CameraChoice::File).unwrap();
    assert_eq!(first.scene.camera.position, DVec3::new(0.0, 0.0, 9.0));
    for choice in [CameraChoice::parse("1"), CameraChoice::parse("Top")] {
        let top = load_with(&doc, choice).unwrap();
        assert_eq!(top.scene.camera.position, DVec3::new(0.0, 9.0, 0.0));
        // The animated parent: its static pose, and a note that says so.
        assert_eq!(
            notes_with(
                &top.notes,
                "cameras[1] 'Top' hangs under an animated node: using its static pose"
            ),
            1,
            "{:?}",
            top.notes
        );
    }
    assert_eq!(notes_with(&first.notes, "hangs under"), 0);
    let framing = load_with(&doc, CameraChoice::parse("framing")).unwrap();
    assert_eq!(
        notes_with(&framing.notes, "--camera framing: using a framing camera"),
        1
    );
    assert_eq!(
        framing.scene.camera.projection,
        penumbra::scene::Projection::Perspective { vfov_deg: 45.0 }
    );
    for (choice, text) in [
        (
            "7",
            "--camera 7: no node of the default scene places cameras[7]",
        ),
        ("Side", "--camera 'Side': no camera of that name"),
    ] {
        let e = load_with(&doc, CameraChoice::parse(choice)).unwrap_err();
        assert_eq!(e.field, "cameras", "{e}");
        assert!(e.message.contains(text), "{e}");
        assert!(
            e.message
                .contains("its cameras: cameras[0] 'Front', cameras[1] 'Top'"),
            "{e}"
        );
    }
}

/// The share of the frame's limiting dimension that the projected corners
/// of `lo..hi` span, checking that all are inside the frame.
fn fill(cam: &Camera, lo: DVec3, hi: DVec3) -> f64 {
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for k in 0..8 {
        let pick = |bit: usize, a: f64, b: f64| if k >> bit & 1 == 0 { a } else { b };
        let c = DVec3::new(
            pick(0, lo.x, hi.x),
            pick(1, lo.y, hi.y),
            pick(2, lo.z, hi.z),
        );
        let (x, y) = cam.project(c).expect("in front of the camera");
        (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
    }
    let (w, h) = (f64::from(cam.width), f64::from(cam.height));
    assert!(
        x0 >= 0.0 && x1 <= w && y0 >= 0.0 && y1 <= h,
        "[{x0}, {x1}] × [{y0}, {y1}] in {w}×{h}"
    );
    ((x1 - x0) / w).max((y1 - y0) / h)
}

fn bounds(loaded: &Loaded) -> (DVec3, DVec3) {
    loaded
        .scene
        .objects
        .iter()
        .filter_map(|o| match &o.shape {
            Shape::Mesh(m) => m.bounds(),
            _ => None,
        })
        .reduce(|(a, b), (c, d)| (a.min(c), b.max(d)))
        .unwrap()
}

#[test]
fn the_framing_camera_fills_the_frame_with_the_bounding_box() {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/khronos");
    let models = [
        "Duck/Duck.gltf",
        "BoxTextured/BoxTextured.gltf",
        "TextureSettingsTest/TextureSettingsTest.gltf",
    ];
    let dir = TempDir::new().unwrap();
    // A long bar, a tall tower and 125 cubes, written here.
    let mut shapes = Vec::new();
    for (name, scale) in [("bar", [20.0, 1.0, 2.0]), ("tower", [1.0, 30.0, 1.5])] {
        let mut doc = Doc::new();
        let pos = doc.vec3(&CUBE);
        let ix = doc.indices_u16(&CUBE_INDICES);
        doc.mesh_node(
            json!([{ "attributes": { "POSITION": pos }, "indices": ix }]),
            json!({ "scale": scale, "translation": [100, -3, 7] }),
        );
        shapes.push(doc.write(dir.path(), name, Container::Glb));
    }
    shapes.push(cubes_doc(125, true).write(dir.path(), "cubes", Container::Glb));
    let paths = models.iter().map(|m| data.join(m)).chain(shapes);
    for path in paths {
        for (width, height) in [
            (Some(640), Some(480)),
            (Some(200), Some(900)),
            (Some(1000), Some(100)),
        ] {
            let opts = LoadOptions {
                width,
                height,
                camera: CameraChoice::Framing,
                ..Default::default()
            };
            let loaded = loaders::load_scene(&path, &opts).unwrap_or_else(|e| panic!("{e}"));
            let (lo, hi) = bounds(&loaded);
            let f = fill(&loaded.scene.camera, lo, hi);
            assert!(
                (0.80..=0.95).contains(&f),
                "{}: {width:?}×{height:?} fills {f}",
                path.display()
            );
        }
    }
}

#[test]
fn a_flat_chart_is_seen_face_on_from_its_front() {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/khronos");
    let chart = data.join("TextureCoordinateTest/TextureCoordinateTest.gltf");
    let loaded = loaders::load_scene(&chart, &LoadOptions::default()).unwrap();
    let cam = loaded.scene.camera;
    let (lo, hi) = bounds(&loaded);
    let f = fill(&cam, lo, hi);
    assert!((0.80..=0.95).contains(&f), "fills {f}");
    let view = -cam.orientation.col(2);
    // Every triangle's plane is square to the view within 2°. Its back
    // plane (area 4) faces +Z, its four labelled quads (area 1 each) −Z:
    // a tie, so it is seen from +Z, glTF's front.
    assert!(view.dot(DVec3::NEG_Z) > 2f64.to_radians().cos(), "{view}");
    for o in &loaded.scene.objects {
        let Shape::Mesh(m) = &o.shape else { continue };
        for t in &m.indices {
            let [a, b, c] = t.map(|i| m.positions[i as usize]);
            let n = (b - a).cross(c - a).normalize();
            let angle = n.dot(view).abs().clamp(-1.0, 1.0).acos().to_degrees();
            assert!(angle < 2.0, "a triangle at {angle}° from the view");
        }
    }
    // A flat chart lying on the floor, facing up: seen from above.
    let mut doc = Doc::new();
    let pos = doc.vec3(&[
        [0.0, 0.0, 0.0],
        [4.0, 0.0, 0.0],
        [4.0, 0.0, -3.0],
        [0.0, 0.0, -3.0],
    ]);
    let ix = doc.indices_u16(&[0, 1, 2, 0, 2, 3]);
    doc.mesh_node(
        json!([{ "attributes": { "POSITION": pos }, "indices": ix }]),
        json!({}),
    );
    let floor = load_doc(&doc, &LoadOptions::default());
    let view = -floor.scene.camera.orientation.col(2);
    assert!(view.dot(DVec3::NEG_Y) > 2f64.to_radians().cos(), "{view}");
    let (lo, hi) = bounds(&floor);
    let f = fill(&floor.scene.camera, lo, hi);
    assert!((0.80..=0.95).contains(&f), "fills {f}");
}

/// meshopt's filters: positions through the EXPONENTIAL filter (15-bit
/// mantissas) and normals through the OCTAHEDRAL one (8-bit normalized
/// bytes, as gltfpack `-cc` writes), both encoded here by the reference
/// encoder; the loader's decode must give the positions within their
/// mantissa's precision and the normals within the bytes' (a degree).
#[test]
fn meshopt_filters_decode_positions_and_normals() {
    use meshopt::encoding::{encode_filter_exp, encode_filter_oct, EncodeExpMode};
    let (vertices, indices) = grid();
    let positions: Vec<[f32; 3]> = vertices.iter().map(|v| [v[0], v[1], v[2]]).collect();
    // Unit normals tilted every way.
    let normals: Vec<[f32; 4]> = vertices
        .iter()
        .map(|v| {
            let n = glam::Vec3::new(v[0] - 1.4, v[1] - 1.3, 1.0).normalize();
            [n.x, n.y, n.z, 0.0]
        })
        .collect();
    let exp = encode_filter_exp(&positions, 15, EncodeExpMode::Separate);
    let oct = encode_filter_oct::<i8>(&normals, 8);
    let enc_p = meshopt::encoding::encode_vertex_buffer(&exp).unwrap();
    let enc_n = meshopt::encoding::encode_vertex_buffer(&oct).unwrap();
    let raw_i: Vec<u8> = indices.iter().flat_map(|x| x.to_le_bytes()).collect();
    let mut doc = Doc::new();
    let (a, b) = (doc.view(&enc_p), doc.view(&enc_n));
    let ix_view = doc.view(&raw_i);
    let n = vertices.len();
    let ext = |doc: &Doc, view: usize, len: usize, stride: usize, filter: &str| {
        let v = &doc.root["bufferViews"][view];
        json!({ "buffer": 1, "byteLength": stride * n, "byteStride": stride,
                "extensions": { "EXT_meshopt_compression": {
                    "buffer": 0, "byteOffset": v["byteOffset"], "byteLength": len,
                    "byteStride": stride, "count": n, "mode": "ATTRIBUTES", "filter": filter } } })
    };
    doc.root["bufferViews"][a] = ext(&doc, a, enc_p.len(), 12, "EXPONENTIAL");
    doc.root["bufferViews"][b] = ext(&doc, b, enc_n.len(), 4, "OCTAHEDRAL");
    doc.root["extensionsUsed"] = json!(["EXT_meshopt_compression", "KHR_mesh_quantization"]);
    let p = doc.push(
        "accessors",
        json!({ "bufferView": a, "componentType": 5126, "count": n, "type": "VEC3",
                "min": [0, 0, -1], "max": [3, 3, 1] }),
    );
    let nrm = doc.push(
        "accessors",
        json!({ "bufferView": b, "componentType": BYTE, "normalized": true, "count": n,
                "type": "VEC3" }),
    );
    let ix = doc.push(
        "accessors",
        json!({ "bufferView": ix_view, "componentType": 5125, "count": indices.len(),
                "type": "SCALAR" }),
    );
    doc.mesh_node(
        json!([{ "attributes": { "POSITION": p, "NORMAL": nrm }, "indices": ix }]),
        json!({}),
    );
    let len = doc.bin.len();
    let buffers = json!([{ "byteLength": len }, { "byteLength": 16 * n,
        "extensions": { "EXT_meshopt_compression": { "fallback": true } } }]);
    let dir = TempDir::new().unwrap();
    let read = gltf::read(&write_glb(&doc, buffers, dir.path())).unwrap_or_else(|e| panic!("{e}"));
    let mesh = &read.meshes[0].mesh;
    for (k, q) in mesh.positions.iter().enumerate() {
        let want = DVec3::from_array(positions[k].map(f64::from));
        // 15-bit mantissas: relative error below 2^-14 per component.
        let tol = want.abs().max_element() * 2f64.powi(-14) + 1e-12;
        assert!(
            (*q - want).abs().max_element() <= tol,
            "vertex {k}: {q} != {want}"
        );
    }
    for (k, got) in mesh.normals.as_ref().unwrap().iter().enumerate() {
        let want = DVec3::new(
            normals[k][0].into(),
            normals[k][1].into(),
            normals[k][2].into(),
        );
        let angle = got.dot(want).clamp(-1.0, 1.0).acos().to_degrees();
        assert!(angle < 1.0, "normal {k}: {angle}° off");
    }
}
