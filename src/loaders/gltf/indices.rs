//! Indices above `u32` in a glTF file's JSON, refused before the `gltf`
//! crate reads it.
//!
//! gltf-json 1.4.1 reads every index (`textures[0].source`,
//! `materials[0].pbrMetallicRoughness.baseColorTexture.index`, ...) as a
//! `u64` and keeps it `as u32`, so 4294967296 would silently become
//! index 0 and pass its range check. This module walks the JSON first and
//! names the first index field whose value does not fit, by the file's own
//! field path; indices that fit but lie out of range are left to the
//! crate's validation, which names them too.

use serde_json::Value;

/// The keys whose value is an index into one of the file's arrays (or an
/// array of such indices), in glTF 2.0 and the extensions penumbra reads
/// (`KHR_lights_punctual`'s `light`).
const INDEX_KEYS: &[&str] = &[
    "buffer",
    "bufferView",
    "camera",
    "children",
    "index",
    "indices",
    "input",
    "inverseBindMatrices",
    "joints",
    "light",
    "material",
    "mesh",
    "node",
    "nodes",
    "output",
    "sampler",
    "scene",
    "skeleton",
    "skin",
    "source",
];

/// The keys whose value maps names to accessor indices (`attributes`), or
/// holds an array of such maps (`targets`).
const INDEX_MAP_KEYS: &[&str] = &["attributes", "targets"];

/// The first index in `root` above `u32::MAX`: its field path and the
/// message for it.
pub(super) fn first_oversized_index(root: &Value) -> Option<(String, String)> {
    let mut path = String::new();
    walk(root, &mut path)
}

/// Walks `value` at `path`, checking the index fields of every object.
fn walk(value: &Value, path: &mut String) -> Option<(String, String)> {
    match value {
        Value::Object(map) => {
            for (key, v) in map {
                // `extras` is the application's own data, not indices.
                if key == "extras" {
                    continue;
                }
                let len = path.len();
                if !path.is_empty() {
                    path.push('.');
                }
                path.push_str(key);
                let found = if INDEX_KEYS.contains(&key.as_str()) {
                    check_indices(v, path)
                } else if INDEX_MAP_KEYS.contains(&key.as_str()) {
                    check_maps(v, path)
                } else {
                    None
                };
                let found = found.or_else(|| walk(v, path));
                path.truncate(len);
                if found.is_some() {
                    return found;
                }
            }
            None
        }
        Value::Array(items) => items.iter().enumerate().find_map(|(i, v)| {
            let len = path.len();
            path.push_str(&format!("[{i}]"));
            let found = walk(v, path);
            path.truncate(len);
            found
        }),
        _ => None,
    }
}

/// An index, or an array of indices, at `path`.
fn check_indices(value: &Value, path: &str) -> Option<(String, String)> {
    match value {
        Value::Array(items) => items
            .iter()
            .enumerate()
            .find_map(|(i, v)| check_index(v, &format!("{path}[{i}]"))),
        v => check_index(v, path),
    }
}

/// An object of indices (`attributes`), or an array of them (`targets`), at `path`.
fn check_maps(value: &Value, path: &str) -> Option<(String, String)> {
    match value {
        Value::Object(map) => map
            .iter()
            .find_map(|(k, v)| check_index(v, &format!("{path}.{k}"))),
        Value::Array(items) => items
            .iter()
            .enumerate()
            .find_map(|(i, v)| check_maps(v, &format!("{path}[{i}]"))),
        _ => None,
    }
}

/// One value at `path`: refused when it is an integer above `u32::MAX`
/// (other types and negative numbers are the `gltf` crate's to report).
fn check_index(value: &Value, path: &str) -> Option<(String, String)> {
    let n = value.as_u64().filter(|&n| n > u64::from(u32::MAX))?;
    let message = format!(
        "index {n} is larger than a glTF index can be ({} at most)",
        u32::MAX
    );
    Some((path.to_string(), message))
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn finds_indices_above_u32_by_their_path() {
        let big = u64::from(u32::MAX) + 1;
        let doc = json!({
            "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": big}}}]
        });
        let (path, message) = first_oversized_index(&doc).unwrap();
        assert_eq!(
            path,
            "materials[0].pbrMetallicRoughness.baseColorTexture.index"
        );
        assert!(message.contains("4294967296"), "{message}");
        let doc = json!({"textures": [{"source": 0}, {"sampler": 1, "source": big}]});
        assert_eq!(first_oversized_index(&doc).unwrap().0, "textures[1].source");
        let doc = json!({"scenes": [{"nodes": [0, big]}]});
        assert_eq!(first_oversized_index(&doc).unwrap().0, "scenes[0].nodes[1]");
        let doc = json!({"meshes": [{"primitives": [{"attributes": {"POSITION": big}}]}]});
        assert_eq!(
            first_oversized_index(&doc).unwrap().0,
            "meshes[0].primitives[0].attributes.POSITION"
        );
        let doc = json!({"meshes": [{"primitives": [{"targets": [{"NORMAL": big}]}]}]});
        assert_eq!(
            first_oversized_index(&doc).unwrap().0,
            "meshes[0].primitives[0].targets[0].NORMAL"
        );
    }

    #[test]
    fn leaves_sizes_extras_and_indices_that_fit() {
        let big = u64::from(u32::MAX) + 1;
        let doc = json!({
            "buffers": [{"byteLength": big}],
            "accessors": [{"count": big, "byteOffset": big, "bufferView": u32::MAX}],
            "nodes": [{"extras": {"index": big}}]
        });
        assert_eq!(first_oversized_index(&doc), None);
    }
}
