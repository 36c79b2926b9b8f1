//! Error metrics between two renders of the same size, for `penumbra diff`.
//!
//! Images are [`Image`]s (linear RGBA `f32`, row 0 at the top). Files are read
//! by extension: `.exr` as linear float (as [`crate::output`] writes it), `.png`
//! as sRGB-encoded (8 or 16 bit) and decoded to linear with the IEC 61966-2-1
//! curve. Alpha is ignored by every metric.
//!
//! The metrics (over the R, G, B channels of every pixel):
//!
//! * `max_abs_error`: `max |a − b|`;
//! * `mean_abs_error`: the mean of `|a − b|` over pixels and channels;
//! * `rmse`: `sqrt(mean (a − b)²)`, same mean;
//! * `off_by_more_than_1_of_255`: the fraction of pixels where some channel's
//!   8-bit sRGB code ([`crate::output::srgb8`], i.e. what a PNG would store)
//!   differs by more than 1;
//! * `flip_mean`, `flip_max`: NVIDIA's FLIP (Andersson et al., "FLIP: A
//!   Difference Evaluator for Alternating Images", Proc. ACM Comput. Graph.
//!   Interact. Tech. 3(2), 2020), through the `nv-flip` crate (the binding of
//!   the reference C++ implementation that wgpu's image tests use). The crate
//!   exposes LDR-FLIP only, which compares sRGB images: both images go in as
//!   their 8-bit sRGB encodings, so values above 1 are clipped as in a PNG. The
//!   viewing condition is FLIP's default of 67 pixels per degree (a 0.7 m
//!   viewing distance from a 24-inch 4K monitor). `flip_mean` is the number
//!   FLIP's authors recommend reporting; per-pixel values lie in [0, 1].
//!
//! Not computed: the relative depth error, which needs the depth AOV the
//! renderer does not write yet.
//!
//! NaN in either image makes the error metrics NaN (they are never silently
//! skipped); the 8-bit and FLIP metrics see NaN as 0, as the PNG encoder does.

use std::path::Path;

use crate::frame::Image;
use crate::output::srgb8;

/// Why two images could not be compared.
#[derive(Debug, thiserror::Error)]
pub enum MetricsError {
    /// The extension is neither .png nor .exr.
    #[error("{0}: unknown image format: expected a .png or .exr file")]
    UnknownFormat(String),
    /// Opening or reading the file failed.
    #[error("{path}: cannot read: {error}")]
    Io {
        /// The file.
        path: String,
        /// The underlying error.
        error: std::io::Error,
    },
    /// The file is not a valid image of its format.
    #[error("{path}: cannot decode: {error}")]
    Decode {
        /// The file.
        path: String,
        /// The underlying error.
        error: image::ImageError,
    },
    /// The images differ in size.
    #[error("{b}: is {b_width}x{b_height} but {a} is {a_width}x{a_height}: the images must be the same size")]
    SizeMismatch {
        /// The first image's name.
        a: String,
        /// Its width.
        a_width: u32,
        /// Its height.
        a_height: u32,
        /// The second image's name.
        b: String,
        /// Its width.
        b_width: u32,
        /// Its height.
        b_height: u32,
    },
}

/// The IEC 61966-2-1 decoding of an sRGB-encoded value in [0, 1] to linear.
pub fn srgb_decode(encoded: f32) -> f32 {
    let c = encoded.clamp(0.0, 1.0);
    if c <= 0.040_45 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// Reads a `.png` (sRGB, decoded to linear) or `.exr` (linear) file.
pub fn read_image(path: &Path) -> Result<Image, MetricsError> {
    let name = path.display().to_string();
    let format = match path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .as_deref()
    {
        Some("png") => image::ImageFormat::Png,
        Some("exr") => image::ImageFormat::OpenExr,
        _ => return Err(MetricsError::UnknownFormat(name)),
    };
    let mut reader = image::ImageReader::open(path).map_err(|error| MetricsError::Io {
        path: name.clone(),
        error,
    })?;
    reader.set_format(format);
    let decoded = reader.decode().map_err(|error| match error {
        image::ImageError::IoError(error) => MetricsError::Io {
            path: name.clone(),
            error,
        },
        error => MetricsError::Decode {
            path: name.clone(),
            error,
        },
    })?;
    let (width, height) = (decoded.width(), decoded.height());
    let pixels: Vec<[f32; 4]> = if format == image::ImageFormat::OpenExr {
        decoded.into_rgba32f().pixels().map(|p| p.0).collect()
    } else if decoded.color().bytes_per_pixel() / decoded.color().channel_count() > 1 {
        // 16-bit PNG: the same curve on the 16-bit code.
        decoded
            .into_rgba16()
            .pixels()
            .map(|p| {
                let c = |v: u16| srgb_decode(v as f32 / 65535.0);
                [c(p[0]), c(p[1]), c(p[2]), p[3] as f32 / 65535.0]
            })
            .collect()
    } else {
        let lut: Vec<f32> = (0..=255u8).map(|v| srgb_decode(v as f32 / 255.0)).collect();
        decoded
            .into_rgba8()
            .pixels()
            .map(|p| {
                let c = |v: u8| lut[v as usize];
                [c(p[0]), c(p[1]), c(p[2]), p[3] as f32 / 255.0]
            })
            .collect()
    };
    Ok(Image {
        width,
        height,
        pixels,
    })
}

/// The metrics between two images (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Metrics {
    /// Width, pixels.
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
    /// `max |a − b|` over pixels and RGB channels.
    pub max_abs_error: f64,
    /// Mean of `|a − b|` over pixels and RGB channels.
    pub mean_abs_error: f64,
    /// Root mean square of `a − b` over pixels and RGB channels.
    pub rmse: f64,
    /// Pixels where some channel's 8-bit sRGB code differs by more than 1.
    pub pixels_off_by_more_than_1: u64,
    /// That count divided by the number of pixels (0 for an empty image).
    pub off_by_more_than_1_of_255: f64,
    /// Mean of the FLIP error map.
    pub flip_mean: f64,
    /// Maximum of the FLIP error map.
    pub flip_max: f64,
}

impl Metrics {
    /// One `name: value` line per metric.
    pub fn lines(&self) -> Vec<String> {
        vec![
            format!("size: {}x{}", self.width, self.height),
            format!("max_abs_error: {}", self.max_abs_error),
            format!("mean_abs_error: {}", self.mean_abs_error),
            format!("rmse: {}", self.rmse),
            format!(
                "pixels_off_by_more_than_1_of_255: {}",
                self.pixels_off_by_more_than_1
            ),
            format!(
                "off_by_more_than_1_of_255: {}",
                self.off_by_more_than_1_of_255
            ),
            format!("flip_mean: {}", self.flip_mean),
            format!("flip_max: {}", self.flip_max),
        ]
    }
}

fn check_sizes(a: &Image, a_name: &str, b: &Image, b_name: &str) -> Result<(), MetricsError> {
    if (a.width, a.height) != (b.width, b.height) {
        return Err(MetricsError::SizeMismatch {
            a: a_name.to_string(),
            a_width: a.width,
            a_height: a.height,
            b: b_name.to_string(),
            b_width: b.width,
            b_height: b.height,
        });
    }
    Ok(())
}

/// The pixel-wise metrics (everything but FLIP, which [`compare`] adds).
pub fn pixel_metrics(a: &Image, b: &Image) -> Result<Metrics, MetricsError> {
    check_sizes(a, "first image", b, "second image")?;
    let mut max = 0.0f64;
    let mut sum = 0.0f64;
    let mut sum2 = 0.0f64;
    let mut off = 0u64;
    for (p, q) in a.pixels.iter().zip(&b.pixels) {
        let mut pixel_off = false;
        for c in 0..3 {
            let d = (p[c] as f64 - q[c] as f64).abs();
            // `f64::max` would drop a NaN: keep it.
            max = if d.is_nan() || max.is_nan() {
                f64::NAN
            } else {
                max.max(d)
            };
            sum += d;
            sum2 += d * d;
            pixel_off |= srgb8(p[c]).abs_diff(srgb8(q[c])) > 1;
        }
        off += pixel_off as u64;
    }
    let pixels = a.pixels.len() as f64;
    let samples = 3.0 * pixels;
    let mean = |s: f64| if samples > 0.0 { s / samples } else { 0.0 };
    Ok(Metrics {
        width: a.width,
        height: a.height,
        max_abs_error: max,
        mean_abs_error: mean(sum),
        rmse: mean(sum2).sqrt(),
        pixels_off_by_more_than_1: off,
        off_by_more_than_1_of_255: if pixels > 0.0 {
            off as f64 / pixels
        } else {
            0.0
        },
        flip_mean: 0.0,
        flip_max: 0.0,
    })
}

fn to_flip(image: &Image) -> nv_flip::FlipImageRgb8 {
    let rgb: Vec<u8> = image
        .pixels
        .iter()
        .flat_map(|p| [srgb8(p[0]), srgb8(p[1]), srgb8(p[2])])
        .collect();
    nv_flip::FlipImageRgb8::with_data(image.width, image.height, &rgb)
}

/// The FLIP error map of `test` against `reference` (row-major, one value in
/// [0, 1] per pixel), from their 8-bit sRGB encodings.
pub fn flip_map(reference: &Image, test: &Image) -> Result<Vec<f32>, MetricsError> {
    check_sizes(reference, "reference", test, "test")?;
    if reference.pixels.is_empty() {
        return Ok(Vec::new());
    }
    let map = nv_flip::flip(
        to_flip(reference),
        to_flip(test),
        nv_flip::DEFAULT_PIXELS_PER_DEGREE,
    );
    Ok(map.to_vec())
}

/// All the metrics of `test` against `reference`.
pub fn compare(reference: &Image, test: &Image) -> Result<Metrics, MetricsError> {
    Ok(compare_with_map(reference, test)?.0)
}

/// The metrics and the FLIP error map.
fn compare_with_map(reference: &Image, test: &Image) -> Result<(Metrics, Vec<f32>), MetricsError> {
    let mut m = pixel_metrics(reference, test)?;
    let map = flip_map(reference, test)?;
    if !map.is_empty() {
        m.flip_mean = map.iter().map(|&v| v as f64).sum::<f64>() / map.len() as f64;
        m.flip_max = map.iter().fold(0.0f64, |a, &v| a.max(v as f64));
    }
    Ok((m, map))
}

/// The FLIP error map in FLIP's magma colour map, as a linear image (its
/// sRGB encoding, as [`crate::output::write_image`] writes a PNG, gives back
/// exactly the map's 8-bit colours).
pub fn flip_false_colour(width: u32, height: u32, map: &[f32]) -> Image {
    let values = nv_flip::FlipImageFloat::with_data(width, height, map);
    let rgb = values.apply_color_lut(&nv_flip::magma_lut()).to_vec();
    let lut: Vec<f32> = (0..=255u8).map(|v| srgb_decode(v as f32 / 255.0)).collect();
    let pixels = rgb
        .chunks_exact(3)
        .map(|c| {
            [
                lut[c[0] as usize],
                lut[c[1] as usize],
                lut[c[2] as usize],
                1.0,
            ]
        })
        .collect();
    Image {
        width,
        height,
        pixels,
    }
}

/// Reads both files, compares them, and (with `output`) writes the FLIP map
/// in false colour there, atomically. Errors name the file.
pub fn diff_files(a: &Path, b: &Path, output: Option<&Path>) -> anyhow::Result<Metrics> {
    // Refuse an unwritable output before reading anything.
    if let Some(out) = output {
        crate::output::check_writable(out)?;
    }
    let ia = read_image(a)?;
    let ib = read_image(b)?;
    check_sizes(&ia, &a.display().to_string(), &ib, &b.display().to_string())?;
    let (m, map) = compare_with_map(&ia, &ib)?;
    if let Some(out) = output {
        crate::output::write_image(out, &flip_false_colour(ia.width, ia.height, &map))?;
    }
    Ok(m)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_decode_inverts_the_8_bit_encoding() {
        for v in 0..=255u8 {
            assert_eq!(srgb8(srgb_decode(v as f32 / 255.0)), v, "code {v}");
        }
    }
}

/// Relative error of one depth AOV against another: over pixels where both
/// hit something (finite depth), `|a − b| / a`; and the pixels where exactly
/// one of them hit.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DepthError {
    /// Largest relative error.
    pub max_relative: f64,
    /// Mean relative error.
    pub mean_relative: f64,
    /// Pixels where one depth is finite (a hit) and the other is not.
    pub hit_mismatches: u64,
}

/// Compares two depth AOVs (reference first); `None` if their lengths differ.
pub fn depth_error(reference: &[f32], test: &[f32]) -> Option<DepthError> {
    if reference.len() != test.len() {
        return None;
    }
    let mut e = DepthError::default();
    let mut n = 0u64;
    for (&a, &b) in reference.iter().zip(test) {
        match (a.is_finite(), b.is_finite()) {
            (true, true) => {
                let rel = ((a as f64 - b as f64) / a as f64).abs();
                e.max_relative = e.max_relative.max(rel);
                e.mean_relative += rel;
                n += 1;
            }
            (false, false) => {}
            _ => e.hit_mismatches += 1,
        }
    }
    if n > 0 {
        e.mean_relative /= n as f64;
    }
    Some(e)
}

/// The `Z` (depth) channel of an OpenEXR file, if it has one.
pub fn read_depth(path: &Path) -> Option<Vec<f32>> {
    let image = exr::prelude::read_all_flat_layers_from_file(path).ok()?;
    let layer = image.layer_data.first()?;
    let z = layer
        .channel_data
        .list
        .iter()
        .find(|c| c.name.to_string() == "Z")?;
    match &z.sample_data {
        exr::prelude::FlatSamples::F32(v) => Some(v.clone()),
        exr::prelude::FlatSamples::F16(v) => Some(v.iter().map(|h| h.to_f32()).collect()),
        exr::prelude::FlatSamples::U32(_) => None,
    }
}
