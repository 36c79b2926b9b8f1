//! KHR_draco_mesh_compression: triangle primitives whose indices and
//! attributes are one Draco stream in a bufferView, decoded with the
//! `draco-oxide-decoder` crate (a pure-Rust reader of the Draco 2.2
//! bitstream, interoperable with Google's encoder; docs/gltf.md says what
//! else was tried).
//!
//! From the extension's specification (Khronos glTF extension registry,
//! `KHR_draco_mesh_compression/README.md`): the primitive's extension
//! object names the `bufferView` holding the stream and maps each glTF
//! attribute semantic to the Draco attribute's unique id (`attributes`).
//! The primitive's `indices` and those attributes' accessors keep their
//! `count`, `componentType` and `type` but have no bufferView: the decoder
//! fills them, the faces giving the indices and each Draco point a vertex.
//! Attributes the map does not name are read uncompressed as usual.
//!
//! What the accessors declare is charged against `--max-scene-memory`
//! before the stream is decoded, the counts the stream's header declares
//! (by which the decoder allocates) may not exceed it ([`check_counts`]),
//! and the decoded mesh must match it exactly, so a small stream cannot
//! claim more than its file declares.

use std::collections::HashMap;

use draco_oxide_core::attribute::ComponentDataType;
use serde_json::Value;

/// The name of the extension, as in the file.
pub(super) const NAME: &str = "KHR_draco_mesh_compression";

/// One accessor the stream fills: its index in `accessors`, what it is
/// (`indices` or an attribute's semantic) and its declared shape.
#[derive(Clone, Debug)]
pub(super) struct Filled {
    pub accessor: usize,
    /// `None` for the primitive's indices, else the Draco attribute's unique id.
    pub unique_id: Option<u64>,
    /// Where the file names it, relative to the primitive, e.g.
    /// `indices` or `extensions.KHR_draco_mesh_compression.attributes.NORMAL`.
    pub field: String,
    pub count: usize,
    pub components: usize,
}

/// One compressed primitive, as its extension object declares it.
#[derive(Clone, Debug)]
pub(super) struct Compressed {
    pub view: usize,
    pub filled: Vec<Filled>,
}

impl Compressed {
    /// The decoded size in bytes, as the reader keeps it (f64 components).
    pub fn decoded_len(&self) -> u64 {
        self.filled.iter().fold(0u64, |sum, f| {
            let n = (f.count as u64).saturating_mul(f.components as u64);
            sum.saturating_add(n.saturating_mul(8))
        })
    }
}

/// The primitive's extension object, if it has one; errors are (field
/// relative to the primitive, message). `accessors` is the file's
/// `accessors` array, for the declared counts and shapes.
pub(super) fn parse(
    prim: &Value,
    accessors: &Value,
) -> Result<Option<Compressed>, (String, String)> {
    let ext_field = format!("extensions.{NAME}");
    let Some(ext) = prim.get("extensions").and_then(|e| e.get(NAME)) else {
        return Ok(None);
    };
    let view = ext
        .get("bufferView")
        .and_then(Value::as_u64)
        .and_then(|v| usize::try_from(v).ok());
    let Some(view) = view else {
        let message = "must be the index of the bufferView holding the Draco stream";
        return Err((format!("{ext_field}.bufferView"), message.into()));
    };
    let Some(map) = ext.get("attributes").and_then(Value::as_object) else {
        let message = "must map attribute semantics to Draco attribute ids";
        return Err((format!("{ext_field}.attributes"), message.into()));
    };
    let accessor = |index: Option<&Value>, field: String| {
        let index = index
            .and_then(Value::as_u64)
            .and_then(|i| usize::try_from(i).ok());
        let Some((i, acc)) = index.and_then(|i| Some((i, accessors.get(i)?))) else {
            return Err((field, "is not an accessor of the file".to_string()));
        };
        let count = acc.get("count").and_then(Value::as_u64).unwrap_or(0);
        let components = match acc.get("type").and_then(Value::as_str) {
            Some("SCALAR") => 1,
            Some("VEC2") => 2,
            Some("VEC3") => 3,
            Some("VEC4") => 4,
            _ => 0,
        };
        Ok((i, count as usize, components))
    };
    let Some(indices) = prim.get("indices") else {
        let message = format!("is required with {NAME} (a Draco mesh is indexed)");
        return Err(("indices".into(), message));
    };
    let (i, count, components) = accessor(Some(indices), "indices".into())?;
    let mut filled = vec![Filled {
        accessor: i,
        unique_id: None,
        field: "indices".into(),
        count,
        components,
    }];
    for (semantic, id) in map {
        let field = format!("{ext_field}.attributes.{semantic}");
        let Some(id) = id.as_u64() else {
            return Err((field, "must be a Draco attribute id".into()));
        };
        let used = prim.get("attributes").and_then(|a| a.get(semantic));
        let Some(used) = used else {
            let message = format!("names attributes.{semantic}, which the primitive lacks");
            return Err((field, message));
        };
        let (i, count, components) = accessor(Some(used), format!("attributes.{semantic}"))?;
        filled.push(Filled {
            accessor: i,
            unique_id: Some(id),
            field,
            count,
            components,
        });
    }
    Ok(Some(Compressed { view, filled }))
}

/// Decodes the stream into the values of each filled accessor, as numbers
/// in the accessor's own component domain (integers stay integers, for the
/// reader to normalise as it does uncompressed data); errors are (field
/// relative to the primitive, message).
pub(super) fn decode(
    c: &Compressed,
    stream: &[u8],
) -> Result<HashMap<usize, Vec<f64>>, (String, String)> {
    let ext_field = format!("extensions.{NAME}");
    let corners = c.filled.iter().find(|f| f.unique_id.is_none());
    let faces = corners.map_or(0, |f| f.count / 3) as u64;
    check_counts(stream, faces).map_err(|m| {
        let message = format!("bufferViews[{}] {m}", c.view);
        (format!("{ext_field}.bufferView"), message)
    })?;
    // The decoder is young (an alpha): a panic of its own on a malformed
    // stream is reported as this stream's error too.
    let decoded = crate::panics::catch(|| draco_oxide_decoder::decode_mesh(stream));
    let mesh = match decoded {
        Ok(Ok(mesh)) => Ok(mesh),
        Ok(Err(e)) => Err(e.to_string()),
        Err(panic) => Err(format!("the decoder failed ({panic})")),
    }
    .map_err(|e| {
        let message = format!("bufferViews[{}] is not a valid Draco mesh: {e}", c.view);
        (format!("{ext_field}.bufferView"), message)
    })?;
    let points = mesh.attributes.first().map_or(0, |a| a.len());
    let mut out = HashMap::new();
    for f in &c.filled {
        let values = match f.unique_id {
            None => {
                let corners = mesh.faces.len() * 3;
                if corners != f.count || f.components != 1 {
                    let message =
                        format!(
                        "accessors[{}] declares {} indices but the Draco stream has {} triangles",
                        f.accessor, f.count, mesh.faces.len()
                    );
                    return Err((f.field.clone(), message));
                }
                let flat = mesh.faces.iter().flat_map(|t| t.map(usize::from));
                flat.map(|p| p as f64).collect()
            }
            Some(id) => {
                let att = mesh
                    .attributes
                    .iter()
                    .find(|a| a.get_id().as_usize() as u64 == id);
                let Some(att) = att else {
                    let message = format!("Draco attribute {id} is not in the stream");
                    return Err((f.field.clone(), message));
                };
                if att.len() != f.count || att.len() != points {
                    let message = format!(
                        "accessors[{}] declares {} vertices but the Draco stream has {}",
                        f.accessor,
                        f.count,
                        att.len()
                    );
                    return Err((f.field.clone(), message));
                }
                if att.get_num_components() != f.components {
                    let message = format!(
                        "accessors[{}] has {} components but Draco attribute {id} has {}",
                        f.accessor,
                        f.components,
                        att.get_num_components()
                    );
                    return Err((f.field.clone(), message));
                }
                attribute_values(att, f.components).ok_or_else(|| {
                    let message = format!("Draco attribute {id} has an unreadable value type");
                    (f.field.clone(), message)
                })?
            }
        };
        out.insert(f.accessor, values);
    }
    Ok(out)
}

/// The counts the stream's connectivity header declares, against the
/// `faces` triangles its `indices` accessor declares (and the memory budget
/// was charged for): the decoder allocates by these counts before it reads
/// the data behind them, so a few bytes could otherwise claim terabytes.
/// From the Draco bitstream specification 2.2 (google/draco,
/// `docs/spec`): the header is "DRACO", version major and minor, geometry
/// type, method (0 sequential, 1 edgebreaker) and 16 flag bits (0x8000:
/// metadata follows); sequential connectivity starts with varints
/// num_faces and num_points, edgebreaker's with a traversal byte, varints
/// num_encoded_vertices and num_faces, a byte num_attribute_data, and
/// varints num_encoded_symbols and num_encoded_split_symbols.
fn check_counts(stream: &[u8], faces: u64) -> Result<(), String> {
    let too_short = || "is not a valid Draco mesh: it ends inside its header".to_string();
    let header = stream.get(..11).ok_or_else(too_short)?;
    if &header[..5] != b"DRACO" {
        return Err("is not a valid Draco mesh: it lacks the DRACO magic".into());
    }
    if u16::from_le_bytes([header[9], header[10]]) & 0x8000 != 0 {
        return Err("is a Draco stream with metadata, which penumbra does not read".into());
    }
    let mut at = 11;
    // An unsigned LEB128 number at `at`, which moves past it.
    let varint = |at: &mut usize| -> Result<u64, String> {
        let mut value = 0u64;
        for shift in (0..64).step_by(7) {
            let byte = *stream.get(*at).ok_or_else(too_short)?;
            *at += 1;
            value |= u64::from(byte & 0x7f) << shift;
            if byte & 0x80 == 0 {
                return Ok(value);
            }
        }
        Err("is not a valid Draco mesh: a count in its header is longer than 64 bits".into())
    };
    let declared = |what: &str, n: u64, most: u64| {
        match n <= most {
        true => Ok(()),
        false => Err(format!(
            "declares {n} {what} in its Draco header, more than the {most} its accessors allow (refused before decoding)"
        )),
    }
    };
    match header[8] {
        0 => {
            declared("triangles", varint(&mut at)?, faces)?;
            // Each point is a corner of some triangle.
            declared("points", varint(&mut at)?, faces.saturating_mul(3))?;
        }
        1 => {
            at += 1; // the traversal decoder's type
            declared("vertices", varint(&mut at)?, faces.saturating_mul(3))?;
            declared("triangles", varint(&mut at)?, faces)?;
            at += 1; // num_attribute_data
            declared("symbols", varint(&mut at)?, faces)?;
            declared("split symbols", varint(&mut at)?, faces)?;
        }
        _ => {} // The decoder names an unknown method.
    }
    Ok(())
}

/// One value per point, `n` components each, through the attribute's
/// point-to-value map.
fn attribute_values(att: &draco_oxide_core::attribute::Attribute, n: usize) -> Option<Vec<f64>> {
    let ty = att.get_component_type();
    let size = ty.size();
    let read: fn(&[u8]) -> f64 = match ty {
        ComponentDataType::F32 => |b| f32::from_ne_bytes(b.try_into().unwrap_or_default()).into(),
        ComponentDataType::F64 => |b| f64::from_ne_bytes(b.try_into().unwrap_or_default()),
        ComponentDataType::U8 => |b| b[0].into(),
        ComponentDataType::I8 => |b| (b[0] as i8).into(),
        ComponentDataType::U16 => |b| u16::from_ne_bytes(b.try_into().unwrap_or_default()).into(),
        ComponentDataType::I16 => |b| i16::from_ne_bytes(b.try_into().unwrap_or_default()).into(),
        ComponentDataType::U32 => |b| u32::from_ne_bytes(b.try_into().unwrap_or_default()).into(),
        ComponentDataType::I32 => |b| i32::from_ne_bytes(b.try_into().unwrap_or_default()).into(),
        _ => return None,
    };
    let bytes = att.get_data_as_bytes();
    let element = size * n;
    let mut out = Vec::with_capacity(att.len() * n);
    for p in 0..att.len() {
        let v = usize::from(att.get_unique_val_idx(p.into()));
        let value = bytes.get(v * element..(v + 1) * element)?;
        out.extend(value.chunks_exact(size).map(read));
    }
    Some(out)
}
