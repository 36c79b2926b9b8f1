//! The texture target: image headers through the texture loader
//! (`penumbra::loaders::texture::decode`) under a small memory budget.
//!
//! Seeds are small PNGs of every colour type and bit depth the `image`
//! crate writes, JPEGs (grey and colour) and an OpenEXR image (which the
//! loader must refuse as a format). Mutations rewrite the header fields a
//! texture bomb plays with: the PNG IHDR's width, height, bit depth and
//! colour type (its CRC recomputed so that the decoder reads on), a JPEG
//! frame header's (SOFn) size, precision and component count, an OpenEXR
//! image's windows.

use std::io::Cursor;

use image::{DynamicImage, ImageFormat};
use penumbra::loaders::guard::Guard;
use penumbra::loaders::LoadOptions;

use super::mutate::{self, Rng};

/// The seeds: `(name, bytes)`.
pub fn seeds() -> Vec<(String, Vec<u8>)> {
    let rgb = image::RgbImage::from_fn(24, 16, |x, y| image::Rgb([x as u8 * 10, y as u8 * 15, 90]));
    let colour = DynamicImage::ImageRgb8(rgb);
    let images = [
        ("grey8.png", colour.to_luma8().into(), ImageFormat::Png),
        (
            "grey_alpha8.png",
            colour.to_luma_alpha8().into(),
            ImageFormat::Png,
        ),
        ("rgb8.png", colour.clone(), ImageFormat::Png),
        ("rgba16.png", colour.to_rgba16().into(), ImageFormat::Png),
        ("grey16.png", colour.to_luma16().into(), ImageFormat::Png),
        ("rgb.jpg", colour.clone(), ImageFormat::Jpeg),
        ("grey.jpg", colour.to_luma8().into(), ImageFormat::Jpeg),
        (
            "rgb32f.exr",
            colour.to_rgb32f().into(),
            ImageFormat::OpenExr,
        ),
    ];
    images
        .into_iter()
        .filter_map(|(name, img, format): (&str, DynamicImage, _)| {
            let mut data = Vec::new();
            img.write_to(&mut Cursor::new(&mut data), format).ok()?;
            Some((name.to_string(), data))
        })
        .collect()
}

/// A mutated copy of a texture seed: its header rewritten on most cases,
/// byte-level mutations on a quarter.
pub fn mutate(seed: &[u8], donors: &[Vec<u8>], rng: &mut Rng) -> Vec<u8> {
    let mut data = seed.to_vec();
    if !rng.one_in(4) {
        if data.starts_with(b"\x89PNG") {
            mutate_png_header(&mut data, rng);
        } else if data.starts_with(&[0xFF, 0xD8]) {
            mutate_jpeg_header(&mut data, rng);
        } else {
            mutate::mutate_exr_windows(&mut data, rng);
        }
    }
    if rng.one_in(4) {
        mutate::mutate_bytes(&mut data, donors, rng);
    }
    data
}

/// Sides at the edges the loader checks: empty, tiny, the bombs' sizes,
/// [`penumbra::loaders::texture::MAX_TEXTURE_SIDE`] and one past it, and
/// the largest the formats hold.
const SIDES: [u32; 10] = [0, 1, 2, 9000, 16384, 16385, 46341, 65535, 1 << 31, u32::MAX];

/// Rewrites the PNG IHDR (at bytes 16..29): size, bit depth and colour
/// type, any of them, and its CRC so that the decoder accepts the chunk.
fn mutate_png_header(data: &mut [u8], rng: &mut Rng) {
    let Some(ihdr) = data.get_mut(8..33) else {
        return;
    };
    if rng.one_in(2) {
        ihdr[8..12].copy_from_slice(&rng.pick(&SIDES).to_be_bytes());
    }
    if rng.one_in(2) {
        ihdr[12..16].copy_from_slice(&rng.pick(&SIDES).to_be_bytes());
    }
    if rng.one_in(2) {
        ihdr[16] = *rng.pick(&[1, 2, 4, 8, 16, 3, 0]);
    }
    if rng.one_in(2) {
        ihdr[17] = *rng.pick(&[0, 2, 3, 4, 6, 1, 7]);
    }
    let crc = crc32fast::hash(&ihdr[4..21]);
    ihdr[21..25].copy_from_slice(&crc.to_be_bytes());
}

/// Rewrites the first JPEG frame header (SOF0..SOF15, not DHT/JPG/DAC):
/// height, width, sample precision and component count, any of them.
fn mutate_jpeg_header(data: &mut [u8], rng: &mut Rng) {
    let mut i = 2;
    while i + 9 < data.len() && data[i] == 0xFF {
        let marker = data[i + 1];
        if (0xC0..=0xCF).contains(&marker) && ![0xC4, 0xC8, 0xCC].contains(&marker) {
            let sides: [u16; 6] = [0, 1, 9000, 16384, 16385, 65535];
            if rng.one_in(2) {
                data[i + 5..i + 7].copy_from_slice(&rng.pick(&sides).to_be_bytes());
            }
            if rng.one_in(2) {
                data[i + 7..i + 9].copy_from_slice(&rng.pick(&sides).to_be_bytes());
            }
            if rng.one_in(4) {
                data[i + 4] = *rng.pick(&[8, 12, 16, 0]);
            }
            if rng.one_in(4) {
                data[i + 9] = *rng.pick(&[1, 2, 3, 4, 255]);
            }
            return;
        }
        i += 2 + usize::from(u16::from_be_bytes([data[i + 2], data[i + 3]]));
    }
}

/// Decodes `data` as a texture under a memory budget of `budget` bytes and
/// lavapipe's 1 GiB texture image: `Err` is the loader's refusal.
pub fn run(data: &[u8], budget: u64) -> Result<(), String> {
    let opts = LoadOptions {
        max_scene_bytes: budget,
        max_texture_bytes: 1 << 30,
        ..Default::default()
    };
    let guard = Guard::new("case.json".as_ref(), &opts);
    penumbra::loaders::texture::decode(data, None, "case", true, &guard)
        .map(|_| ())
        .map_err(|e| e.0)
}
