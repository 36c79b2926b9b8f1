//! Writing images: PNG holds the linear colour clamped to [0, 1], sRGB-encoded,
//! 8 bits; OpenEXR holds linear float RGB. Files are written to a temporary
//! file beside the target and renamed into place, so a failed run never leaves
//! a partial file at the output path. This module owns that atomic write
//! ([`persist_with`], [`write_atomic`]) for every file penumbra produces: the
//! render outputs, the farm's parts, scripts and merges, and the watch loop's
//! previews, each with the [`Durability`] it needs.

use std::io::Write;
use std::path::Path;

use crate::frame::Image;

/// The image formats we write, chosen by the file extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// 8-bit sRGB PNG.
    Png,
    /// 32-bit float linear OpenEXR.
    Exr,
}

/// Why an image could not be written.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// The extension is neither .png nor .exr.
    #[error("{0}: unknown output format: expected a .png or .exr file name")]
    UnknownFormat(String),
    /// Creating, writing or renaming failed. (The cause is in the message,
    /// so it is not also a `source()`: `anyhow`'s `{:#}` would print it twice.)
    #[error("{path}: cannot write: {error}")]
    Io {
        /// The output path.
        path: String,
        /// The underlying error.
        error: std::io::Error,
    },
    /// Encoding failed.
    #[error("{path}: cannot encode: {error}")]
    Encode {
        /// The output path.
        path: String,
        /// The underlying error.
        error: image::ImageError,
    },
}

impl Format {
    /// The format for a path's extension.
    pub fn from_path(path: &Path) -> Result<Format, OutputError> {
        match path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .as_deref()
        {
            Some("png") => Ok(Format::Png),
            Some("exr") => Ok(Format::Exr),
            _ => Err(OutputError::UnknownFormat(path.display().to_string())),
        }
    }
}

/// The sRGB transfer function (IEC 61966-2-1) of a linear value in [0, 1].
pub fn srgb_encode(linear: f32) -> f32 {
    let c = linear.clamp(0.0, 1.0);
    if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

/// 8-bit sRGB code of a linear value (clamped to [0, 1]; NaN gives 0): the
/// code [`srgb_encode`] rounds to, found in a table instead of a `powf` per
/// channel ([`Srgb8Table`]), a fifth of the time to encode a PNG.
pub fn srgb8(linear: f32) -> u8 {
    static TABLE: std::sync::LazyLock<Srgb8Table> = std::sync::LazyLock::new(Srgb8Table::new);
    TABLE.code(linear)
}

/// [`srgb8`] by the formula: `srgb_encode(l) * 255 + 0.5`, truncated.
fn srgb8_formula(linear: f32) -> u8 {
    let l = if linear.is_nan() { 0.0 } else { linear };
    (srgb_encode(l) * 255.0 + 0.5) as u8
}

/// The linear values at which [`srgb8_formula`]'s code steps up, and a
/// coarse index into them by the top bits of the value.
///
/// For values in [0, 1] the bit patterns of `f32`s order like the values, so
/// the least value of each code is found by bisecting bit patterns; the code
/// of `l` is then the number of those steps at or below `l`. `bucket[i]` is
/// the code at the start of the `i`-th range of 2^18 bit patterns, and at
/// most two steps fall in one range (they are at least 0.0088 apart near 1,
/// where 2^18 patterns span 0.016), so a lookup is an index and a compare or
/// two. The tests check it against the formula.
struct Srgb8Table {
    /// `steps[k]`: the least value whose code is `k + 1`.
    steps: [f32; 255],
    /// The code of the least value of each range of 2^18 bit patterns.
    bucket: Vec<u8>,
}

/// Bits of a pattern below the bucket index.
const BUCKET_SHIFT: u32 = 18;

impl Srgb8Table {
    fn new() -> Srgb8Table {
        let one = 1.0f32.to_bits();
        let mut steps = [0.0f32; 255];
        for (k, step) in steps.iter_mut().enumerate() {
            // The least pattern in [0, 1] whose code exceeds k.
            let (mut lo, mut hi) = (0u32, one);
            while lo < hi {
                let mid = lo + (hi - lo) / 2;
                if srgb8_formula(f32::from_bits(mid)) as usize > k {
                    hi = mid;
                } else {
                    lo = mid + 1;
                }
            }
            *step = f32::from_bits(lo);
        }
        let bucket = (0..=(one >> BUCKET_SHIFT))
            .map(|i| {
                let first = f32::from_bits(i << BUCKET_SHIFT);
                steps.partition_point(|&s| s <= first) as u8
            })
            .collect();
        Srgb8Table { steps, bucket }
    }

    fn code(&self, linear: f32) -> u8 {
        // NaN, negative values and -0.0 give 0; 1 and above give 255.
        if linear.is_nan() || linear <= 0.0 {
            return 0;
        }
        if linear >= 1.0 {
            return 255;
        }
        let mut code = self.bucket[(linear.to_bits() >> BUCKET_SHIFT) as usize];
        while code < 255 && linear >= self.steps[code as usize] {
            code += 1;
        }
        code
    }
}

/// Encodes the image in memory.
pub fn encode(image: &Image, format: Format) -> Result<Vec<u8>, image::ImageError> {
    encode_with(image, format, png::Compression::Balanced)
}

/// [`encode`] with a PNG compression level of the caller's: `watch` writes its previews with
/// [`png::Compression::Fast`], which the next stage overwrites anyway.
pub fn encode_with(
    image: &Image,
    format: Format,
    compression: png::Compression,
) -> Result<Vec<u8>, image::ImageError> {
    let mut bytes = Vec::new();
    let cursor = &mut std::io::Cursor::new(&mut bytes);
    match format {
        Format::Png => {
            if image.pixels.len() != image.width as usize * image.height as usize {
                return Err(size_mismatch());
            }
            let w = image.width as usize;
            encode_png_rows_with(cursor, image.width, image.height, compression, |y, row| {
                let src = &image.pixels[y as usize * w..(y as usize + 1) * w];
                for (out, p) in row.chunks_exact_mut(3).zip(src) {
                    out.copy_from_slice(&[srgb8(p[0]), srgb8(p[1]), srgb8(p[2])]);
                }
                Ok(())
            })
            .map_err(|e| image::ImageError::IoError(std::io::Error::other(e.to_string())))?;
        }
        Format::Exr => {
            let rgb: Vec<f32> = image
                .pixels
                .iter()
                .flat_map(|p| [p[0], p[1], p[2]])
                .collect();
            image::Rgb32FImage::from_raw(image.width, image.height, rgb)
                .ok_or_else(size_mismatch)?
                .write_to(cursor, image::ImageFormat::OpenExr)?;
        }
    }
    Ok(bytes)
}

/// Writes an 8-bit sRGB PNG row by row: `row(y, buf)` fills row `y` (`3 *
/// width` bytes, RGB). Holding one row at a time is what lets `penumbra
/// merge` write an image of any size in bounded memory; `render` writes its
/// PNGs through the same encoder, so a merged image and an undivided render
/// are the same bytes.
pub fn encode_png_rows<W: Write>(
    out: W,
    width: u32,
    height: u32,
    row: impl FnMut(u32, &mut [u8]) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    encode_png_rows_with(out, width, height, png::Compression::Balanced, row)
}

/// [`encode_png_rows`] at another compression level.
fn encode_png_rows_with<W: Write>(
    out: W,
    width: u32,
    height: u32,
    compression: png::Compression,
    mut row: impl FnMut(u32, &mut [u8]) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    let mut encoder = png::Encoder::new(out, width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_compression(compression);
    encoder.set_filter(png::Filter::Adaptive);
    let mut writer = encoder.write_header()?;
    let mut stream = writer.stream_writer()?;
    let mut buf = vec![0u8; width as usize * 3];
    for y in 0..height {
        row(y, &mut buf)?;
        stream.write_all(&buf)?;
    }
    stream.finish()?;
    writer.finish()?;
    Ok(())
}

fn size_mismatch() -> image::ImageError {
    image::ImageError::Parameter(image::error::ParameterError::from_kind(
        image::error::ParameterErrorKind::DimensionMismatch,
    ))
}

/// Checks that `path` can be written (format known, directory exists and is
/// writable) before any rendering is done.
pub fn check_writable(path: &Path) -> Result<Format, OutputError> {
    let format = Format::from_path(path)?;
    let dir = parent_dir(path);
    // Say what is wrong in the user's terms rather than through the name of
    // the temporary file that could not be created.
    let plain = |msg: String| OutputError::Io {
        path: path.display().to_string(),
        error: std::io::Error::other(msg),
    };
    if path.is_dir() {
        return Err(plain("is a directory".into()));
    }
    if !dir.is_dir() {
        return Err(plain(format!("directory {} does not exist", dir.display())));
    }
    tempfile::NamedTempFile::new_in(dir).map_err(|error| OutputError::Io {
        path: path.display().to_string(),
        error,
    })?;
    Ok(format)
}

fn parent_dir(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// Encodes and writes the image atomically (temporary file, then rename),
/// synced to disk ([`Durability::Sync`]).
pub fn write_image(path: &Path, image: &Image) -> Result<(), OutputError> {
    let format = Format::from_path(path)?;
    let bytes = encode(image, format).map_err(|error| OutputError::Encode {
        path: path.display().to_string(),
        error,
    })?;
    write_atomic(path, &bytes, Durability::Sync)
}

/// What an atomic write promises beyond atomicity. Either way a reader of
/// `path` sees the old file or the complete new one, never a partial file,
/// and a failed write leaves nothing behind; the choice is only about a
/// crash of the machine (power loss, kernel panic) shortly after the write.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Durability {
    /// The temporary file is synced (`fsync`) before the rename, so that
    /// after a crash `path` holds the old file or the complete new one. For
    /// results that cost a render to remake: `penumbra render`'s output, the
    /// farm's parts, scripts and merged images.
    Sync,
    /// No sync: after a crash the file may be empty or stale. For the watch
    /// loop's previews, rewritten after every stage of every reload: the
    /// next save rewrites them anyway, and a sync (milliseconds, more on a
    /// busy disk) would add to every reload's save-to-image latency.
    NoSync,
}

/// Writes `bytes` to a temporary file beside `path` and renames it into
/// place, with the given [`Durability`]. The file gets the usual permissions
/// (0666 less the umask), not the private 0600 of a temporary file.
pub fn write_atomic(path: &Path, bytes: &[u8], durability: Durability) -> Result<(), OutputError> {
    persist_with_durability(path, durability, |f| {
        f.write_all(bytes).map_err(anyhow::Error::from)
    })
    .map_err(|e| match e.downcast::<OutputError>() {
        Ok(e) => e,
        Err(e) => OutputError::Io {
            path: path.display().to_string(),
            error: std::io::Error::other(format!("{e:#}")),
        },
    })
}

/// Atomic write of a file produced by `write` (which may stream it): a
/// temporary file beside `path`, synced and renamed into place only when
/// `write` succeeds; on any error nothing is left at `path` or beside it.
/// [`persist_with_durability`] with [`Durability::Sync`].
pub fn persist_with(
    path: &Path,
    write: impl FnOnce(&mut std::io::BufWriter<&std::fs::File>) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    persist_with_durability(path, Durability::Sync, write)
}

/// Atomic write of a file produced by `write`, with the given
/// [`Durability`]: the one implementation behind [`persist_with`],
/// [`write_atomic`] and every image penumbra writes.
pub fn persist_with_durability(
    path: &Path,
    durability: Durability,
    write: impl FnOnce(&mut std::io::BufWriter<&std::fs::File>) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    let io = |error| OutputError::Io {
        path: path.display().to_string(),
        error,
    };
    let mut builder = tempfile::Builder::new();
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(std::fs::Permissions::from_mode(0o666));
    }
    let tmp = builder.tempfile_in(parent_dir(path)).map_err(io)?;
    {
        let mut w = std::io::BufWriter::new(tmp.as_file());
        write(&mut w)?;
        w.flush().map_err(io)?;
    }
    // A test aid for the last-resort panic report (src/panics.rs): a panic
    // here, with the temporary file written but not renamed, must leave no
    // output behind.
    if std::env::var_os("PENUMBRA_TEST_INTERNAL_ERROR").is_some() {
        panic!("PENUMBRA_TEST_INTERNAL_ERROR is set");
    }
    if durability == Durability::Sync {
        tmp.as_file().sync_all().map_err(io)?;
    }
    tmp.persist(path).map_err(|e| io(e.error))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_matches_the_standard() {
        // Reference values of the IEC 61966-2-1 curve.
        assert_eq!(srgb8(0.0), 0);
        assert_eq!(srgb8(1.0), 255);
        assert_eq!(srgb8(2.0), 255);
        assert_eq!(srgb8(-1.0), 0);
        assert_eq!(srgb8(f32::NAN), 0);
        assert_eq!(srgb8(0.5), 188); // 0.7354 * 255
        assert_eq!(srgb8(0.18), 118); // 0.4614 * 255
        assert_eq!(srgb8(0.002), 7); // linear segment: 12.92 * 0.002 * 255 = 6.6
    }

    /// The table gives the formula's code: on a sweep of every 61st bit
    /// pattern of [0, 1] (17 million values), on the 4,096 patterns each side
    /// of every step, and on the special values.
    #[test]
    fn the_srgb_table_gives_the_formulas_codes() {
        let table = Srgb8Table::new();
        let check = |bits: u32| {
            let l = f32::from_bits(bits);
            assert_eq!(table.code(l), srgb8_formula(l), "{l:e} (bits {bits:#x})");
        };
        let one = 1.0f32.to_bits();
        (0..=one).step_by(61).for_each(check);
        for s in table.steps {
            let b = s.to_bits();
            (b.saturating_sub(4096)..=(b + 4096).min(one)).for_each(check);
        }
        for l in [-0.0, -1e-30, f32::MIN_POSITIVE, 1.0, 1.5, f32::INFINITY] {
            check(f32::to_bits(l));
        }
        assert_eq!(table.code(f32::NAN), srgb8_formula(f32::NAN));
        assert_eq!(
            table.code(f32::NEG_INFINITY),
            srgb8_formula(f32::NEG_INFINITY)
        );
        // Every code is reached, in order.
        assert!(table.steps.windows(2).all(|w| w[0] < w[1]));
    }
}

/// Which arbitrary output variables to write (`--aov depth,normal,uv,id`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AovSet {
    /// Channel `Z`: distance along the primary ray (+inf on misses).
    pub depth: bool,
    /// Channels `N.X`, `N.Y`, `N.Z`: unit geometric normal facing the viewer.
    pub normal: bool,
    /// Channels `uv.U`, `uv.V`: barycentric coordinates of triangle hits.
    pub uv: bool,
    /// Channels `id.object`, `id.primitive` (32-bit unsigned; 4294967295 on
    /// misses).
    pub id: bool,
}

impl std::str::FromStr for AovSet {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let mut set = AovSet::default();
        for name in s.split(',').map(str::trim) {
            match name {
                "depth" => set.depth = true,
                "normal" => set.normal = true,
                "uv" => set.uv = true,
                "id" => set.id = true,
                _ => {
                    return Err(format!(
                        "unknown AOV `{name}`: expected depth, normal, uv or id"
                    ))
                }
            }
        }
        Ok(set)
    }
}

/// Writes linear RGB plus the chosen AOV channels into one OpenEXR file,
/// atomically.
pub fn write_exr_with_aovs(
    path: &Path,
    image: &Image,
    aovs: &crate::frame::Aovs,
    set: AovSet,
) -> Result<(), OutputError> {
    use exr::prelude::*;
    let name = path.display().to_string();
    if Format::from_path(path)? != Format::Exr {
        return Err(OutputError::UnknownFormat(format!(
            "{name} (AOVs need an .exr output)"
        )));
    }
    let size = (image.width as usize, image.height as usize);
    let f32s = |name: &str, v: Vec<f32>| AnyChannel::new(name, FlatSamples::F32(v));
    let mut channels: Vec<AnyChannel<FlatSamples>> = (0..3)
        .map(|c| {
            f32s(
                ["R", "G", "B"][c],
                image.pixels.iter().map(|p| p[c]).collect(),
            )
        })
        .collect();
    if set.depth {
        channels.push(f32s("Z", aovs.depth.clone()));
    }
    if set.normal {
        for (c, n) in ["N.X", "N.Y", "N.Z"].iter().enumerate() {
            channels.push(f32s(n, aovs.normal.iter().map(|v| v[c]).collect()));
        }
    }
    if set.uv {
        for (c, n) in ["uv.U", "uv.V"].iter().enumerate() {
            channels.push(f32s(n, aovs.uv.iter().map(|v| v[c]).collect()));
        }
    }
    if set.id {
        channels.push(AnyChannel::new(
            "id.object",
            FlatSamples::U32(aovs.object.clone()),
        ));
        channels.push(AnyChannel::new(
            "id.primitive",
            FlatSamples::U32(aovs.primitive.clone()),
        ));
    }
    let layer = Layer::new(
        size,
        LayerAttributes::named("penumbra"),
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(channels.into()),
    );
    let mut bytes = Vec::new();
    exr::image::Image::from_layer(layer)
        .write()
        .to_buffered(std::io::Cursor::new(&mut bytes))
        .map_err(|e| OutputError::Io {
            path: name.clone(),
            error: std::io::Error::other(e.to_string()),
        })?;
    write_atomic(path, &bytes, Durability::Sync)
}
