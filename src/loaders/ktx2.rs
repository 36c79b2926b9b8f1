//! KTX2 texture images holding Basis Universal data (glTF's
//! KHR_texture_basisu): the container's header is read by the `ktx2`
//! crate, and the base level is transcoded to RGBA8 by the `basisu` crate
//! (a pure-Rust port of the reference transcoder; docs/gltf.md says what
//! else was tried). Mip-maps are built from the base level as for PNG and
//! JPEG images, so the file's own levels are not used.
//!
//! From the extension's specification (Khronos glTF extension registry,
//! `KHR_texture_basisu/README.md`): the image is a KTX v2 file whose
//! `vkFormat` is `VK_FORMAT_UNDEFINED` and whose data is ETC1S
//! (supercompressed with BasisLZ) or UASTC (optionally with Zstandard), a
//! single 2D image (one layer, one face, no depth), with the image's
//! `mimeType` `image/ktx2`.

use basisu::{DecodeFlags, TargetFormat, Transcoder};
use ktx2::SupercompressionScheme;

use super::guard::Refused;

/// The twelve bytes every KTX v2 file starts with (KTX 2.0 specification,
/// section 3.1, "identifier").
const IDENTIFIER: [u8; 12] = [
    0xAB, b'K', b'T', b'X', b' ', b'2', b'0', 0xBB, b'\r', b'\n', 0x1A, b'\n',
];

/// The media type glTF gives KTX v2 images.
pub const MIME: &str = "image/ktx2";

/// Whether `bytes` is a KTX v2 file.
pub fn is_ktx2(bytes: &[u8]) -> bool {
    bytes.starts_with(&IDENTIFIER)
}

/// The base level's size from the header, after checking that the file is
/// a single 2D Basis Universal image.
pub fn dimensions(bytes: &[u8]) -> Result<(u32, u32), Refused> {
    let reader =
        ktx2::Reader::new(bytes).map_err(|e| Refused(format!("is a corrupt KTX2 image: {e}")))?;
    let h = reader.header();
    if h.format.is_some() {
        return Err(Refused(format!(
            "is a KTX2 image of format {:?}; KHR_texture_basisu requires Basis Universal data (vkFormat 0)",
            h.format
        )));
    }
    match h.supercompression_scheme {
        None | Some(SupercompressionScheme::BasisLZ | SupercompressionScheme::Zstandard) => {}
        Some(other) => {
            return Err(Refused(format!(
                "is a KTX2 image supercompressed with {other:?}, which Basis Universal does not use"
            )))
        }
    }
    if h.pixel_depth > 1 || h.layer_count > 1 || h.face_count != 1 {
        return Err(Refused(format!(
            "is a KTX2 image of {} layers, {} faces and depth {}; a texture is one 2D image",
            h.layer_count, h.face_count, h.pixel_depth
        )));
    }
    Ok((h.pixel_width, h.pixel_height))
}

/// The base level as `width` × `height` RGBA8 texels, rows from the top.
pub fn decode(bytes: &[u8], width: u32, height: u32) -> Result<Vec<[u8; 4]>, Refused> {
    let corrupt =
        |e: basisu::Error| Refused(format!("is a corrupt KTX2/Basis Universal image ({e:?})"));
    let transcoder = Transcoder::new(bytes).map_err(corrupt)?;
    let rgba = transcoder
        .transcode(0, TargetFormat::Rgba32, DecodeFlags::NONE)
        .map_err(corrupt)?;
    let expected = width as usize * height as usize * 4;
    if rgba.len() != expected {
        return Err(Refused(format!(
            "is {width}×{height} texels by its KTX2 header, but its Basis Universal data decodes to {} bytes",
            rgba.len()
        )));
    }
    Ok(rgba
        .chunks_exact(4)
        .map(|c| [c[0], c[1], c[2], c[3]])
        .collect())
}
