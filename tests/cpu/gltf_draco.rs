//! KHR_draco_mesh_compression (issue 39): the Duck compressed by Google's
//! Draco encoder (tests/data/khronos/Duck/README.md says how) decodes to
//! the plain Duck's triangles within half a quantization step, and a bad
//! stream, a bad extension object or a declared size over the budget gives
//! one error naming the file's field.

use std::path::{Path, PathBuf};

use glam::{DVec2, DVec3};
use penumbra::loaders::gltf;
use penumbra::loaders::{self, LoadOptions};
use serde_json::{json, Value};

use crate::gltf_loader::glb;

fn duck(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/khronos/Duck")
        .join(name)
}

/// The Draco Duck's JSON and BIN chunk.
fn draco_duck() -> (Value, Vec<u8>) {
    let data = std::fs::read(duck("Duck_draco.glb")).unwrap();
    let word = |at: usize| u32::from_le_bytes(data[at..at + 4].try_into().unwrap()) as usize;
    let json_len = word(12);
    let json = serde_json::from_slice(&data[20..20 + json_len]).unwrap();
    let bin_at = 20 + json_len;
    let bin = data[bin_at + 8..bin_at + 8 + word(bin_at)].to_vec();
    (json, bin)
}

/// The largest side of the bounding box of `points` (each `n` numbers).
fn largest_side(points: impl Iterator<Item = Vec<f64>>) -> f64 {
    let mut lo = [f64::MAX; 3];
    let mut hi = [f64::MIN; 3];
    for p in points {
        for (k, x) in p.into_iter().enumerate() {
            lo[k] = lo[k].min(x);
            hi[k] = hi[k].max(x);
        }
    }
    lo.iter()
        .zip(&hi)
        .map(|(l, h)| h - l)
        .filter(|d| d.is_finite())
        .fold(0.0, f64::max)
}

/// One triangle's corners: world position and TEXCOORD_0.
type Corners = [(DVec3, DVec2); 3];

fn triangles(doc: &gltf::GltfDocument) -> Vec<Corners> {
    let m = &doc.meshes[0].mesh;
    m.indices
        .iter()
        .map(|t| t.map(|i| (m.positions[i as usize], m.uvs[0][i as usize])))
        .collect()
}

#[test]
fn the_draco_duck_decodes_to_the_plain_ducks_triangles_within_half_a_quantization_step() {
    let plain = gltf::read(&duck("Duck.gltf")).unwrap_or_else(|e| panic!("{e}"));
    let draco = gltf::read(&duck("Duck_draco.glb")).unwrap_or_else(|e| panic!("{e}"));
    let (plain_mesh, draco_mesh) = (&plain.meshes[0].mesh, &draco.meshes[0].mesh);
    assert_eq!(draco_mesh.indices.len(), plain_mesh.indices.len());
    assert_eq!(draco_mesh.positions.len(), plain_mesh.positions.len());

    // Draco quantizes each attribute on one grid over its bounding box's
    // largest side, 2^bits − 1 steps (gltf-transform's defaults: 14 bits
    // for POSITION, 12 for TEXCOORD_0), rounding to the nearest step. The
    // Duck's root node is a uniform scale, so the world-space step is the
    // world bounding box's largest side over the same number of steps.
    let pos_step = largest_side(plain_mesh.positions.iter().map(|p| p.to_array().to_vec()))
        / f64::from((1 << 14) - 1);
    let uv_step = largest_side(plain_mesh.uvs[0].iter().map(|p| p.to_array().to_vec()))
        / f64::from((1 << 12) - 1);
    // The file's values and the decoder's are f32: a few ulps of the
    // largest coordinates (below 2 in world units, below 1 in uv) on top.
    let (pos_tol, uv_tol) = (
        pos_step / 2.0 + 4.0 * 2.0 * f64::from(f32::EPSILON),
        uv_step / 2.0 + 4.0 * f64::from(f32::EPSILON),
    );

    // Draco reorders vertices and triangles and may start a triangle at
    // another corner, but keeps its winding: match each decoded triangle
    // to a plain one, corners rotated, near its centroid.
    let plain_tris = triangles(&plain);
    let centroid = |t: &Corners| (t[0].0 + t[1].0 + t[2].0) / 3.0;
    let mut by_x: Vec<(f64, usize)> = plain_tris
        .iter()
        .enumerate()
        .map(|(i, t)| (centroid(t).x, i))
        .collect();
    by_x.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut unmatched = 0;
    for t in triangles(&draco) {
        let x = centroid(&t).x;
        let start = by_x.partition_point(|(cx, _)| *cx < x - pos_tol);
        let matched = by_x[start..]
            .iter()
            .take_while(|(cx, _)| *cx <= x + pos_tol)
            .any(|&(_, i)| {
                (0..3).any(|r| {
                    (0..3).all(|k| {
                        let (p, uv) = plain_tris[i][(k + r) % 3];
                        (p - t[k].0).abs().max_element() <= pos_tol
                            && (uv - t[k].1).abs().max_element() <= uv_tol
                    })
                })
            });
        unmatched += usize::from(!matched);
    }
    assert_eq!(unmatched, 0, "decoded triangles with no plain match");
}

/// The error for the Draco Duck changed by `change`, written as a GLB.
fn draco_error(change: impl FnOnce(&mut Value, &mut Vec<u8>), opts: &LoadOptions) -> String {
    let (mut json, mut bin) = draco_duck();
    change(&mut json, &mut bin);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("duck.glb");
    json["buffers"][0]["byteLength"] = json!(bin.len());
    std::fs::write(
        &path,
        glb(serde_json::to_string(&json).unwrap().as_bytes(), &bin),
    )
    .unwrap();
    let Err(err) = gltf::load(&path, opts) else {
        panic!("expected an error")
    };
    let text = err.to_string();
    assert!(text.contains(&path.display().to_string()), "{text}");
    assert_eq!(text.lines().count(), 1, "{text}");
    text
}

const EXT: &str = "meshes[0].primitives[0].extensions.KHR_draco_mesh_compression";

#[test]
fn bad_draco_streams_and_extension_objects_name_the_field() {
    let opts = LoadOptions::default();
    // A stream cut short, and one with flipped bytes.
    let cut = draco_error(
        |j, _| j["bufferViews"][1]["byteLength"] = json!(4000),
        &opts,
    );
    assert!(
        cut.contains(&format!(
            "{EXT}.bufferView: bufferViews[1] is not a valid Draco mesh"
        )),
        "{cut}"
    );
    let flipped = draco_error(
        |j, bin| {
            let at = j["bufferViews"][1]["byteOffset"].as_u64().unwrap() as usize;
            bin[at + 20..at + 400].iter_mut().for_each(|b| *b ^= 0x5a);
        },
        &opts,
    );
    assert!(
        flipped.contains(&format!("{EXT}.bufferView: ")),
        "{flipped}"
    );
    // An attribute id the stream lacks, a count other than the stream's,
    // a shape other than the stream's, and no bufferView.
    let id = draco_error(
        |j, _| {
            j["meshes"][0]["primitives"][0]["extensions"]["KHR_draco_mesh_compression"]
                ["attributes"]["POSITION"] = json!(7)
        },
        &opts,
    );
    assert!(
        id.contains(&format!(
            "{EXT}.attributes.POSITION: Draco attribute 7 is not in the stream"
        )),
        "{id}"
    );
    let count = draco_error(|j, _| j["accessors"][2]["count"] = json!(2400), &opts);
    assert!(count.contains(&format!("{EXT}.attributes.POSITION: accessors[2] declares 2400 vertices but the Draco stream has 2399")), "{count}");
    let indices = draco_error(|j, _| j["accessors"][0]["count"] = json!(12639), &opts);
    assert!(indices.contains("meshes[0].primitives[0].indices: accessors[0] declares 12639 indices but the Draco stream has 4212 triangles"), "{indices}");
    let fewer = draco_error(|j, _| j["accessors"][0]["count"] = json!(12633), &opts);
    assert!(fewer.contains(&format!("{EXT}.bufferView: bufferViews[1] declares 4212 triangles in its Draco header, more than the 4211 its accessors allow (refused before decoding)")), "{fewer}");
    let shape = draco_error(|j, _| j["accessors"][3]["type"] = json!("VEC3"), &opts);
    assert!(shape.contains(&format!("{EXT}.attributes.TEXCOORD_0: accessors[3] has 3 components but Draco attribute 2 has 2")), "{shape}");
    let view = draco_error(
        |j, _| {
            j["meshes"][0]["primitives"][0]["extensions"]["KHR_draco_mesh_compression"]
                ["bufferView"] = json!(9)
        },
        &opts,
    );
    assert!(
        view.contains(&format!(
            "{EXT}.bufferView: 9 is not a bufferView of the file"
        )),
        "{view}"
    );
}

#[test]
fn a_draco_primitives_declared_size_is_charged_before_it_is_decoded() {
    // A billion vertices declared for a 17 kB stream: refused by the
    // budget, from the accessors, before the decoder sees the stream.
    let opts = LoadOptions {
        max_scene_bytes: 64 << 20,
        ..loaders::LoadOptions::default()
    };
    let bomb = draco_error(
        |j, _| j["accessors"][2]["count"] = json!(1_000_000_000u64),
        &opts,
    );
    assert!(
        bomb.contains(&format!("{EXT}.bufferView: the scene would need")),
        "{bomb}"
    );
    assert!(bomb.contains("--max-scene-memory"), "{bomb}");
    // A stream whose header claims more than its accessors: the Duck's
    // edgebreaker header (byte 11 the traversal type, then the varint
    // number of encoded vertices, 2108 in two bytes) made to claim 16383,
    // more than three per declared triangle; refused before the decoder
    // allocates by it.
    let header = draco_error(
        |j, bin| {
            let at = j["bufferViews"][1]["byteOffset"].as_u64().unwrap() as usize;
            assert_eq!(bin[at + 12..at + 14], [0xbc, 0x10], "2108 as a varint");
            bin[at + 12..at + 14].copy_from_slice(&[0xff, 0x7f]);
        },
        &opts,
    );
    assert!(
        header.contains("bufferViews[1] declares 16383 vertices in its Draco header, more than the 12636 its accessors allow (refused before decoding)"),
        "{header}"
    );
    // The same budget holds the Duck itself.
    let path = duck("Duck_draco.glb");
    gltf::load(&path, &opts).unwrap_or_else(|e| panic!("{e}"));
}
