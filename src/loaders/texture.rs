//! Texture images: PNG or JPEG bytes (a file, a glTF bufferView or a
//! `data:` URI) decoded with the `image` crate into a [`Texture`].
//!
//! Decoding is bounded before it allocates: the header's size is checked
//! against [`MAX_TEXTURE_SIDE`] and the scene's memory budget ([`Guard`]),
//! so a small file that claims a huge image fails with a message instead of
//! exhausting memory.

use std::io::Cursor;

use super::guard::{Guard, Refused};
use crate::scene::Texture;

/// The largest texture side penumbra decodes (and the smallest
/// `maxImageDimension2D` Vulkan requires is 4096; devices are checked
/// again when the scene is uploaded).
pub const MAX_TEXTURE_SIDE: u32 = 16384;

/// Decodes `bytes` (PNG or JPEG; `mime` is the file's declared type, if
/// any, and must agree with the bytes) into an RGBA8 texture called `label`.
/// `srgb` marks a colour texture. The texels are charged to `guard`'s
/// memory budget.
pub fn decode(
    bytes: &[u8],
    mime: Option<&str>,
    label: &str,
    srgb: bool,
    guard: &Guard,
) -> Result<Texture, Refused> {
    let reader = image::ImageReader::new(Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| Refused(format!("cannot read the image: {e}")))?;
    let format = match reader.format() {
        Some(f @ (image::ImageFormat::Png | image::ImageFormat::Jpeg)) => f,
        Some(other) => {
            return Err(Refused(format!(
                "is a {other:?} image; textures must be PNG or JPEG"
            )))
        }
        None => {
            return Err(Refused(
                "is not a PNG or JPEG image (unknown format)".into(),
            ))
        }
    };
    if let Some(m) = mime {
        let declared = match m {
            "image/png" => Some(image::ImageFormat::Png),
            "image/jpeg" => Some(image::ImageFormat::Jpeg),
            _ => None,
        };
        if declared != Some(format) {
            return Err(Refused(format!(
                "declares mimeType {m:?} but holds a {format:?} image"
            )));
        }
    }
    let (width, height) = reader
        .into_dimensions()
        .map_err(|e| Refused(format!("is a corrupt {format:?} image: {e}")))?;
    if width == 0 || height == 0 {
        return Err(Refused(format!("is an empty image ({width}×{height})")));
    }
    if width > MAX_TEXTURE_SIDE || height > MAX_TEXTURE_SIDE {
        return Err(Refused(format!(
            "is {width}×{height} texels, larger than the {MAX_TEXTURE_SIDE} texels a side penumbra takes"
        )));
    }
    // RGBA8 and the mip chain (at most 4/3 more).
    let bytes_needed = u64::from(width) * u64::from(height) * 4 * 4 / 3;
    guard.charge_bytes(bytes_needed)?;
    let mut reader = image::ImageReader::with_format(Cursor::new(bytes), format);
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(MAX_TEXTURE_SIDE);
    limits.max_image_height = Some(MAX_TEXTURE_SIDE);
    limits.max_alloc = Some(bytes_needed.saturating_mul(4).max(1 << 20));
    reader.limits(limits);
    let image = reader
        .decode()
        .map_err(|e| Refused(format!("is a corrupt {format:?} image: {e}")))?;
    let rgba = image.to_rgba8();
    let texels = rgba.pixels().map(|p| p.0).collect();
    Ok(Texture {
        label: label.to_string(),
        file: None,
        width,
        height,
        texels,
        srgb,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::loaders::LoadOptions;

    fn png(w: u32, h: u32) -> Vec<u8> {
        let img = image::RgbaImage::from_fn(w, h, |x, y| image::Rgba([x as u8, y as u8, 7, 255]));
        let mut out = Vec::new();
        img.write_to(&mut Cursor::new(&mut out), image::ImageFormat::Png)
            .unwrap();
        out
    }

    #[test]
    fn decodes_png_rows_from_the_top() {
        let g = Guard::new("s.json".as_ref(), &LoadOptions::default());
        let t = decode(&png(3, 2), Some("image/png"), "t.png", true, &g).unwrap();
        assert_eq!((t.width, t.height), (3, 2));
        assert_eq!(t.texels[0], [0, 0, 7, 255]);
        assert_eq!(t.texels[5], [2, 1, 7, 255]);
    }

    #[test]
    fn refuses_bad_bytes_and_wrong_types() {
        let g = Guard::new("s.json".as_ref(), &LoadOptions::default());
        let e = decode(b"not an image", None, "x", true, &g).unwrap_err();
        assert!(e.0.contains("not a PNG or JPEG"), "{}", e.0);
        let e = decode(&png(2, 2), Some("image/jpeg"), "x", true, &g).unwrap_err();
        assert!(e.0.contains("mimeType"), "{}", e.0);
        let mut cut = png(64, 64);
        cut.truncate(cut.len() / 2);
        let e = decode(&cut, None, "x", true, &g).unwrap_err();
        assert!(e.0.contains("corrupt"), "{}", e.0);
    }
}
