//! EXT_meshopt_compression: buffer views whose bytes are a meshoptimizer
//! stream in another buffer, decoded with the reference decoder (the
//! `meshopt` crate).
//!
//! From the extension's specification (Khronos glTF extension registry,
//! `EXT_meshopt_compression/README.md`): a bufferView's extension object
//! names the compressed bytes (`buffer`, `byteOffset`, `byteLength`) and
//! what they decode to: `count` elements of `byteStride` bytes, by `mode`
//! `ATTRIBUTES` (stride a multiple of 4, at most 256), `TRIANGLES` (count a
//! multiple of 3) or `INDICES` (stride 2 or 4), then `filter` `NONE`,
//! `OCTAHEDRAL` (stride 4 or 8), `QUATERNION` (stride 8) or `EXPONENTIAL`
//! (stride a multiple of 4), attributes only. The decoded size, `count ×
//! byteStride`, must equal the bufferView's `byteLength`. A buffer whose
//! extension object says `fallback: true` holds data only for readers
//! without the extension; penumbra never reads it.
//!
//! Every decoded view is charged against `--max-scene-memory` from its
//! declared size before it is allocated, so a small file cannot claim a
//! huge decoded size.

use meshopt::ffi;
use serde_json::Value;

/// One compressed view, as its extension object declares it.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Compressed {
    pub buffer: usize,
    pub offset: usize,
    pub length: usize,
    pub stride: usize,
    pub count: usize,
    mode: Mode,
    filter: Filter,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Mode {
    Attributes,
    Triangles,
    Indices,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Filter {
    None,
    Octahedral,
    Quaternion,
    Exponential,
}

/// The name of the extension, as in the file.
pub(super) const NAME: &str = "EXT_meshopt_compression";

impl Compressed {
    /// The decoded size in bytes.
    pub fn decoded_len(&self) -> u64 {
        (self.count as u64).saturating_mul(self.stride as u64)
    }
}

/// A `bufferViews[i]` JSON object's compression, if it has one; `Err`
/// gives the key under the extension object that is wrong and why.
/// `view_length` is the view's own `byteLength`.
pub(super) fn parse(
    view: &Value,
    view_length: usize,
) -> Result<Option<Compressed>, (String, String)> {
    let ext = &view["extensions"][NAME];
    if ext.is_null() {
        return Ok(None);
    }
    let uint = |key: &str, default: Option<usize>| -> Result<usize, (String, String)> {
        match &ext[key] {
            Value::Null => default.ok_or_else(|| (key.into(), "is missing".into())),
            v => v
                .as_u64()
                .and_then(|x| usize::try_from(x).ok())
                .ok_or_else(|| (key.into(), format!("must be an integer >= 0, got {v}"))),
        }
    };
    let buffer = uint("buffer", None)?;
    let offset = uint("byteOffset", Some(0))?;
    let length = uint("byteLength", None)?;
    let stride = uint("byteStride", None)?;
    let count = uint("count", None)?;
    let mode = match ext["mode"].as_str() {
        Some("ATTRIBUTES") => Mode::Attributes,
        Some("TRIANGLES") => Mode::Triangles,
        Some("INDICES") => Mode::Indices,
        _ => {
            let message = format!(
                "must be \"ATTRIBUTES\", \"TRIANGLES\" or \"INDICES\", got {}",
                ext["mode"]
            );
            return Err(("mode".into(), message));
        }
    };
    let filter = match ext["filter"].as_str() {
        None if ext["filter"].is_null() => Filter::None,
        Some("NONE") => Filter::None,
        Some("OCTAHEDRAL") => Filter::Octahedral,
        Some("QUATERNION") => Filter::Quaternion,
        Some("EXPONENTIAL") => Filter::Exponential,
        _ => {
            let message = format!(
                "must be \"NONE\", \"OCTAHEDRAL\", \"QUATERNION\" or \"EXPONENTIAL\", got {}",
                ext["filter"]
            );
            return Err(("filter".into(), message));
        }
    };
    let bad = |key: &str, m: String| Err((key.to_string(), m));
    match mode {
        Mode::Attributes if stride == 0 || stride % 4 != 0 || stride > 256 => {
            return bad(
                "byteStride",
                format!("must be a multiple of 4 up to 256 for ATTRIBUTES, got {stride}"),
            )
        }
        Mode::Triangles | Mode::Indices if stride != 2 && stride != 4 => {
            return bad(
                "byteStride",
                format!("must be 2 or 4 for TRIANGLES and INDICES, got {stride}"),
            )
        }
        Mode::Triangles if count % 3 != 0 => {
            return bad(
                "count",
                format!("must be a multiple of 3 for TRIANGLES, got {count}"),
            )
        }
        _ => {}
    }
    let filter_ok = match filter {
        Filter::None => true,
        _ if mode != Mode::Attributes => false,
        Filter::Octahedral => stride == 4 || stride == 8,
        Filter::Quaternion => stride == 8,
        Filter::Exponential => stride % 4 == 0,
    };
    if !filter_ok {
        let message =
            format!("{filter:?} does not apply to mode {mode:?} with byteStride {stride}");
        return bad("filter", message);
    }
    let c = Compressed {
        buffer,
        offset,
        length,
        stride,
        count,
        mode,
        filter,
    };
    if c.decoded_len() != view_length as u64 {
        let message = format!(
            "count × byteStride is {} bytes but the bufferView's byteLength is {view_length}",
            c.decoded_len()
        );
        return bad("count", message);
    }
    Ok(Some(c))
}

/// Whether a `buffers[i]` JSON object is a fallback buffer of the extension.
pub(super) fn is_fallback(buffer: &Value) -> bool {
    buffer["extensions"][NAME]["fallback"].as_bool() == Some(true)
}

/// Decodes `source` (the compressed bytes, exactly `byteLength` of them)
/// into `count × byteStride` bytes; the caller has charged that size.
pub(super) fn decode(c: &Compressed, source: &[u8]) -> Result<Vec<u8>, String> {
    let len = c.count * c.stride;
    // u32 storage: the filters read 4-byte words in place.
    let mut words = vec![0u32; len.div_ceil(4)];
    let dest = words.as_mut_ptr().cast::<std::ffi::c_void>();
    // SAFETY: `dest` holds at least `count * stride` bytes; the decoders
    // read only `source[..source.len()]` and check the stream's framing,
    // returning non-zero on malformed input.
    let rc = unsafe {
        match c.mode {
            Mode::Attributes => ffi::meshopt_decodeVertexBuffer(
                dest,
                c.count,
                c.stride,
                source.as_ptr(),
                source.len(),
            ),
            Mode::Triangles => ffi::meshopt_decodeIndexBuffer(
                dest,
                c.count,
                c.stride,
                source.as_ptr(),
                source.len(),
            ),
            Mode::Indices => ffi::meshopt_decodeIndexSequence(
                dest,
                c.count,
                c.stride,
                source.as_ptr(),
                source.len(),
            ),
        }
    };
    if rc != 0 {
        return Err(format!(
            "the compressed data is malformed (meshopt decoder error {rc})"
        ));
    }
    // SAFETY: as above; each filter rewrites `count` elements of `stride`
    // bytes in place, within `dest`.
    unsafe {
        match c.filter {
            Filter::None => {}
            Filter::Octahedral => ffi::meshopt_decodeFilterOct(dest, c.count, c.stride),
            Filter::Quaternion => ffi::meshopt_decodeFilterQuat(dest, c.count, c.stride),
            Filter::Exponential => ffi::meshopt_decodeFilterExp(dest, c.count, c.stride),
        }
    }
    let mut bytes: Vec<u8> = bytemuck::cast_slice(&words).to_vec();
    bytes.truncate(len);
    Ok(bytes)
}
