//! The glTF loader against small files written here by hand (JSON text and
//! little-endian buffers, as `.gltf` with a data: URI or an external `.bin`,
//! and as `.glb`), and against the bunny files in shared/data.

use std::f64::consts::{FRAC_PI_2, FRAC_PI_4};
use std::path::{Path, PathBuf};

use glam::{DMat3, DVec3, Vec3};
use penumbra::loaders::gltf::{self, GltfDocument};
use penumbra::loaders::{GltfMaterials, LoadOptions, Loaded};
use penumbra::scene::{LightKind, Projection, Shader, Shape};
use penumbra::SceneError;
use serde_json::{json, Value};
use tempfile::TempDir;

/// A glTF document under construction: the JSON root and one binary buffer.
pub(crate) struct Doc {
    pub(crate) root: Value,
    pub(crate) bin: Vec<u8>,
}

/// How the buffer is stored.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Container {
    Embedded,
    External,
    Glb,
}

impl Doc {
    pub(crate) fn new() -> Self {
        let root = json!({
            "asset": { "version": "2.0" },
            "scene": 0,
            "scenes": [{ "nodes": [] }],
            "nodes": [], "meshes": [], "accessors": [], "bufferViews": []
        });
        Doc {
            root,
            bin: Vec::new(),
        }
    }

    pub(crate) fn push(&mut self, array: &str, item: Value) -> usize {
        let list = self.root[array].as_array_mut();
        let list = match list {
            Some(list) => list,
            None => {
                self.root[array] = json!([]);
                self.root[array].as_array_mut().unwrap()
            }
        };
        list.push(item);
        list.len() - 1
    }

    /// Appends bytes (4-aligned) as a new buffer view.
    pub(crate) fn view(&mut self, bytes: &[u8]) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let offset = self.bin.len();
        self.bin.extend_from_slice(bytes);
        self.push(
            "bufferViews",
            json!({ "buffer": 0, "byteOffset": offset, "byteLength": bytes.len() }),
        )
    }

    pub(crate) fn vec3(&mut self, data: &[[f32; 3]]) -> usize {
        let bytes: Vec<u8> = data
            .iter()
            .flatten()
            .flat_map(|x| x.to_le_bytes())
            .collect();
        let view = self.view(&bytes);
        // glTF requires min and max on POSITION accessors (NaN is skipped by f32::min/max).
        let min = (0..3)
            .map(|k| data.iter().fold(f32::MAX, |m, v| m.min(v[k])))
            .collect::<Vec<_>>();
        let max = (0..3)
            .map(|k| data.iter().fold(f32::MIN, |m, v| m.max(v[k])))
            .collect::<Vec<_>>();
        self.push(
            "accessors",
            json!({ "bufferView": view, "componentType": 5126, "count": data.len(), "type": "VEC3",
                    "min": min, "max": max }),
        )
    }

    pub(crate) fn indices_u16(&mut self, ix: &[u16]) -> usize {
        let bytes: Vec<u8> = ix.iter().flat_map(|x| x.to_le_bytes()).collect();
        let view = self.view(&bytes);
        self.push(
            "accessors",
            json!({ "bufferView": view, "componentType": 5123, "count": ix.len(), "type": "SCALAR" }),
        )
    }

    fn indices_u32(&mut self, ix: &[u32]) -> usize {
        let bytes: Vec<u8> = ix.iter().flat_map(|x| x.to_le_bytes()).collect();
        let view = self.view(&bytes);
        self.push(
            "accessors",
            json!({ "bufferView": view, "componentType": 5125, "count": ix.len(), "type": "SCALAR" }),
        )
    }

    /// A mesh of these primitives on a new root node with extra node fields.
    pub(crate) fn mesh_node(&mut self, primitives: Value, node: Value) -> usize {
        let mesh = self.push("meshes", json!({ "primitives": primitives }));
        let mut node = node;
        node["mesh"] = json!(mesh);
        self.root_node(node)
    }

    pub(crate) fn root_node(&mut self, node: Value) -> usize {
        let n = self.push("nodes", node);
        self.root["scenes"][0]["nodes"]
            .as_array_mut()
            .unwrap()
            .push(json!(n));
        n
    }

    /// Writes the document into `dir` as `name` plus the extension.
    pub(crate) fn write(&self, dir: &Path, name: &str, how: Container) -> PathBuf {
        let mut root = self.root.clone();
        let len = self.bin.len();
        match how {
            Container::Embedded => {
                let uri = format!(
                    "data:application/octet-stream;base64,{}",
                    crate::base64::encode(&self.bin)
                );
                root["buffers"] = json!([{ "byteLength": len, "uri": uri }]);
            }
            Container::External => {
                std::fs::write(dir.join(format!("{name}.bin")), &self.bin).unwrap();
                root["buffers"] = json!([{ "byteLength": len, "uri": format!("{name}.bin") }]);
            }
            Container::Glb => root["buffers"] = json!([{ "byteLength": len }]),
        }
        let text = serde_json::to_string(&root).unwrap();
        let path = match how {
            Container::Glb => {
                let path = dir.join(format!("{name}.glb"));
                std::fs::write(&path, glb(text.as_bytes(), &self.bin)).unwrap();
                path
            }
            _ => {
                let path = dir.join(format!("{name}.gltf"));
                std::fs::write(&path, text).unwrap();
                path
            }
        };
        path
    }
}

pub(crate) fn glb(json: &[u8], bin: &[u8]) -> Vec<u8> {
    let pad = |data: &[u8], fill: u8| {
        let mut v = data.to_vec();
        while !v.len().is_multiple_of(4) {
            v.push(fill);
        }
        v
    };
    let (json, bin) = (pad(json, b' '), pad(bin, 0));
    let total = 12 + 8 + json.len() + if bin.is_empty() { 0 } else { 8 + bin.len() };
    let mut out = Vec::new();
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    if !bin.is_empty() {
        out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(&bin);
    }
    out
}

pub(crate) const TRI: [[f32; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];

/// One triangle on a root node with the given fields.
fn triangle_doc(node: Value) -> Doc {
    let mut doc = Doc::new();
    let pos = doc.vec3(&TRI);
    doc.mesh_node(json!([{ "attributes": { "POSITION": pos } }]), node);
    doc
}

pub(crate) fn read_doc(doc: &Doc, how: Container) -> (TempDir, GltfDocument) {
    let dir = TempDir::new().unwrap();
    let path = doc.write(dir.path(), "model", how);
    let read = gltf::read(&path).unwrap_or_else(|e| panic!("{e}"));
    (dir, read)
}

pub(crate) fn load_doc(doc: &Doc, opts: &LoadOptions) -> Loaded {
    let dir = TempDir::new().unwrap();
    let path = doc.write(dir.path(), "model", Container::Glb);
    let loaded = gltf::load(&path, opts).unwrap_or_else(|e| panic!("{e}"));
    loaded.scene.validate().unwrap_or_else(|e| panic!("{e}"));
    loaded
}

/// The error for this document, checking that it names the file and `field`.
pub(crate) fn error_of(doc: &Doc, how: Container, field: &str) -> SceneError {
    let dir = TempDir::new().unwrap();
    let path = doc.write(dir.path(), "model", how);
    let err = gltf::read(&path).expect_err("expected an error");
    let text = err.to_string();
    assert!(text.contains(&path.display().to_string()), "{text}");
    assert_eq!(err.field, field, "{text}");
    assert!(text.contains(field), "{text}");
    err
}

fn close(a: DVec3, b: DVec3, tol: f64) -> bool {
    (a - b).abs().max_element() <= tol
}

fn assert_close(a: DVec3, b: DVec3, tol: f64) {
    assert!(close(a, b, tol), "{a} != {b}");
}

pub(crate) fn notes_with(notes: &[String], text: &str) -> usize {
    notes.iter().filter(|n| n.contains(text)).count()
}

#[test]
fn indexed_and_non_indexed_triangles_in_every_container() {
    let mut doc = Doc::new();
    let quad = doc.vec3(&[
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
    ]);
    let ix = doc.indices_u16(&[0, 1, 2, 0, 2, 3]);
    let tri = doc.vec3(&TRI);
    let ix32 = doc.indices_u32(&[2, 1, 0]);
    doc.mesh_node(
        json!([
            { "attributes": { "POSITION": quad }, "indices": ix },
            { "attributes": { "POSITION": tri } },
            { "attributes": { "POSITION": tri }, "indices": ix32, "mode": 4 }
        ]),
        json!({ "name": "Quad" }),
    );
    for how in [Container::Embedded, Container::External, Container::Glb] {
        let (dir, read) = read_doc(&doc, how);
        assert_eq!(read.meshes.len(), 3, "{how:?}");
        assert_eq!(read.meshes[0].mesh.indices, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(read.meshes[0].mesh.positions[2], DVec3::new(1.0, 1.0, 0.0));
        assert_eq!(read.meshes[0].name, "node 'Quad' mesh 0 primitive 0");
        assert_eq!(read.meshes[1].mesh.indices, vec![[0, 1, 2]]);
        assert_eq!(read.meshes[2].mesh.indices, vec![[2, 1, 0]]);
        assert!(read.meshes[0].mesh.normals.is_none());
        assert!(read.camera.is_none() && read.lights.is_empty() && read.notes.is_empty());
        let ext = match how {
            Container::Glb => "glb",
            _ => "gltf",
        };
        let mut files = vec![dir.path().join(format!("model.{ext}"))];
        if let Container::External = how {
            files.push(dir.path().join("model.bin"));
        }
        assert_eq!(read.files, files);
    }
}

#[test]
fn strips_and_fans_follow_the_spec_vertex_order() {
    let mut doc = Doc::new();
    let pos = doc.vec3(&[
        [0.0; 3],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 2.0, 0.0],
    ]);
    let ix = doc.indices_u16(&[4, 3, 2, 1, 0]);
    doc.mesh_node(
        json!([
            { "attributes": { "POSITION": pos }, "mode": 5 },
            { "attributes": { "POSITION": pos }, "mode": 6 },
            { "attributes": { "POSITION": pos }, "mode": 5, "indices": ix },
            { "attributes": { "POSITION": pos }, "mode": 6, "indices": ix }
        ]),
        json!({}),
    );
    let (_dir, read) = read_doc(&doc, Container::Embedded);
    let tris: Vec<_> = read.meshes.iter().map(|m| m.mesh.indices.clone()).collect();
    assert_eq!(tris[0], vec![[0, 1, 2], [1, 3, 2], [2, 3, 4]]);
    assert_eq!(tris[1], vec![[1, 2, 0], [2, 3, 0], [3, 4, 0]]);
    assert_eq!(tris[2], vec![[4, 3, 2], [3, 1, 2], [2, 1, 0]]);
    assert_eq!(tris[3], vec![[3, 2, 4], [2, 1, 4], [1, 0, 4]]);
}

#[test]
fn node_hierarchy_composes_parent_and_child_transforms() {
    let mut doc = Doc::new();
    let pos = doc.vec3(&[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]);
    let mesh = doc.push(
        "meshes",
        json!({ "primitives": [{ "attributes": { "POSITION": pos } }] }),
    );
    let s = std::f64::consts::FRAC_1_SQRT_2;
    // Child: scale (1, 2, 1), then 90° about +Z, then move by (0, 1, 0).
    let child = doc.push(
        "nodes",
        json!({ "mesh": mesh, "translation": [0, 1, 0], "rotation": [0, 0, s, s], "scale": [1, 2, 1] }),
    );
    // Parent as a column-major matrix: uniform scale 2, then move by (10, 0, 0).
    let matrix = [2, 0, 0, 0, 0, 2, 0, 0, 0, 0, 2, 0, 10, 0, 0, 1];
    doc.root_node(json!({ "matrix": matrix, "children": [child] }));
    let (_dir, read) = read_doc(&doc, Container::Glb);
    let p = &read.meshes[0].mesh.positions;
    // (1,0,0) -> scale (1,0,0) -> rotate (0,1,0) -> +(0,1,0) = (0,2,0) -> parent (10,4,0).
    assert_close(p[0], DVec3::new(10.0, 4.0, 0.0), 1e-6);
    // (0,1,0) -> (0,2,0) -> (-2,0,0) -> (-2,1,0) -> (6,2,0).
    assert_close(p[1], DVec3::new(6.0, 2.0, 0.0), 1e-6);
    // (0,0,1) -> (0,0,1) -> (0,0,1) -> (0,1,1) -> (10,2,2).
    assert_close(p[2], DVec3::new(10.0, 2.0, 2.0), 1e-6);
    assert_eq!(
        read.meshes[0].name,
        format!("node {child} mesh 0 primitive 0")
    );
}

#[test]
fn negative_scale_flips_winding_to_keep_the_normal_side() {
    let doc = triangle_doc(json!({ "scale": [-1, 1, 1] }));
    let (_dir, read) = read_doc(&doc, Container::Glb);
    let mesh = &read.meshes[0].mesh;
    assert_eq!(mesh.indices, vec![[0, 2, 1]]);
    assert_eq!(mesh.positions[1], DVec3::new(-1.0, 0.0, 0.0));
    // Unmirrored the triangle faces +Z; the mirror image must too.
    assert!(mesh.triangle(0).geometric_normal().z > 0.0);
}

#[test]
fn normals_use_the_inverse_transpose_and_are_normalised() {
    let mut doc = Doc::new();
    let pos = doc.vec3(&TRI);
    let nrm = doc.vec3(&[[0.0, 0.0, 1.0], [1.0, 1.0, 0.0], [0.0, 0.0, 3.0]]);
    doc.mesh_node(
        json!([{ "attributes": { "POSITION": pos, "NORMAL": nrm } }]),
        json!({ "scale": [2, 1, 1], "rotation": [0, 0, 0, 1] }),
    );
    let (_dir, read) = read_doc(&doc, Container::Embedded);
    let normals = read.meshes[0].mesh.normals.clone().unwrap();
    assert_close(normals[0], DVec3::Z, 1e-12);
    // (1,1,0) under diag(2,1,1)^-T = diag(0.5,1,1): (0.5,1,0), normalised.
    assert_close(normals[1], DVec3::new(0.5, 1.0, 0.0).normalize(), 1e-12);
    assert_close(normals[2], DVec3::Z, 1e-12);

    // A node scaled to nothing hides its mesh: degenerate triangles, no normals.
    doc.root["nodes"][0]["scale"] = json!([0, 0, 0]);
    let (_dir, read) = read_doc(&doc, Container::Glb);
    assert!(read.meshes[0].mesh.normals.is_none());

    // A zero normal cannot be normalised.
    let mut doc = Doc::new();
    let pos = doc.vec3(&TRI);
    let nrm = doc.vec3(&[[0.0, 0.0, 1.0], [0.0, 0.0, 0.0], [0.0, 0.0, 1.0]]);
    doc.mesh_node(
        json!([{ "attributes": { "POSITION": pos, "NORMAL": nrm } }]),
        json!({}),
    );
    let err = error_of(
        &doc,
        Container::Glb,
        "meshes[0].primitives[0].attributes.NORMAL",
    );
    assert!(err.message.contains(&format!("accessors[{nrm}]")), "{err}");
}

#[test]
fn sparse_positions_are_substituted() {
    let mut doc = Doc::new();
    let base = doc.vec3(&TRI);
    let sparse_ix = doc.view(&[2u8, 0]);
    let values: Vec<u8> = [5.0f32, 6.0, 7.0]
        .iter()
        .flat_map(|x| x.to_le_bytes())
        .collect();
    let sparse_values = doc.view(&values);
    let sparse = json!({
        "count": 1,
        "indices": { "bufferView": sparse_ix, "componentType": 5121 },
        "values": { "bufferView": sparse_values }
    });
    doc.root["accessors"][base]["sparse"] = sparse.clone();
    // And one without a bufferView: zeros except the substituted vertex.
    let zeros = doc.push(
        "accessors",
        json!({ "componentType": 5126, "count": 3, "type": "VEC3", "sparse": sparse,
                "min": [0, 0, 0], "max": [5, 6, 7] }),
    );
    doc.mesh_node(
        json!([{ "attributes": { "POSITION": base } }, { "attributes": { "POSITION": zeros } }]),
        json!({}),
    );
    let (_dir, read) = read_doc(&doc, Container::Glb);
    let p = &read.meshes[0].mesh.positions;
    assert_eq!(p, &vec![DVec3::ZERO, DVec3::X, DVec3::new(5.0, 6.0, 7.0)]);
    let p = &read.meshes[1].mesh.positions;
    assert_eq!(
        p,
        &vec![DVec3::ZERO, DVec3::ZERO, DVec3::new(5.0, 6.0, 7.0)]
    );
}

fn camera_doc(camera: Value) -> Doc {
    let mut doc = triangle_doc(json!({}));
    doc.push("cameras", camera);
    let s = std::f64::consts::FRAC_1_SQRT_2;
    // 90° about +Y, with a scale the orientation must drop; nested under a moved parent.
    let cam = doc.push(
        "nodes",
        json!({ "camera": 0, "rotation": [0, s, 0, s], "scale": [2, 3, 4], "translation": [0, 0, 3] }),
    );
    doc.root_node(json!({ "translation": [1, 2, 0], "children": [cam] }));
    doc
}

fn size(doc: &Doc, width: Option<u32>, height: Option<u32>) -> (u32, u32) {
    let c = load_doc(
        doc,
        &LoadOptions {
            width,
            height,
            ..Default::default()
        },
    )
    .scene
    .camera;
    (c.width, c.height)
}

#[test]
fn perspective_camera() {
    let doc = camera_doc(json!({
        "type": "perspective",
        "perspective": { "yfov": 0.5, "aspectRatio": 2.0, "znear": 0.1, "zfar": 100 }
    }));
    let (_dir, read) = read_doc(&doc, Container::Glb);
    let cam = read.camera.unwrap();
    assert_close(cam.position, DVec3::new(1.0, 2.0, 3.0), 1e-12);
    // Rotating 90° about +Y: right -> -Z, up -> +Y, back -> +X.
    let expected = DMat3::from_cols(-DVec3::Z, DVec3::Y, DVec3::X);
    for k in 0..3 {
        assert_close(cam.orientation.col(k), expected.col(k), 1e-7);
    }
    match cam.projection {
        Projection::Perspective { vfov_deg } => {
            assert!((vfov_deg - 0.5f64.to_degrees()).abs() < 1e-5)
        }
        p => panic!("{p:?}"),
    }
    assert_eq!(cam.aspect_ratio, Some(2.0));
    assert_eq!(size(&doc, None, None), (1024, 512));
    assert_eq!(size(&doc, Some(800), None), (800, 400));
    assert_eq!(size(&doc, None, Some(300)), (600, 300));
    assert_eq!(size(&doc, Some(300), Some(300)), (300, 300));
    let loaded = load_doc(&doc, &LoadOptions::default());
    assert_eq!(loaded.scene.camera.orientation, cam.orientation);
    assert_eq!(notes_with(&loaded.notes, "no camera"), 0);
}

#[test]
fn orthographic_camera() {
    let doc = camera_doc(json!({
        "type": "orthographic",
        "orthographic": { "xmag": 7, "ymag": 3, "znear": 0.1, "zfar": 100 }
    }));
    let (_dir, read) = read_doc(&doc, Container::Embedded);
    let cam = read.camera.unwrap();
    assert_eq!(
        cam.projection,
        Projection::Orthographic { half_height: 3.0 }
    );
    assert_eq!(cam.aspect_ratio, None);
    assert_close(cam.orientation.col(2), DVec3::X, 1e-7);
    assert_eq!(size(&doc, None, None), (1024, 768));
    assert_eq!(size(&doc, Some(400), None), (400, 300));
    assert_eq!(size(&doc, None, Some(300)), (400, 300));
}

#[test]
fn punctual_lights() {
    let mut doc = triangle_doc(json!({}));
    doc.root["extensionsUsed"] = json!(["KHR_lights_punctual"]);
    doc.root["extensions"] = json!({ "KHR_lights_punctual": { "lights": [
        { "type": "point", "color": [1.0, 0.5, 0.25], "intensity": 10, "range": 5 },
        { "type": "directional", "intensity": 2 },
        { "type": "spot", "spot": {} },
        { "type": "spot", "spot": { "innerConeAngle": 0.2, "outerConeAngle": 0.5 } }
    ]}});
    let s = std::f64::consts::FRAC_1_SQRT_2;
    let ext = |i: usize| json!({ "KHR_lights_punctual": { "light": i } });
    doc.root_node(json!({ "translation": [1, 2, 3], "extensions": ext(0) }));
    // 90° about +X turns -Z into +Y.
    doc.root_node(json!({ "rotation": [s, 0, 0, s], "scale": [3, 3, 3], "extensions": ext(1) }));
    doc.root_node(json!({ "translation": [0, 5, 0], "extensions": ext(2) }));
    doc.root_node(
        json!({ "rotation": [s, 0, 0, s], "translation": [4, 0, 0], "extensions": ext(3) }),
    );
    let (_dir, read) = read_doc(&doc, Container::Glb);
    let l = &read.lights;
    assert_eq!(l.len(), 4);
    assert_eq!(
        l[0].kind,
        LightKind::Point {
            position: DVec3::new(1.0, 2.0, 3.0)
        }
    );
    assert_eq!(
        (l[0].intensity, l[0].diffuse, l[0].specular),
        (10.0, Vec3::new(1.0, 0.5, 0.25), Vec3::new(1.0, 0.5, 0.25))
    );
    assert_eq!(l[0].ambient, Vec3::ZERO);
    match l[1].kind {
        LightKind::Directional { direction } => assert_close(direction, DVec3::Y, 1e-7),
        k => panic!("{k:?}"),
    }
    assert_eq!((l[1].intensity, l[1].diffuse), (2.0, Vec3::ONE));
    match l[2].kind {
        LightKind::Spot {
            position,
            direction,
            inner_angle,
            outer_angle,
        } => {
            assert_eq!(
                (position, direction),
                (DVec3::new(0.0, 5.0, 0.0), -DVec3::Z)
            );
            assert_eq!(inner_angle, 0.0);
            assert!((outer_angle - FRAC_PI_4).abs() < 1e-6);
        }
        k => panic!("{k:?}"),
    }
    match l[3].kind {
        LightKind::Spot {
            position,
            direction,
            inner_angle,
            outer_angle,
        } => {
            assert_eq!(position, DVec3::new(4.0, 0.0, 0.0));
            assert_close(direction, DVec3::Y, 1e-7);
            assert!((inner_angle - 0.2).abs() < 1e-6 && (outer_angle - 0.5).abs() < 1e-6);
        }
        k => panic!("{k:?}"),
    }
    assert_eq!(read.notes.len(), 1, "{:?}", read.notes);
    assert_eq!(notes_with(&read.notes, "inverse-square"), 1);
    let loaded = load_doc(&doc, &LoadOptions::default());
    assert_eq!(loaded.scene.lights, read.lights);
}

#[test]
fn invalid_spot_angles_name_the_field() {
    for (spot, field) in [
        (
            json!({ "innerConeAngle": 0.6, "outerConeAngle": 0.5 }),
            "innerConeAngle",
        ),
        (json!({ "innerConeAngle": -0.1 }), "innerConeAngle"),
        (json!({ "outerConeAngle": 2.0 }), "outerConeAngle"),
        (json!({ "outerConeAngle": 0.0 }), "outerConeAngle"),
    ] {
        let mut doc = triangle_doc(json!({}));
        doc.root["extensions"] =
            json!({ "KHR_lights_punctual": { "lights": [{ "type": "spot", "spot": spot }] } });
        doc.root_node(json!({ "extensions": { "KHR_lights_punctual": { "light": 0 } } }));
        let field = format!("extensions.KHR_lights_punctual.lights[0].spot.{field}");
        error_of(&doc, Container::Embedded, &field);
    }
    // pi/2 exactly is allowed, although it rounds up as f32.
    let mut doc = triangle_doc(json!({}));
    doc.root["extensions"] = json!({ "KHR_lights_punctual": { "lights": [
        { "type": "spot", "spot": { "outerConeAngle": FRAC_PI_2 } }
    ]}});
    doc.root_node(json!({ "extensions": { "KHR_lights_punctual": { "light": 0 } } }));
    load_doc(&doc, &LoadOptions::default());
}

#[test]
fn materials_become_distinct_shaders_and_no_material_is_white() {
    let mut doc = Doc::new();
    let pos = doc.vec3(&TRI);
    doc.root["materials"] = json!([
        { "pbrMetallicRoughness": { "baseColorFactor": [1, 0, 0, 0.5] } },
        { "pbrMetallicRoughness": { "baseColorFactor": [0, 1, 0, 1], "metallicFactor": 0 } },
        { "pbrMetallicRoughness": { "baseColorFactor": [1, 0, 0, 1] } }
    ]);
    doc.mesh_node(
        json!([
            { "attributes": { "POSITION": pos }, "material": 0 },
            { "attributes": { "POSITION": pos }, "material": 1 },
            { "attributes": { "POSITION": pos }, "material": 2 },
            { "attributes": { "POSITION": pos } }
        ]),
        json!({}),
    );
    let (_dir, read) = read_doc(&doc, Container::External);
    let colours: Vec<_> = read.meshes.iter().map(|m| m.base_color).collect();
    assert_eq!(
        colours,
        vec![Some(Vec3::X), Some(Vec3::Y), Some(Vec3::X), None]
    );
    // glTF's default metallicFactor 1 is a metal: named once for the two
    // materials that have it.
    assert_eq!(
        notes_with(&read.notes, "metallic-roughness"),
        1,
        "{:?}",
        read.notes
    );
    assert_eq!(read.notes.len(), 1, "{:?}", read.notes);

    // glTF's own model, the default: one shader per distinct material
    // (materials 0 and 2 are the same), glTF's defaults without one.
    let loaded = load_doc(&doc, &LoadOptions::default());
    let pbr: Vec<_> = loaded
        .scene
        .shaders
        .iter()
        .map(|s| match s {
            Shader::MetallicRoughness(m) => (m.base_colour, m.metallic, m.roughness),
            s => panic!("{s:?}"),
        })
        .collect();
    assert_eq!(
        pbr,
        vec![
            (Vec3::X, 1.0, 1.0),
            (Vec3::Y, 0.0, 1.0),
            (Vec3::ONE, 1.0, 1.0)
        ]
    );
    let ids: Vec<_> = loaded.scene.objects.iter().map(|o| o.shader).collect();
    assert_eq!(ids, vec![0, 1, 0, 2]);
    assert_eq!(
        notes_with(&loaded.notes, "metallic-roughness"),
        0,
        "applied, so not named: {:?}",
        loaded.notes
    );

    // The seminar's mapping, on request.
    let scene = load_doc(&doc, &phong_options()).scene;
    let diffuse: Vec<_> = scene
        .shaders
        .iter()
        .map(|s| match s {
            Shader::Phong(p) => {
                assert_eq!(
                    (p.ambient, p.specular, p.shininess),
                    (Vec3::ZERO, Vec3::ZERO, 1.0)
                );
                p.diffuse
            }
            s => panic!("{s:?}"),
        })
        .collect();
    assert_eq!(diffuse, vec![Vec3::X, Vec3::Y, Vec3::ONE]);
    let ids: Vec<_> = scene.objects.iter().map(|o| o.shader).collect();
    assert_eq!(ids, vec![0, 1, 0, 2]);
    assert_eq!(scene.background, Vec3::ZERO);
}

#[test]
fn points_and_lines_are_skipped_with_one_note() {
    let mut doc = Doc::new();
    let pos = doc.vec3(&TRI);
    let prims: Vec<Value> = [0, 1, 2, 3, 4]
        .iter()
        .map(|m| json!({ "attributes": { "POSITION": pos }, "mode": m }))
        .collect();
    doc.mesh_node(json!(prims), json!({}));
    let (_dir, read) = read_doc(&doc, Container::Glb);
    assert_eq!(read.meshes.len(), 1);
    assert_eq!(read.notes.len(), 1);
    assert!(
        read.notes[0].ends_with("skipped 4 point/line primitives"),
        "{:?}",
        read.notes
    );
}

#[test]
fn skins_morph_targets_and_animations_get_one_note() {
    let mut doc = Doc::new();
    let pos = doc.vec3(&TRI);
    let delta = doc.vec3(&[[0.0, 0.0, 9.0]; 3]);
    let times = doc.view(&[0u8; 4]);
    let time = doc.push(
        "accessors",
        json!({ "bufferView": times, "componentType": 5126, "count": 1, "type": "SCALAR" }),
    );
    doc.mesh_node(
        json!([{ "attributes": { "POSITION": pos }, "targets": [{ "POSITION": delta }] }]),
        json!({ "weights": [1.0], "skin": 0 }),
    );
    doc.root["skins"] = json!([{ "joints": [0] }]);
    doc.root["animations"] = json!([{
        "channels": [{ "sampler": 0, "target": { "node": 0, "path": "translation" } }],
        "samplers": [{ "input": time, "output": delta }]
    }]);
    let (_dir, read) = read_doc(&doc, Container::Glb);
    assert_eq!(read.notes.len(), 1, "{:?}", read.notes);
    assert!(read.notes[0].ends_with(
        "skins and animations are not applied: static pose \
         (morph targets with the file's static weights)"
    ));
    // The static pose: targets are added with the node's static weights.
    assert_eq!(read.meshes[0].mesh.positions[1], DVec3::new(1.0, 0.0, 9.0));
}

#[test]
fn no_camera_and_no_lights_get_a_framing_camera_and_a_default_light() {
    let mut doc = Doc::new();
    let pos = doc.vec3(&[[-3.0, 0.0, 1.0], [5.0, 0.5, 1.0], [0.0, 2.0, -7.0]]);
    doc.mesh_node(
        json!([{ "attributes": { "POSITION": pos } }]),
        json!({ "translation": [100, 0, 0] }),
    );
    for (width, height) in [
        (None, None),
        (Some(1000), Some(100)),
        (Some(100), Some(1000)),
    ] {
        let loaded = load_doc(
            &doc,
            &LoadOptions {
                width,
                height,
                ..Default::default()
            },
        );
        let notes = &loaded.notes;
        assert_eq!(
            notes_with(notes, ": using a framing camera"),
            1,
            "{notes:?}"
        );
        assert_eq!(
            notes_with(notes, ": lit by the default environment"),
            1,
            "{notes:?}"
        );
        assert!(notes[0].starts_with("no camera in ") && notes[0].contains("model.glb"));
        let cam = loaded.scene.camera;
        assert_eq!(cam.projection, Projection::Perspective { vfov_deg: 45.0 });
        let (lo, hi) = match &loaded.scene.objects[0].shape {
            Shape::Mesh(m) => m.bounds().unwrap(),
            s => panic!("{s:?}"),
        };
        let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        for k in 0..8 {
            let pick = |bit: usize, a: f64, b: f64| if k >> bit & 1 == 0 { a } else { b };
            let corner = DVec3::new(
                pick(0, lo.x, hi.x),
                pick(1, lo.y, hi.y),
                pick(2, lo.z, hi.z),
            );
            let (x, y) = cam.project(corner).unwrap();
            let (w, h) = (f64::from(cam.width), f64::from(cam.height));
            assert!(
                x > 0.0 && x < w && y > 0.0 && y < h,
                "corner {corner} at ({x}, {y}) in {w}x{h}"
            );
            (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
        }
        // The box's projection is centred in the frame.
        let (w, h) = (f64::from(cam.width), f64::from(cam.height));
        assert!(
            ((x0 + x1) / 2.0 - w / 2.0).abs() < 1e-3 * w,
            "{x0}..{x1} in {w}"
        );
        assert!(
            ((y0 + y1) / 2.0 - h / 2.0).abs() < 1e-3 * h,
            "{y0}..{y1} in {h}"
        );
        // Looking from 30° right of the front (+Z) and 20° above it.
        let (az, el) = (30f64.to_radians(), 20f64.to_radians());
        let from = DVec3::new(az.sin() * el.cos(), el.sin(), az.cos() * el.cos());
        assert_close(cam.orientation.col(2), from, 1e-12);
        check_default_environment(&loaded);
    }
}

/// A file without lights under glTF's own materials: the default
/// environment alone (no shadow rays, so geometry enclosing the scene cannot
/// block it), over the grey background, shown tone-mapped.
fn check_default_environment(loaded: &Loaded) {
    use penumbra::loaders::lighting::{DEFAULT_BACKGROUND, DEFAULT_ENVIRONMENT};
    let scene = &loaded.scene;
    assert!(loaded.lit_by_default);
    assert_eq!(scene.lights.len(), 1, "{:?}", scene.lights);
    let l = &scene.lights[0];
    match l.kind {
        LightKind::Environment { up, .. } => assert_eq!(up, DVec3::Y),
        k => panic!("{k:?}"),
    }
    assert_eq!((l.intensity, l.diffuse), (DEFAULT_ENVIRONMENT, Vec3::ONE));
    assert_eq!(scene.background, Vec3::from(DEFAULT_BACKGROUND));
}

/// The default lights follow the camera: a key light travelling along the
/// view, downwards and across from over the camera's shoulder, and a weaker
/// fill travelling nearly along the view.
fn check_default_lights(scene: &penumbra::scene::Scene) {
    let o = scene.camera.orientation;
    let (right, up, forward) = (o.col(0), o.col(1), -o.col(2));
    assert_eq!(scene.lights.len(), 2, "{:?}", scene.lights);
    let dirs: Vec<DVec3> = scene
        .lights
        .iter()
        .map(|l| match l.kind {
            LightKind::Directional { direction } => direction,
            k => panic!("{k:?}"),
        })
        .collect();
    let (key, fill) = (dirs[0], dirs[1]);
    // Key: from above (travels down), behind (along the view), from the side.
    assert!(key.dot(forward) > 0.7 && key.dot(up) < -0.3, "{key}");
    assert!(key.dot(right).abs() > 0.1, "{key}");
    // Fill: within 15° of the view, from the other side than the key.
    assert!(fill.dot(forward) > 15f64.to_radians().cos(), "{fill}");
    assert!(fill.dot(right) * key.dot(right) < 0.0, "{fill} {key}");
    let (k, f) = (&scene.lights[0], &scene.lights[1]);
    assert!(k.intensity > f.intensity && f.intensity > 0.0);
    for l in [k, f] {
        assert_eq!((l.ambient, l.diffuse), (Vec3::ZERO, Vec3::ONE));
        match l.kind {
            LightKind::Directional { direction } => {
                assert!((direction.length() - 1.0).abs() < 1e-12)
            }
            _ => unreachable!(),
        }
    }
}

#[test]
fn a_file_with_a_camera_and_no_lights_is_lit_from_that_camera() {
    // The camera looks up at the triangle from below and behind: a light
    // fixed in the world (as before) would light its far side.
    let mut doc = triangle_doc(json!({}));
    doc.push(
        "cameras",
        json!({ "type": "perspective", "perspective": { "yfov": 0.8, "znear": 0.1 } }),
    );
    // Rotated 180° about X: looks along +Z with up −Y, from z = −5.
    doc.root_node(json!({ "camera": 0, "translation": [0.3, 0.3, -5], "rotation": [1, 0, 0, 0] }));
    // The seminar's Phong mapping keeps the default lights of before.
    let phong = LoadOptions {
        gltf_materials: GltfMaterials::Phong,
        ..Default::default()
    };
    let loaded = load_doc(&doc, &phong);
    assert_close(-loaded.scene.camera.orientation.col(2), DVec3::Z, 1e-12);
    check_default_lights(&loaded.scene);
    assert!(!loaded.lit_by_default);
    assert_eq!(loaded.scene.background, Vec3::ZERO);
    assert_eq!(notes_with(&loaded.notes, "relative to the camera"), 1);
    assert_eq!(notes_with(&loaded.notes, "no camera"), 0);
    // glTF's own materials: the default environment instead.
    let loaded = load_doc(&doc, &LoadOptions::default());
    check_default_environment(&loaded);
    assert_eq!(notes_with(&loaded.notes, "relative to the camera"), 0);
}

#[test]
fn the_environment_flag_replaces_the_default_environment_and_joins_a_files_lights() {
    use penumbra::loaders::lighting::Lighting;
    let with = |environment, background| LoadOptions {
        lighting: Lighting {
            environment,
            background,
        },
        ..Default::default()
    };
    // No lights: the asked environment instead of the default one.
    let doc = triangle_doc(json!({}));
    let loaded = load_doc(&doc, &with(Some(3.0), Some([0.1, 0.2, 0.3])));
    assert_eq!(loaded.scene.lights.len(), 1);
    assert_eq!(loaded.scene.lights[0].intensity, 3.0);
    assert!(matches!(
        loaded.scene.lights[0].kind,
        LightKind::Environment { .. }
    ));
    assert_eq!(loaded.scene.background, Vec3::new(0.1, 0.2, 0.3));
    // A file with a light keeps it and gets the environment beside it.
    let mut doc = triangle_doc(json!({}));
    doc.root["extensionsUsed"] = json!(["KHR_lights_punctual"]);
    doc.root["extensions"] =
        json!({ "KHR_lights_punctual": { "lights": [{ "type": "directional", "intensity": 2 }] } });
    doc.root_node(json!({ "extensions": { "KHR_lights_punctual": { "light": 0 } } }));
    let loaded = load_doc(&doc, &LoadOptions::default());
    assert_eq!(loaded.scene.lights.len(), 1);
    assert!(!loaded.lit_by_default);
    assert_eq!(loaded.scene.background, Vec3::ZERO);
    let loaded = load_doc(&doc, &with(Some(3.0), None));
    let kinds: Vec<_> = loaded.scene.lights.iter().map(|l| l.kind).collect();
    assert!(
        matches!(
            kinds[..],
            [LightKind::Directional { .. }, LightKind::Environment { .. }]
        ),
        "{kinds:?}"
    );
}

#[test]
fn default_scene_is_used_and_must_have_triangles() {
    let mut doc = triangle_doc(json!({}));
    let pos = doc.vec3(&[[0.0, 0.0, 5.0], [1.0, 0.0, 5.0], [0.0, 1.0, 5.0]]);
    let mesh = doc.push(
        "meshes",
        json!({ "primitives": [{ "attributes": { "POSITION": pos }, "mode": 1 }] }),
    );
    let node = doc.push("nodes", json!({ "mesh": mesh }));
    doc.push("scenes", json!({ "nodes": [node] }));
    doc.root["scene"] = json!(1);
    let dir = TempDir::new().unwrap();
    let path = doc.write(dir.path(), "lines", Container::Glb);
    let err = gltf::load(&path, &LoadOptions::default()).unwrap_err();
    assert_eq!(
        (err.field.as_str(), err.message.as_str()),
        ("scenes[1]", "no triangle meshes in the default scene")
    );
    // Without `scene`, scene 0 is used.
    doc.root.as_object_mut().unwrap().remove("scene");
    let read = read_doc(&doc, Container::Glb).1;
    assert_eq!(read.meshes.len(), 1);
}

#[test]
fn missing_file_and_corrupt_json() {
    let dir = TempDir::new().unwrap();
    let missing = dir.path().join("nothing.glb");
    let err = gltf::read(&missing).unwrap_err();
    assert!(err.to_string().contains("nothing.glb"), "{err}");

    let corrupt = dir.path().join("corrupt.gltf");
    std::fs::write(
        &corrupt,
        r#"{"asset": {"version": "2.0"}, "nodes": [{"mesh": "x"}]}"#,
    )
    .unwrap();
    let err = gltf::read(&corrupt).unwrap_err();
    assert_eq!(err.field, "nodes[0].mesh", "{err}");
    assert!(err.to_string().contains("corrupt.gltf"), "{err}");

    std::fs::write(&corrupt, "{\"asset\": ").unwrap();
    let err = gltf::read(&corrupt).unwrap_err();
    assert_eq!(err.field, "asset", "{err}");
    assert!(
        err.to_string().contains("corrupt.gltf") && err.message.contains("line 1"),
        "{err}"
    );

    let bad_glb = dir.path().join("bad.glb");
    std::fs::write(&bad_glb, b"glTF\x02\0\0\0\x04\0\0\0").unwrap();
    let err = gltf::read(&bad_glb).unwrap_err();
    assert!(
        err.to_string().contains("bad.glb") && err.message.contains("GLB"),
        "{err}"
    );

    // A dangling index is caught by validation, with its path.
    let mut doc = triangle_doc(json!({}));
    doc.root["nodes"][0]["mesh"] = json!(7);
    error_of(&doc, Container::Glb, "nodes[0].mesh");
}

#[test]
fn missing_and_short_buffers() {
    let doc = triangle_doc(json!({}));
    let dir = TempDir::new().unwrap();
    let path = doc.write(dir.path(), "model", Container::External);
    std::fs::remove_file(dir.path().join("model.bin")).unwrap();
    let err = gltf::read(&path).unwrap_err();
    assert_eq!(err.field, "buffers[0].uri");
    assert!(
        err.to_string().contains("model.gltf") && err.message.contains("model.bin"),
        "{err}"
    );

    // Truncated by 2 bytes: still rejected although 4-byte padding would hide it.
    let path = doc.write(dir.path(), "model", Container::External);
    std::fs::write(dir.path().join("model.bin"), &doc.bin[..doc.bin.len() - 2]).unwrap();
    let err = gltf::read(&path).unwrap_err();
    assert_eq!(err.field, "buffers[0].byteLength", "{err}");

    // Buffer views and accessors reaching past their container.
    let mut bad = triangle_doc(json!({}));
    bad.root["bufferViews"][0]["byteLength"] = json!(400);
    error_of(&bad, Container::Glb, "bufferViews[0]");
    let mut bad = triangle_doc(json!({}));
    bad.root["accessors"][0]["count"] = json!(4);
    error_of(&bad, Container::Embedded, "accessors[0]");
    let mut bad = triangle_doc(json!({}));
    bad.root["accessors"][0]["byteOffset"] = json!(4);
    error_of(&bad, Container::Glb, "accessors[0]");
    let mut bad = triangle_doc(json!({}));
    bad.root["bufferViews"][0]["byteStride"] = json!(8);
    error_of(&bad, Container::Glb, "accessors[0]");
    let mut bad = triangle_doc(json!({}));
    bad.root["accessors"][0]["count"] = json!(0);
    let read = read_doc(&bad, Container::Glb).1;
    assert!(read.meshes[0].mesh.indices.is_empty());
    let mut bad = triangle_doc(json!({}));
    bad.root["accessors"][0]["type"] = json!("VEC2");
    let err = error_of(
        &bad,
        Container::Glb,
        "meshes[0].primitives[0].attributes.POSITION",
    );
    assert!(err.message.contains("accessors[0]"), "{err}");
}

#[test]
fn bad_indices_and_positions() {
    let mut doc = Doc::new();
    let pos = doc.vec3(&TRI);
    let ix = doc.indices_u16(&[0, 1, 3]);
    doc.mesh_node(
        json!([{ "attributes": { "POSITION": pos }, "indices": ix }]),
        json!({}),
    );
    let err = error_of(&doc, Container::Glb, "meshes[0].primitives[0].indices");
    assert!(err.message.contains("out of range"), "{err}");

    let mut doc = Doc::new();
    let pos = doc.vec3(&[[0.0; 3], [f32::NAN, 0.0, 0.0], [0.0, 1.0, 0.0]]);
    doc.mesh_node(json!([{ "attributes": { "POSITION": pos } }]), json!({}));
    let err = error_of(
        &doc,
        Container::Embedded,
        "meshes[0].primitives[0].attributes.POSITION",
    );
    assert!(err.message.contains("vertex 1"), "{err}");

    let mut doc = Doc::new();
    let pos = doc.vec3(&[[0.0; 3]; 4]);
    doc.mesh_node(json!([{ "attributes": { "POSITION": pos } }]), json!({}));
    error_of(
        &doc,
        Container::Glb,
        "meshes[0].primitives[0].attributes.POSITION",
    );

    // Sparse index past the accessor's count.
    let mut doc = triangle_doc(json!({}));
    let ix = doc.view(&[9u8, 0, 0, 0]);
    let values = doc.view(&[0u8; 12]);
    doc.root["accessors"][0]["sparse"] = json!({
        "count": 1,
        "indices": { "bufferView": ix, "componentType": 5121 },
        "values": { "bufferView": values }
    });
    error_of(&doc, Container::Glb, "accessors[0].sparse.indices");

    // A cycle in the node hierarchy.
    let mut doc = triangle_doc(json!({}));
    doc.root["nodes"][0]["children"] = json!([0]);
    error_of(&doc, Container::Glb, "nodes[0]");
}

/// Dev paths; repointed when merging.
const BUNNY: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/bunny.glb");
const BUNNY_SCENE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/bunny_scene.glb");

#[test]
fn bunny_scene_glb() {
    let opts = LoadOptions {
        width: Some(1024),
        height: Some(1024),
        ..Default::default()
    };
    let loaded = gltf::load(Path::new(BUNNY_SCENE), &opts).unwrap_or_else(|e| panic!("{e}"));
    let scene = &loaded.scene;
    scene.validate().unwrap();
    assert_eq!(scene.objects.len(), 2);
    assert_eq!(scene.triangle_count(), 3676);
    assert!(loaded.notes.is_empty(), "{:?}", loaded.notes);
    assert_eq!(loaded.files, vec![PathBuf::from(BUNNY_SCENE)]);
    let cam = scene.camera;
    assert_close(cam.position, DVec3::new(1.6, 1.2, 2.8), 1e-6);
    match cam.projection {
        Projection::Perspective { vfov_deg } => {
            assert!((vfov_deg - 35.0).abs() < 1e-3, "{vfov_deg}")
        }
        p => panic!("{p:?}"),
    }
    let (x, y) = cam.project(DVec3::new(0.25, 0.3, 0.0)).unwrap();
    assert!(
        (x - 512.0).abs() < 1e-3 && (y - 512.0).abs() < 1e-3,
        "({x}, {y})"
    );
    assert_eq!(scene.lights.len(), 1);
    let light = scene.lights[0];
    match light.kind {
        LightKind::Directional { direction } => {
            assert_close(direction, DVec3::new(2.0, -2.0, -1.0) / 3.0, 1e-5)
        }
        k => panic!("{k:?}"),
    }
    assert_eq!(light.intensity, 1.0);
    // The file's aspectRatio 1 picks a square default size.
    let loaded = gltf::load(Path::new(BUNNY_SCENE), &LoadOptions::default()).unwrap();
    assert_eq!(
        (loaded.scene.camera.width, loaded.scene.camera.height),
        (1024, 1024)
    );
}

#[test]
fn bunny_glb() {
    let loaded =
        gltf::load(Path::new(BUNNY), &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    loaded.scene.validate().unwrap();
    assert_eq!(loaded.scene.triangle_count(), 3674);
    assert_eq!(loaded.scene.objects.len(), 1);
    assert_eq!(notes_with(&loaded.notes, "no camera in"), 1);
    assert_eq!(notes_with(&loaded.notes, "no lights in"), 1);
    // Metallic 0 and roughness 1: the diffuse surface Phong draws, no note.
    assert_eq!(loaded.notes.len(), 2, "{:?}", loaded.notes);
    check_default_environment(&loaded);
    let c = loaded.scene.camera;
    assert_eq!((c.width, c.height), (1024, 768));
    let read = gltf::read(Path::new(BUNNY)).unwrap();
    assert!(read.camera.is_none() && read.lights.is_empty());
    assert_eq!(read.meshes[0].base_color, Some(Vec3::splat(0.8)));
}

#[test]
fn dangling_references_and_bad_enums_are_caught_by_validation() {
    let lights = |lights: Value| {
        let mut doc = triangle_doc(json!({}));
        doc.root["extensions"] = json!({ "KHR_lights_punctual": { "lights": lights } });
        doc.root_node(json!({ "extensions": { "KHR_lights_punctual": { "light": 0 } } }));
        doc
    };
    let mut doc = triangle_doc(json!({}));
    doc.root_node(json!({ "extensions": { "KHR_lights_punctual": { "light": 5 } } }));
    error_of(
        &doc,
        Container::Glb,
        "nodes[1].extensions.KHR_lights_punctual.light",
    );
    error_of(
        &lights(json!([{ "type": "spot" }])),
        Container::Glb,
        "extensions.KHR_lights_punctual.lights[0].spot",
    );
    error_of(
        &lights(json!([{ "type": "laser" }])),
        Container::Glb,
        "extensions.KHR_lights_punctual.lights[0].type",
    );

    let mut doc = triangle_doc(json!({}));
    doc.push("cameras", json!({ "type": "perspective" }));
    doc.root_node(json!({ "camera": 0 }));
    error_of(&doc, Container::Glb, "cameras[0]");
    let mut doc = triangle_doc(json!({}));
    doc.root["meshes"][0]["primitives"][0]["mode"] = json!(9);
    error_of(&doc, Container::Glb, "meshes[0].primitives[0].mode");
    let mut doc = triangle_doc(json!({}));
    doc.root["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(3);
    error_of(
        &doc,
        Container::Glb,
        "meshes[0].primitives[0].attributes.POSITION",
    );
    let mut doc = triangle_doc(json!({}));
    doc.root["accessors"][0]["componentType"] = json!(5130);
    error_of(&doc, Container::Glb, "accessors[0].componentType");
}

/// A file using most features, for the mutation test below.
fn feature_doc() -> Doc {
    let mut doc = Doc::new();
    let pos = doc.vec3(&[[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]]);
    let nrm = doc.vec3(&[[0.0, 0.0, 1.0]; 4]);
    let ix = doc.indices_u16(&[0, 1, 2, 2, 1, 3]);
    let sparse_ix = doc.view(&[1u8, 3]);
    let sparse_values = doc.view(&[0u8; 24]);
    doc.root["accessors"][pos]["sparse"] = json!({
        "count": 2,
        "indices": { "bufferView": sparse_ix, "componentType": 5121 },
        "values": { "bufferView": sparse_values }
    });
    doc.root["bufferViews"][nrm]["byteStride"] = json!(12);
    // Textures, a normal map (tangents generated) and every attribute kind.
    let uv = doc.accessor(&[0, 0, 255, 0, 0, 255, 255, 255], 5121, 4, "VEC2", true);
    let colour = doc.accessor(&[255; 16], 5121, 4, "VEC4", true);
    let image = doc.view(&png(2, 2));
    let normal_image = doc.view(&png(1, 1));
    doc.root["images"] = json!([
        { "bufferView": image, "mimeType": "image/png" },
        { "bufferView": normal_image, "mimeType": "image/png" }
    ]);
    doc.root["samplers"] = json!([{ "magFilter": 9728, "minFilter": 9986, "wrapS": 33071 }]);
    doc.root["textures"] = json!([{ "source": 0, "sampler": 0 }, { "source": 1 }]);
    doc.root["materials"] = json!([{
        "pbrMetallicRoughness": { "baseColorTexture": { "index": 0, "texCoord": 0 } },
        "normalTexture": { "index": 1, "texCoord": 0 },
        "emissiveTexture": { "index": 0, "texCoord": 0 },
        "alphaMode": "MASK"
    }]);
    doc.mesh_node(
        json!([
            { "attributes": { "POSITION": pos, "NORMAL": nrm, "TEXCOORD_0": uv, "COLOR_0": colour },
              "indices": ix, "material": 0 },
            { "attributes": { "POSITION": pos, "TEXCOORD_0": uv }, "mode": 5, "material": 0 }
        ]),
        json!({ "scale": [1, -1, 1] }),
    );
    doc.push(
        "cameras",
        json!({ "type": "perspective", "perspective": { "yfov": 1, "znear": 0.1 } }),
    );
    doc.root_node(json!({ "camera": 0, "translation": [0, 0, 5] }));
    doc.root["extensions"] = json!({ "KHR_lights_punctual": { "lights": [{ "type": "spot" }] } });
    doc.root_node(json!({ "extensions": { "KHR_lights_punctual": { "light": 0 } } }));
    doc
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(400))]

    /// Corrupted numbers in the JSON, bytes in the GLB, or a truncated GLB: an
    /// error or a scene that validates, never a panic.
    #[test]
    fn corrupted_files_never_panic(
        field in 0usize..64,
        value in proptest::sample::select(vec![-1i64, 0, 1, 2, 3, 4, 5, 7, 8, 12, 13, 48, 255, 65535, 1 << 31, 1 << 40]),
        flips in proptest::collection::vec((0usize..4096, proptest::num::u8::ANY), 0..4),
        cut in proptest::option::of(0usize..4096),
    ) {
        let mut doc = feature_doc();
        // Overwrite the `field`-th integer-valued leaf of the JSON.
        let mut leaves = Vec::new();
        collect_integer_leaves(&doc.root, String::new(), &mut leaves);
        let pointer = &leaves[field % leaves.len()];
        *doc.root.pointer_mut(pointer).unwrap() = json!(value);
        let dir = TempDir::new().unwrap();
        let path = doc.write(dir.path(), "m", Container::Glb);
        let mut bytes = std::fs::read(&path).unwrap();
        for (at, b) in flips {
            let n = bytes.len();
            bytes[at % n] = b;
        }
        if let Some(cut) = cut {
            bytes.truncate(cut.min(bytes.len()));
        }
        std::fs::write(&path, &bytes).unwrap();
        if let Ok(loaded) = gltf::load(&path, &LoadOptions::default()) {
            // What the loader accepts, the scene model accepts too.
            proptest::prop_assert!(loaded.scene.validate().is_ok());
        }
    }
}

fn collect_integer_leaves(v: &Value, at: String, out: &mut Vec<String>) {
    match v {
        Value::Array(items) => {
            for (i, x) in items.iter().enumerate() {
                collect_integer_leaves(x, format!("{at}/{i}"), out);
            }
        }
        Value::Object(map) => {
            for (k, x) in map {
                collect_integer_leaves(x, format!("{at}/{k}"), out);
            }
        }
        Value::Number(n) if n.is_u64() => out.push(at),
        _ => {}
    }
}

#[test]
fn escaped_uris_and_a_missing_glb_chunk() {
    let doc = triangle_doc(json!({}));
    let dir = TempDir::new().unwrap();
    std::fs::write(dir.path().join("my data.bin"), &doc.bin).unwrap();
    let mut root = doc.root.clone();
    root["buffers"] = json!([{ "byteLength": doc.bin.len(), "uri": "my%20data.bin" }]);
    let path = dir.path().join("escaped.gltf");
    std::fs::write(&path, root.to_string()).unwrap();
    let read = gltf::read(&path).unwrap();
    assert_eq!(
        read.files,
        vec![path.clone(), dir.path().join("my data.bin")]
    );

    root["buffers"][0]["uri"] = json!("https://example.com/x.bin");
    std::fs::write(&path, root.to_string()).unwrap();
    assert_eq!(gltf::read(&path).unwrap_err().field, "buffers[0].uri");
    root["buffers"][0]["uri"] = json!("data:application/octet-stream;base64,@@@@");
    std::fs::write(&path, root.to_string()).unwrap();
    assert_eq!(gltf::read(&path).unwrap_err().field, "buffers[0].uri");

    // A .glb whose buffer 0 wants the BIN chunk, without one.
    let mut root = doc.root.clone();
    root["buffers"] = json!([{ "byteLength": doc.bin.len() }]);
    let path = dir.path().join("nobin.glb");
    std::fs::write(&path, glb(root.to_string().as_bytes(), &[])).unwrap();
    let err = gltf::read(&path).unwrap_err();
    assert_eq!(err.field, "buffers[0]", "{err}");
}

// ---------------------------------------------------------------------------
// Materials, textures, samplers and vertex attributes (issue 14).

use penumbra::loaders::guard::Guard;
use penumbra::scene::{AlphaMode, Filter, Sampler, TextureRef, UvTransform, Wrap};

/// A PNG of `w × h` texels, texel (x, y) = (x, y, 7, 200 + x).
pub(crate) fn png(w: u32, h: u32) -> Vec<u8> {
    let img = image::RgbaImage::from_fn(w, h, |x, y| {
        image::Rgba([x as u8, y as u8, 7, 200u8.wrapping_add(x as u8)])
    });
    let mut out = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut out), image::ImageFormat::Png)
        .unwrap();
    out
}

pub(crate) fn png_uri(w: u32, h: u32) -> String {
    format!(
        "data:image/png;base64,{}",
        crate::base64::encode(&png(w, h))
    )
}

impl Doc {
    /// An accessor of `count` elements over these bytes.
    pub(crate) fn accessor(
        &mut self,
        bytes: &[u8],
        ty: u32,
        count: usize,
        kind: &str,
        norm: bool,
    ) -> usize {
        let view = self.view(bytes);
        self.push(
            "accessors",
            json!({ "bufferView": view, "componentType": ty, "count": count, "type": kind,
                    "normalized": norm }),
        )
    }

    pub(crate) fn floats(&mut self, data: &[f32], kind: &str, n: usize) -> usize {
        let bytes: Vec<u8> = data.iter().flat_map(|x| x.to_le_bytes()).collect();
        self.accessor(&bytes, 5126, data.len() / n, kind, false)
    }
}

pub(crate) const QUAD: [[f32; 3]; 4] = [
    [0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [1.0, 1.0, 0.0],
    [0.0, 1.0, 0.0],
];

/// A quad with normals and TEXCOORD_0 (float) on one primitive per
/// material given.
pub(crate) fn material_doc(materials: Value) -> Doc {
    let mut doc = Doc::new();
    let pos = doc.vec3(&QUAD);
    let nrm = doc.vec3(&[[0.0, 0.0, 1.0]; 4]);
    let uv = doc.floats(&[0.0, 1.0, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0], "VEC2", 2);
    let ix = doc.indices_u16(&[0, 1, 2, 0, 2, 3]);
    let n = materials.as_array().unwrap().len();
    let prims: Vec<Value> = (0..n)
        .map(|m| {
            json!({ "attributes": { "POSITION": pos, "NORMAL": nrm, "TEXCOORD_0": uv },
                    "indices": ix, "material": m })
        })
        .collect();
    doc.root["materials"] = materials;
    doc.mesh_node(json!(prims), json!({}));
    doc
}

/// glTF materials as the seminar's Phong (`--gltf-materials phong`).
fn phong_options() -> LoadOptions {
    LoadOptions {
        gltf_materials: penumbra::loaders::GltfMaterials::Phong,
        ..Default::default()
    }
}

fn pbr_of(scene: &penumbra::scene::Scene, object: usize) -> penumbra::scene::MetallicRoughness {
    match &scene.shaders[scene.objects[object].shader] {
        Shader::MetallicRoughness(m) => *m,
        s => panic!("{s:?}"),
    }
}

fn phong_of(scene: &penumbra::scene::Scene, object: usize) -> penumbra::scene::Phong {
    match &scene.shaders[scene.objects[object].shader] {
        Shader::Phong(p) => *p,
        s => panic!("{s:?}"),
    }
}

#[test]
fn materials_give_phong_textures_normal_maps_emission_and_alpha() {
    let mut doc = material_doc(json!([
        {
            "pbrMetallicRoughness": {
                "baseColorFactor": [0.5, 0.25, 1, 0.75],
                "baseColorTexture": { "index": 0, "texCoord": 1, "extensions": {
                    "KHR_texture_transform": { "offset": [0.5, 0], "rotation": 0.5, "scale": [2, 3] } } },
                "metallicFactor": 0
            },
            "normalTexture": { "index": 1, "scale": 0.5 },
            "emissiveFactor": [1, 0.5, 0],
            "emissiveTexture": { "index": 0 },
            "extensions": { "KHR_materials_emissive_strength": { "emissiveStrength": 4 } },
            "alphaMode": "MASK", "alphaCutoff": 0.3
        },
        { "pbrMetallicRoughness": { "baseColorTexture": { "index": 0 }, "metallicFactor": 0 },
          "alphaMode": "BLEND" },
        { "pbrMetallicRoughness": { "baseColorTexture": { "index": 0 }, "metallicFactor": 0 } },
        { "pbrMetallicRoughness": { "baseColorTexture": { "index": 0 }, "metallicFactor": 0 },
          "alphaMode": "MASK", "occlusionTexture": { "index": 0, "strength": 0.5 } }
    ]));
    // Texture 1 shows the same image as texture 0, as a normal map.
    doc.root["textures"] = json!([{ "source": 0, "sampler": 0 }, { "source": 0 }]);
    doc.root["samplers"] =
        json!([{ "magFilter": 9728, "minFilter": 9986, "wrapS": 33071, "wrapT": 33648 }]);
    doc.root["images"] = json!([{ "uri": png_uri(3, 2) }]);
    doc.root["extensionsUsed"] = json!([
        "KHR_texture_transform",
        "KHR_materials_emissive_strength",
        "KHR_materials_clearcoat"
    ]);
    let loaded = load_doc(&doc, &phong_options());
    let scene = &loaded.scene;

    // One texture per (image, colour space), labelled with the file.
    assert_eq!(scene.textures.len(), 2);
    let (colour, normal) = (&scene.textures[0], &scene.textures[1]);
    assert!(colour.srgb && !normal.srgb);
    assert_eq!(colour.label, "model.glb images[0]");
    assert_eq!(
        (colour.width, colour.height, colour.file.clone()),
        (3, 2, None)
    );
    assert_eq!(colour.texels[4], [1, 1, 7, 201]);
    assert_eq!(normal.texels, colour.texels);

    let sampler = Sampler {
        mag: Filter::Nearest,
        min: Filter::Nearest,
        mip: Some(Filter::Linear),
        wrap_u: Wrap::ClampToEdge,
        wrap_v: Wrap::MirroredRepeat,
    };
    let base = TextureRef {
        texture: 0,
        sampler,
        tex_coord: 1,
        transform: UvTransform {
            offset: glam::DVec2::new(0.5, 0.0),
            rotation: 0.5,
            scale: glam::DVec2::new(2.0, 3.0),
        },
    };
    let p = phong_of(scene, 0);
    assert_eq!(p.diffuse, Vec3::new(0.5, 0.25, 1.0));
    assert_eq!(
        (p.ambient, p.specular, p.shininess),
        (Vec3::ZERO, Vec3::ZERO, 1.0)
    );
    assert_eq!(p.textures.diffuse, Some(base));
    assert_eq!((p.textures.ambient, p.textures.specular), (None, None));
    // glTF's own model takes the same base colour and texture.
    let pbr_scene = load_doc(&doc, &LoadOptions::default()).scene;
    let m = pbr_of(&pbr_scene, 0);
    assert_eq!(
        (m.base_colour, m.metallic, m.roughness),
        (Vec3::new(0.5, 0.25, 1.0), 0.0, 1.0)
    );
    assert_eq!(m.textures.base_colour, Some(base));
    assert_eq!(m.textures.metallic_roughness, None);
    let maps = &scene.objects[0].maps;
    assert_eq!(maps.normal, Some((TextureRef::new(1), 0.5)));
    assert_eq!(maps.emission, Vec3::new(4.0, 2.0, 0.0));
    assert_eq!(
        maps.emission_texture,
        Some(TextureRef {
            sampler,
            ..TextureRef::new(0)
        })
    );
    assert_eq!(maps.alpha_mode, AlphaMode::Mask { cutoff: 0.3 });
    assert_eq!(maps.opacity, 0.75);
    assert_eq!(maps.opacity_texture, Some(base));

    // BLEND and OPAQUE; MASK with the default cutoff.
    let plain = Some(TextureRef {
        sampler,
        ..TextureRef::new(0)
    });
    let m = &scene.objects[1].maps;
    assert_eq!(
        (m.alpha_mode, m.opacity, m.opacity_texture),
        (AlphaMode::Blend, 1.0, plain)
    );
    let m = &scene.objects[2].maps;
    assert_eq!((m.alpha_mode, m.opacity_texture), (AlphaMode::Opaque, None));
    assert_eq!(
        scene.objects[3].maps.alpha_mode,
        AlphaMode::Mask { cutoff: 0.5 }
    );
    // The occlusion texture: the image in linear space (texture 1, as the
    // normal map's), with its sampler and strength; none elsewhere.
    assert_eq!(
        scene.objects[3].maps.occlusion,
        Some((
            TextureRef {
                sampler,
                ..TextureRef::new(1)
            },
            0.5
        ))
    );
    assert!(scene.objects[..3]
        .iter()
        .all(|o| o.maps.occlusion.is_none()));
    // Materials 1 to 3 are the same Phong shader; their maps differ.
    let ids: Vec<_> = scene.objects.iter().map(|o| o.shader).collect();
    assert_eq!(ids, vec![0, 1, 1, 1]);
    assert_eq!(scene.shaders.len(), 2);

    // The normal-mapped quad got MikkTSpace tangents: +X, w = +1 (its v
    // runs down the image, its bitangent up it).
    let Shape::Mesh(mesh) = &scene.objects[0].shape else {
        panic!()
    };
    let t = mesh.tangents.as_ref().expect("generated tangents");
    assert_eq!(t.len(), mesh.positions.len());
    for t in t {
        assert!(
            (t.truncate() - DVec3::X).length() < 1e-6 && t.w == 1.0,
            "{t}"
        );
    }
    let Shape::Mesh(plain_mesh) = &scene.objects[2].shape else {
        panic!()
    };
    assert!(plain_mesh.tangents.is_none(), "no normal map, no tangents");

    // Each unsupported feature named once.
    let notes = &loaded.notes;
    assert_eq!(
        notes_with(notes, "KHR_materials_clearcoat is not supported"),
        1,
        "{notes:?}"
    );
    assert_eq!(notes_with(notes, "occlusionTexture"), 0, "{notes:?}");
    assert_eq!(notes_with(notes, "metallic-roughness"), 0, "{notes:?}");
    assert_eq!(notes_with(notes, "KHR_texture_transform"), 0, "{notes:?}");
    assert_eq!(notes_with(notes, "emissive_strength"), 0, "{notes:?}");
    assert_eq!(
        notes_with(notes, "textures are not applied"),
        0,
        "{notes:?}"
    );
}

#[test]
fn samplers_map_every_filter_and_wrap_mode() {
    let filters = [
        (json!({}), Sampler::default()),
        (
            json!({ "magFilter": 9729, "minFilter": 9728, "wrapS": 10497, "wrapT": 33071 }),
            Sampler {
                mag: Filter::Linear,
                min: Filter::Nearest,
                mip: None,
                wrap_u: Wrap::Repeat,
                wrap_v: Wrap::ClampToEdge,
            },
        ),
        (
            json!({ "minFilter": 9729 }),
            Sampler {
                mip: None,
                ..Sampler::default()
            },
        ),
        (
            json!({ "minFilter": 9984 }),
            Sampler {
                min: Filter::Nearest,
                mip: Some(Filter::Nearest),
                ..Sampler::default()
            },
        ),
        (
            json!({ "minFilter": 9985 }),
            Sampler {
                mip: Some(Filter::Nearest),
                ..Sampler::default()
            },
        ),
        (
            json!({ "minFilter": 9987, "magFilter": 9728 }),
            Sampler {
                mag: Filter::Nearest,
                ..Sampler::default()
            },
        ),
    ];
    let materials: Vec<Value> = (0..=filters.len())
        .map(|i| json!({ "pbrMetallicRoughness": { "baseColorTexture": { "index": i } } }))
        .collect();
    let mut doc = material_doc(json!(materials));
    let mut textures: Vec<Value> = (0..filters.len())
        .map(|i| json!({ "source": 0, "sampler": i }))
        .collect();
    // No sampler at all: the defaults.
    textures.push(json!({ "source": 0 }));
    doc.root["textures"] = json!(textures);
    doc.root["samplers"] = json!(filters.iter().map(|(j, _)| j.clone()).collect::<Vec<_>>());
    doc.root["images"] = json!([{ "uri": png_uri(1, 1) }]);
    let scene = load_doc(&doc, &phong_options()).scene;
    assert_eq!(scene.textures.len(), 1, "one image, one colour space");
    for (i, (_, want)) in filters.iter().enumerate() {
        let got = phong_of(&scene, i).textures.diffuse.unwrap().sampler;
        assert_eq!(got, *want, "sampler {i}");
    }
    let last = phong_of(&scene, filters.len()).textures.diffuse.unwrap();
    assert_eq!(last.sampler, Sampler::default());
}

#[test]
fn texture_coordinate_sets_and_colours_of_every_accessor_type() {
    let mut doc = Doc::new();
    let pos = doc.vec3(&TRI);
    let uv_f = doc.floats(&[0.0, 0.5, 1.0, 0.25, 0.125, 1.0], "VEC2", 2);
    let uv_b = doc.accessor(&[0, 255, 51, 0, 255, 102], 5121, 3, "VEC2", true);
    let uv_s: Vec<u8> = [0u16, 65535, 13107, 0, 65535, 0]
        .iter()
        .flat_map(|x| x.to_le_bytes())
        .collect();
    let uv_s = doc.accessor(&uv_s, 5123, 3, "VEC2", true);
    let c3 = doc.floats(&[1.0, 0.5, 0.0, 0.0, 1.0, 0.25, 0.0, 0.0, 1.0], "VEC3", 3);
    let c4b = doc.accessor(
        &[255, 0, 0, 51, 0, 255, 0, 102, 0, 0, 255, 255],
        5121,
        3,
        "VEC4",
        true,
    );
    let c4s: Vec<u8> = [65535u16, 0, 0, 0, 0, 65535, 0, 65535, 0, 0, 65535, 13107]
        .iter()
        .flat_map(|x| x.to_le_bytes())
        .collect();
    let c4s = doc.accessor(&c4s, 5123, 3, "VEC4", true);
    doc.mesh_node(
        json!([
            { "attributes": { "POSITION": pos, "TEXCOORD_0": uv_f, "TEXCOORD_1": uv_b, "COLOR_0": c3 } },
            { "attributes": { "POSITION": pos, "TEXCOORD_0": uv_s, "COLOR_0": c4b } },
            { "attributes": { "POSITION": pos, "TEXCOORD_1": uv_f, "COLOR_0": c4s } },
            { "attributes": { "POSITION": pos } }
        ]),
        json!({}),
    );
    let (_dir, read) = read_doc(&doc, Container::Glb);
    let v2 = glam::DVec2::new;
    let m: Vec<_> = read.meshes.iter().map(|m| &m.mesh).collect();
    assert_eq!(
        m[0].uvs[0],
        vec![v2(0.0, 0.5), v2(1.0, 0.25), v2(0.125, 1.0)]
    );
    assert_eq!(m[0].uvs[1], vec![v2(0.0, 1.0), v2(0.2, 0.0), v2(1.0, 0.4)]);
    assert_eq!(
        m[1].uvs,
        vec![vec![v2(0.0, 1.0), v2(0.2, 0.0), v2(1.0, 0.0)]]
    );
    // Set 1 without set 0: set 0 reads as zeros.
    assert_eq!(m[2].uvs.len(), 2);
    assert_eq!(m[2].uvs[0], vec![glam::DVec2::ZERO; 3]);
    assert!(m[3].uvs.is_empty() && m[3].colours.is_none());
    let v4 = glam::Vec4::new;
    assert_eq!(
        m[0].colours.as_deref().unwrap(),
        [
            v4(1.0, 0.5, 0.0, 1.0),
            v4(0.0, 1.0, 0.25, 1.0),
            v4(0.0, 0.0, 1.0, 1.0)
        ]
    );
    assert_eq!(
        m[1].colours.as_deref().unwrap(),
        [
            v4(1.0, 0.0, 0.0, 0.2),
            v4(0.0, 1.0, 0.0, 0.4),
            v4(0.0, 0.0, 1.0, 1.0)
        ]
    );
    assert_eq!(
        m[2].colours.as_deref().unwrap(),
        [
            v4(1.0, 0.0, 0.0, 0.0),
            v4(0.0, 1.0, 0.0, 1.0),
            v4(0.0, 0.0, 1.0, 0.2)
        ]
    );

    // Integers must be normalized; shapes and types are checked.
    let mut bad = doc;
    bad.root["accessors"][uv_b]["normalized"] = json!(false);
    let e = error_of(
        &bad,
        Container::Glb,
        "meshes[0].primitives[0].attributes.TEXCOORD_1",
    );
    assert!(e.message.contains("normalized"), "{e}");
    bad.root["accessors"][uv_b]["normalized"] = json!(true);
    bad.root["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"] = json!(c3);
    error_of(
        &bad,
        Container::Glb,
        "meshes[0].primitives[0].attributes.TEXCOORD_0",
    );
    bad.root["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"] = json!(uv_f);
    bad.root["meshes"][0]["primitives"][0]["attributes"]["COLOR_0"] = json!(uv_f);
    error_of(
        &bad,
        Container::Glb,
        "meshes[0].primitives[0].attributes.COLOR_0",
    );
}

/// KHR_materials_unlit: the colour is base colour × texture × vertex
/// colour, so an unlit material's emission is scaled by COLOR_0; other
/// materials' emission is not.
#[test]
fn unlit_materials_emit_by_vertex_colour() {
    let mut doc = material_doc(json!([
        { "pbrMetallicRoughness": { "baseColorFactor": [0.5, 0.25, 1, 1] },
          "extensions": { "KHR_materials_unlit": {} } },
        { "emissiveFactor": [1, 0.5, 0] }
    ]));
    doc.root["extensionsUsed"] = json!(["KHR_materials_unlit"]);
    let scene = load_doc(&doc, &LoadOptions::default()).scene;
    let (unlit, lit) = (&scene.objects[0].maps, &scene.objects[1].maps);
    assert_eq!(unlit.emission, Vec3::new(0.5, 0.25, 1.0));
    assert!(unlit.emission_by_colour);
    assert_eq!(lit.emission, Vec3::new(1.0, 0.5, 0.0));
    assert!(!lit.emission_by_colour);
}

/// An occlusionTexture's KHR_texture_transform (read from the JSON, as the
/// normal map's) and its texCoord override.
#[test]
fn occlusion_textures_take_their_texture_transform() {
    let mut doc = material_doc(json!([{ "occlusionTexture": { "index": 0, "extensions": {
        "KHR_texture_transform": { "offset": [0.25, 0.5], "texCoord": 1 } } } }]));
    doc.root["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_1"] =
        doc.root["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"].clone();
    doc.root["textures"] = json!([{ "source": 0 }]);
    doc.root["images"] = json!([{ "uri": png_uri(1, 1) }]);
    doc.root["extensionsUsed"] = json!(["KHR_texture_transform"]);
    let scene = load_doc(&doc, &LoadOptions::default()).scene;
    let (t, strength) = scene.objects[0].maps.occlusion.expect("occlusion");
    assert_eq!(strength, 1.0, "glTF's default strength");
    assert_eq!(t.tex_coord, 1);
    assert_eq!(t.transform.offset, glam::DVec2::new(0.25, 0.5));
    assert!(!scene.textures[t.texture].srgb, "occlusion is linear");
}

#[test]
fn tangents_follow_the_node_transform_and_mirroring_flips_their_sign() {
    let mut doc = material_doc(json!([{ "normalTexture": { "index": 0 } }]));
    let tan = doc.floats(&[1.0, 0.0, 0.0, 1.0].repeat(4), "VEC4", 4);
    doc.root["meshes"][0]["primitives"][0]["attributes"]["TANGENT"] = json!(tan);
    doc.root["textures"] = json!([{ "source": 0 }]);
    doc.root["images"] = json!([{ "uri": png_uri(2, 2) }]);
    doc.root["nodes"][0]["scale"] = json!([-2, 1, 1]);
    let (_dir, read) = read_doc(&doc, Container::Embedded);
    let mesh = &read.meshes[0].mesh;
    for t in mesh.tangents.as_ref().unwrap() {
        assert_eq!(*t, glam::DVec4::new(-1.0, 0.0, 0.0, -1.0));
    }
    // A normal map's image is linear.
    assert_eq!(read.textures.len(), 1);
    assert!(!read.textures[0].srgb);
    // A mesh without normals gets MikkTSpace tangents from flat normals.
    let mut flat = doc;
    flat.root["nodes"][0]["scale"] = json!([1, 1, 1]);
    let attrs = &mut flat.root["meshes"][0]["primitives"][0]["attributes"];
    attrs.as_object_mut().unwrap().remove("TANGENT");
    attrs.as_object_mut().unwrap().remove("NORMAL");
    let (_dir, read) = read_doc(&flat, Container::Embedded);
    let mesh = &read.meshes[0].mesh;
    assert!(mesh.normals.is_none());
    let t = mesh.tangents.as_ref().unwrap();
    assert_eq!(t.len(), mesh.positions.len());
    assert!(t
        .iter()
        .all(|t| (t.truncate() - DVec3::X).length() < 1e-6 && t.w == 1.0));
    // Without the normal map's uv set there is no tangent direction: zero
    // tangents, which leave the normal as it is.
    let mut no_uv = flat;
    let attrs = &mut no_uv.root["meshes"][0]["primitives"][0]["attributes"];
    attrs.as_object_mut().unwrap().remove("TEXCOORD_0");
    let (_dir, read) = read_doc(&no_uv, Container::Embedded);
    let t = read.meshes[0].mesh.tangents.as_ref().unwrap();
    assert_eq!(t, &vec![glam::DVec4::W; 4]);
}

#[test]
fn images_from_files_and_glb_buffer_views() {
    // An external file with an escaped name, recorded for `watch`.
    let dir = TempDir::new().unwrap();
    std::fs::write(dir.path().join("my tex.png"), png(2, 3)).unwrap();
    let mut doc =
        material_doc(json!([{ "pbrMetallicRoughness": { "baseColorTexture": { "index": 0 } } }]));
    doc.root["textures"] = json!([{ "source": 0 }]);
    doc.root["images"] = json!([{ "uri": "my%20tex.png" }]);
    let path = doc.write(dir.path(), "model", Container::External);
    let read = gltf::read(&path).unwrap_or_else(|e| panic!("{e}"));
    let file = dir.path().join("my tex.png");
    assert_eq!(read.files.last(), Some(&file));
    assert_eq!(read.textures[0].file.as_ref(), Some(&file));
    assert_eq!((read.textures[0].width, read.textures[0].height), (2, 3));
    let loaded = gltf::load(&path, &LoadOptions::default()).unwrap();
    assert!(loaded.files.contains(&file));

    // A bufferView in a GLB.
    let bytes = png(4, 1);
    let view = doc.view(&bytes);
    doc.root["images"] = json!([{ "bufferView": view, "mimeType": "image/png" }]);
    let (_dir, read) = read_doc(&doc, Container::Glb);
    assert_eq!((read.textures[0].width, read.textures[0].height), (4, 1));
    assert_eq!(read.textures[0].texels[3], [3, 0, 7, 203]);
    assert_eq!(read.textures[0].file, None);
}

#[test]
fn bad_images_and_texture_references_name_the_file_and_field() {
    let base = || {
        let mut doc = material_doc(
            json!([{ "pbrMetallicRoughness": { "baseColorTexture": { "index": 0 } } }]),
        );
        doc.root["textures"] = json!([{ "source": 0 }]);
        doc.root["images"] = json!([{ "uri": png_uri(1, 1) }]);
        doc
    };
    // Sets (or adds) the field at a JSON pointer.
    let with = |pointer: &str, value: Value| {
        let mut doc = base();
        let (parent, key) = pointer.rsplit_once('/').unwrap();
        let parent = doc.root.pointer_mut(parent).unwrap();
        match key.parse::<usize>() {
            Ok(i) => parent[i] = value,
            Err(_) => parent[key] = value,
        }
        doc
    };
    let message = |doc: &Doc, field: &str| error_of(doc, Container::Embedded, field).message;

    let m = message(
        &with("/images/0/uri", json!("missing.png")),
        "images[0].uri",
    );
    assert!(m.contains("missing.png"), "{m}");
    let mut corrupt = png(8, 8);
    corrupt.truncate(corrupt.len() / 2);
    let uri = format!("data:image/png;base64,{}", crate::base64::encode(&corrupt));
    let m = message(&with("/images/0/uri", json!(uri)), "images[0].uri");
    assert!(m.contains("corrupt"), "{m}");
    let gif = format!(
        "data:image/gif;base64,{}",
        crate::base64::encode(b"GIF89a\x01\x00\x01\x00\x00\x00\x00;")
    );
    let m = message(&with("/images/0/uri", json!(gif)), "images[0].uri");
    assert!(m.contains("PNG or JPEG"), "{m}");
    let m = message(
        &with("/images/0/uri", json!(png_uri(16385, 1))),
        "images[0].uri",
    );
    assert!(m.contains("larger than"), "{m}");
    message(
        &with("/images/0/uri", json!("https://example.com/a.png")),
        "images[0].uri",
    );
    message(
        &with("/images/0/uri", json!("data:image/png;base64,@@")),
        "images[0].uri",
    );
    message(&with("/images/0", json!({})), "images[0]");
    let mut doc = base();
    let view = doc.view(&png(1, 1));
    doc.root["images"] = json!([{ "bufferView": view }]);
    message(&doc, "images[0].mimeType");

    // Indices outside the file.
    message(
        &with(
            "/materials/0/pbrMetallicRoughness/baseColorTexture/index",
            json!(3),
        ),
        "materials[0].pbrMetallicRoughness.baseColorTexture.index",
    );
    message(&with("/textures/0/source", json!(2)), "textures[0].source");
    message(
        &with("/textures/0", json!({ "source": 0, "sampler": 1 })),
        "textures[0].sampler",
    );
    message(
        &with(
            "/materials/0/pbrMetallicRoughness/baseColorTexture/texCoord",
            json!(2),
        ),
        "materials[0].pbrMetallicRoughness.baseColorTexture.texCoord",
    );
    let doc = with(
        "/materials/0/pbrMetallicRoughness/baseColorTexture",
        json!({ "index": 0, "extensions": { "KHR_texture_transform": { "texCoord": 5 } } }),
    );
    message(
        &doc,
        "materials[0].pbrMetallicRoughness.baseColorTexture.extensions.KHR_texture_transform.texCoord",
    );
    let doc = with(
        "/materials/0",
        json!({ "alphaMode": "MASK", "alphaCutoff": -1 }),
    );
    message(&doc, "materials[0].alphaCutoff");
    for strength in [1.5, -0.5] {
        let doc = with(
            "/materials/0/occlusionTexture",
            json!({ "index": 0, "strength": strength }),
        );
        message(&doc, "materials[0].occlusionTexture.strength");
    }
    let doc = with("/materials/0/occlusionTexture", json!({ "index": 3 }));
    message(&doc, "materials[0].occlusionTexture.index");
    let doc = with(
        "/materials/0/occlusionTexture",
        json!({ "index": 0, "texCoord": 2 }),
    );
    message(&doc, "materials[0].occlusionTexture.texCoord");

    // The texels are charged to the memory budget before they are decoded.
    let doc = with("/images/0/uri", json!(png_uri(1024, 1024)));
    let dir = TempDir::new().unwrap();
    let path = doc.write(dir.path(), "model", Container::Embedded);
    let opts = LoadOptions {
        max_scene_bytes: 2 << 20,
        ..Default::default()
    };
    let err = gltf::read_with(&path, &Guard::new(&path, &opts)).unwrap_err();
    assert_eq!(err.field, "images[0].uri", "{err}");
    assert!(err.message.contains("memory budget"), "{err}");
}
