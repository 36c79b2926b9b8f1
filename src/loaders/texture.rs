//! Texture images: PNG or JPEG bytes (a file, a glTF bufferView or a
//! `data:` URI) decoded with the `image` crate into a [`Texture`], or a
//! glTF file's KTX2/Basis Universal image ([`super::ktx2`]).
//!
//! Decoding is bounded before it allocates: the decoder reads the header
//! alone first, and its size is checked against [`MAX_TEXTURE_SIDE`], the
//! device's texture image and the scene's memory budget ([`Guard`]) before
//! a texel is decoded, so a small file that claims a huge image (a
//! "texture bomb") is refused from its header with a message instead of
//! exhausting memory. What is charged is what the load and the upload
//! really allocate ([`texture_bytes`]), and the decoded image becomes the
//! texture's RGBA8 texels in place when it is RGBA8 already, so that no two
//! full-size copies are held at once otherwise.

use std::io::Cursor;

use image::{ImageDecoder, ImageFormat};

use super::guard::{Guard, Refused};
use crate::scene::Texture;

/// The largest texture side penumbra decodes (and the smallest
/// `maxImageDimension2D` Vulkan requires is 4096; devices are checked
/// again when the scene is uploaded).
pub const MAX_TEXTURE_SIDE: u32 = 16384;

/// Bytes the decoder itself may allocate beyond its output (row buffers,
/// JPEG component planes are within the output's size).
const DECODER_SLACK: u64 = 16 << 20;

/// Decodes `bytes` (PNG or JPEG; `mime` is the file's declared type, if
/// any, and must agree with the bytes) into an RGBA8 texture called `label`.
/// `srgb` marks a colour texture. The header is read and checked first
/// ([`Guard::charge_texture`]): an image that cannot fit the device or the
/// memory budget is refused before it is decoded.
pub fn decode(
    bytes: &[u8],
    mime: Option<&str>,
    label: &str,
    srgb: bool,
    guard: &Guard,
) -> Result<Texture, Refused> {
    prepare(bytes.to_vec(), mime, label, srgb, guard)?.decode()
}

/// An image whose header [`prepare`] has checked and whose memory it has
/// charged: [`Pending::decode`] decodes it, on any thread (issue 39: the
/// glTF loader decodes its images in parallel).
#[derive(Debug)]
pub struct Pending {
    bytes: Vec<u8>,
    /// `None` for a KTX2 image.
    format: Option<ImageFormat>,
    label: String,
    srgb: bool,
    /// The decoder's output, bytes, from the header.
    decoded: u64,
    /// What decoding holds for a while beyond what it keeps
    /// ([`texture_bytes`]).
    pub transient: u64,
}

/// [`decode`]'s checks, everything before the decode itself: the format,
/// the header's size against the limits and the memory budget (charged
/// here), and whether the bytes can hold that many texels.
pub fn prepare(
    bytes: Vec<u8>,
    mime: Option<&str>,
    label: &str,
    srgb: bool,
    guard: &Guard,
) -> Result<Pending, Refused> {
    if super::ktx2::is_ktx2(&bytes) || mime == Some(super::ktx2::MIME) {
        return prepare_ktx2(bytes, mime, label, srgb, guard);
    }
    let format = format_of(&bytes, mime)?;
    let corrupt = |e: image::ImageError| Refused(format!("is a corrupt {format:?} image: {e}"));
    let mut reader = image::ImageReader::with_format(Cursor::new(&bytes[..]), format);
    // Reading the header may allocate little; its size is checked here,
    // with the size in the message, before the decode's limits are set.
    let mut header = image::Limits::default();
    header.max_alloc = Some(DECODER_SLACK);
    reader.limits(header);
    let decoder = reader.into_decoder().map_err(corrupt)?;
    let (width, height) = decoder.dimensions();
    check_size(width, height)?;
    let decoded = decoder.total_bytes();
    let (transient, kept) = texture_bytes(width, height, decoded);
    guard.charge_texture(width, height, transient, kept)?;
    check_holds(format, width, height, bytes.len())?;
    drop(decoder);
    Ok(Pending {
        bytes,
        format: Some(format),
        label: label.to_string(),
        srgb,
        decoded,
        transient,
    })
}

/// Refuses an empty image, or one larger than [`MAX_TEXTURE_SIDE`], from
/// the size its header gives.
fn check_size(width: u32, height: u32) -> Result<(), Refused> {
    if width == 0 || height == 0 {
        return Err(Refused(format!("is an empty image ({width}×{height})")));
    }
    if width > MAX_TEXTURE_SIDE || height > MAX_TEXTURE_SIDE {
        return Err(Refused(format!(
            "is {width}×{height} texels by its header, larger than the {MAX_TEXTURE_SIDE} texels a side penumbra takes (refused before decoding)"
        )));
    }
    Ok(())
}

/// [`prepare`] for a KTX2 image: its header's size is checked and charged
/// as a PNG's would be; the transcoder's output is the RGBA8 texels.
fn prepare_ktx2(
    bytes: Vec<u8>,
    mime: Option<&str>,
    label: &str,
    srgb: bool,
    guard: &Guard,
) -> Result<Pending, Refused> {
    use super::ktx2;
    if !ktx2::is_ktx2(&bytes) {
        return Err(Refused(format!(
            "declares mimeType {:?} but is not a KTX2 file",
            ktx2::MIME
        )));
    }
    if let Some(m) = mime.filter(|&m| m != ktx2::MIME) {
        return Err(Refused(format!(
            "declares mimeType {m:?} but holds a KTX2 image"
        )));
    }
    let (width, height) = ktx2::dimensions(&bytes)?;
    check_size(width, height)?;
    // The transcoder's output is the RGBA8 image, then copied into texels.
    let decoded = u64::from(width) * u64::from(height) * 4;
    let (_, kept) = texture_bytes(width, height, decoded);
    guard.charge_texture(width, height, decoded, kept)?;
    Ok(Pending {
        bytes,
        format: None,
        label: label.to_string(),
        srgb,
        decoded,
        transient: decoded,
    })
}

impl Pending {
    /// Decodes the image, within the limits its header set.
    pub fn decode(self) -> Result<Texture, Refused> {
        let Some(format) = self.format else {
            let (width, height) = super::ktx2::dimensions(&self.bytes)?;
            return Ok(Texture {
                texels: super::ktx2::decode(&self.bytes, width, height)?,
                label: self.label,
                file: None,
                width,
                height,
                srgb: self.srgb,
            });
        };
        let corrupt = |e: image::ImageError| Refused(format!("is a corrupt {format:?} image: {e}"));
        let mut reader = image::ImageReader::with_format(Cursor::new(&self.bytes[..]), format);
        let mut header = image::Limits::default();
        header.max_alloc = Some(DECODER_SLACK);
        reader.limits(header);
        let mut decoder = reader.into_decoder().map_err(corrupt)?;
        let (width, height) = decoder.dimensions();
        decoder
            .set_limits(limits(self.decoded.saturating_add(DECODER_SLACK)))
            .map_err(corrupt)?;
        let image = image::DynamicImage::from_decoder(decoder).map_err(corrupt)?;
        Ok(Texture {
            label: self.label,
            file: None,
            width,
            height,
            texels: rgba_texels(image),
            srgb: self.srgb,
        })
    }
}

fn format_of(bytes: &[u8], mime: Option<&str>) -> Result<ImageFormat, Refused> {
    let format = match image::guess_format(bytes) {
        Ok(f @ (ImageFormat::Png | ImageFormat::Jpeg)) => f,
        Ok(other) => {
            return Err(Refused(format!(
                "is a {other:?} image; textures must be PNG or JPEG"
            )))
        }
        Err(_) => {
            return Err(Refused(
                "is not a PNG or JPEG image (unknown format)".into(),
            ))
        }
    };
    if let Some(m) = mime {
        let declared = match m {
            "image/png" => Some(ImageFormat::Png),
            "image/jpeg" => Some(ImageFormat::Jpeg),
            _ => None,
        };
        if declared != Some(format) {
            return Err(Refused(format!(
                "declares mimeType {m:?} but holds a {format:?} image"
            )));
        }
    }
    Ok(format)
}

/// The most a zlib stream (PNG's image data) expands: 258 bytes from a
/// match of two one-bit codes.
const DEFLATE_MAX_RATIO: u64 = 1032;

/// Refuses a `width` × `height` image whose file of `len` bytes is too
/// small to hold it whatever its content, before it is decoded: a PNG's
/// rows hold at least one bit a texel and a filter byte a row, which
/// zlib shrinks at most [`DEFLATE_MAX_RATIO`] times; a JPEG codes at
/// least one bit per 8×8 block of its largest component (the DC
/// difference, in every scan that holds it). A small file that claims a
/// large image is truncated, and decoders fill what is missing, so it
/// would otherwise be decoded, uploaded and rendered at full size.
fn check_holds(format: ImageFormat, width: u32, height: u32, len: usize) -> Result<(), Refused> {
    let (w, h) = (u64::from(width), u64::from(height));
    let (least, why) = match format {
        ImageFormat::Png => (
            h * (1 + w.div_ceil(8)) / DEFLATE_MAX_RATIO,
            "a PNG holds at least a bit a texel, compressed at most 1032 times",
        ),
        _ => (
            w.div_ceil(8) * h.div_ceil(8) / 8,
            "a JPEG codes at least a bit per 8×8 block",
        ),
    };
    if (len as u64) < least {
        return Err(Refused(format!(
            "is {width}×{height} texels by its header, but its {len} bytes cannot hold them ({why}: {least} bytes at least); refused before decoding"
        )));
    }
    Ok(())
}

/// Decoder limits: [`MAX_TEXTURE_SIDE`] a side and `max_alloc` bytes.
fn limits(max_alloc: u64) -> image::Limits {
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(MAX_TEXTURE_SIDE);
    limits.max_image_height = Some(MAX_TEXTURE_SIDE);
    limits.max_alloc = Some(max_alloc);
    limits
}

/// Copies of a texture's device-format mip chain ([`Texture::device_bytes`])
/// that an upload holds at once: the packed words
/// (`render::layout::textures`) and the texel image itself, which on a CPU
/// device such as lavapipe is host memory too (the staging buffer between
/// them holds one band of at most 64 MiB, `vulkan::MAX_KEPT_STAGING`).
pub const UPLOAD_COPIES: u64 = 2;

/// The bytes that loading and uploading a `width` × `height` texture
/// allocate, given the decoder's output of `decoded` bytes, as `(transient,
/// kept)`: the decoder's output is freed once it is converted to RGBA8
/// (it is the RGBA8 buffer itself when the image is RGBA8 already), while
/// the RGBA8 texels and the upload's [`UPLOAD_COPIES`] of the linear RGBA16
/// mip chain are all held when the scene is uploaded. For a 9000×9000
/// 1-bit PNG that is 81 MB + 324 MB + 2 × 864 MB = 2.13 GB at its peak;
/// such a render peaks at 2.16 GB on lavapipe (peak RSS, the whole
/// process).
pub fn texture_bytes(width: u32, height: u32, decoded: u64) -> (u64, u64) {
    let rgba8 = u64::from(width) * u64::from(height) * 4;
    let transient = if decoded == rgba8 { 0 } else { decoded };
    let upload = Texture::device_bytes_of(width, height).saturating_mul(UPLOAD_COPIES);
    (transient, rgba8.saturating_add(upload))
}

/// The image's texels as RGBA8, reusing its buffer when it is RGBA8. An
/// RGB8 image (most PNG textures) is widened here, in parallel rows,
/// rather than by `into_rgba8`'s general colour conversion, which took
/// about 4 % of a FlightHelmet render (issue 39); the texels are the same
/// (the test `rgb8_widens_as_into_rgba8`).
fn rgba_texels(image: image::DynamicImage) -> Vec<[u8; 4]> {
    if let image::DynamicImage::ImageRgb8(rgb) = &image {
        use rayon::prelude::*;
        return rgb
            .as_raw()
            .par_chunks_exact(3)
            .map(|c| [c[0], c[1], c[2], 255])
            .collect();
    }
    let raw = image.into_rgba8().into_raw();
    // `[u8; 4]` has the alignment of `u8` and the length is a multiple of
    // four, so the buffer is reused as it is.
    bytemuck::allocation::try_cast_vec(raw).unwrap_or_else(|(_, raw)| {
        raw.chunks_exact(4)
            .map(|c| [c[0], c[1], c[2], c[3]])
            .collect()
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
    fn converts_grey_and_rgba_to_rgba8() {
        let g = Guard::new("s.json".as_ref(), &LoadOptions::default());
        let grey = image::GrayImage::from_fn(3, 2, |x, y| image::Luma([(10 * x + y) as u8]));
        let mut png = Vec::new();
        grey.write_to(&mut Cursor::new(&mut png), image::ImageFormat::Png)
            .unwrap();
        let t = decode(&png, None, "g.png", false, &g).unwrap();
        assert_eq!(t.texels, [0, 10, 20, 1, 11, 21].map(|v| [v, v, v, 255]));
        // The decode passes; the RGBA8 texels and the upload's copies of
        // the RGBA16 chain stay charged.
        let device = Texture::device_bytes_of(3, 2);
        assert_eq!(texture_bytes(3, 2, 6), (6, 24 + UPLOAD_COPIES * device));
        assert_eq!(g.bytes(), 24 + UPLOAD_COPIES * device);
        // RGBA8 already: decoded into the texels' own buffer, charged once.
        assert_eq!(texture_bytes(3, 2, 24), (0, 24 + UPLOAD_COPIES * device));
    }

    #[test]
    fn rgb8_widens_as_into_rgba8() {
        let mut seed = 0x1234_5678u32;
        let rgb = image::RgbImage::from_fn(37, 29, |_, _| {
            seed ^= seed << 13;
            seed ^= seed >> 17;
            seed ^= seed << 5;
            let b = seed.to_le_bytes();
            image::Rgb([b[0], b[1], b[2]])
        });
        let image = image::DynamicImage::ImageRgb8(rgb);
        let plain: Vec<[u8; 4]> = image
            .to_rgba8()
            .into_raw()
            .chunks_exact(4)
            .map(|c| [c[0], c[1], c[2], c[3]])
            .collect();
        assert_eq!(rgba_texels(image), plain);
    }

    #[test]
    fn a_bomb_is_refused_from_its_header() {
        // A 9000×9000 grey PNG header on no image data: the size alone is
        // refused, so the missing rows are never read.
        let header = image::GrayImage::new(1, 1);
        let mut png = Vec::new();
        header
            .write_to(&mut Cursor::new(&mut png), image::ImageFormat::Png)
            .unwrap();
        png[16..24].copy_from_slice(&[0, 0, 0x23, 0x28, 0, 0, 0x23, 0x28]);
        let crc = crc32fast::hash(&png[12..29]);
        png[29..33].copy_from_slice(&crc.to_be_bytes());
        let opts = LoadOptions {
            max_scene_bytes: 1 << 30,
            ..Default::default()
        };
        let g = Guard::new("s.json".as_ref(), &opts);
        let e = decode(&png, None, "bomb.png", true, &g).unwrap_err();
        assert!(e.0.contains("is 9000×9000 texels by its header"), "{}", e.0);
        assert!(e.0.contains("refused before decoding"), "{}", e.0);
        // The device's texture image refuses it too, whatever the budget.
        let opts = LoadOptions {
            max_texture_bytes: 512 << 20,
            ..Default::default()
        };
        let g = Guard::new("s.json".as_ref(), &opts);
        let e = decode(&png, None, "bomb.png", true, &g).unwrap_err();
        assert!(e.0.contains("this device's texture image holds"), "{}", e.0);
        // With room for it, its few bytes cannot hold 9000×9000 texels.
        let g = Guard::new("s.json".as_ref(), &LoadOptions::default());
        let e = decode(&png, None, "bomb.png", true, &g).unwrap_err();
        assert!(e.0.contains("bytes cannot hold them"), "{}", e.0);
        assert!(e.0.contains("9819 bytes at least"), "{}", e.0);
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
