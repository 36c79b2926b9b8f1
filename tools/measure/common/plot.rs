//! What the plotting tools share: a font for plotters' text and PNG output
//! of a plotters RGB buffer through the `image` crate. plotters' `ab_glyph`
//! backend takes a TrueType font registered at run time (no system font
//! lookup compiled in): DejaVu Sans from Debian's fonts-dejavu-core, another
//! common sans-serif file, or the file named by `PENUMBRA_BENCH_FONT`.

use std::path::Path;

use anyhow::Context as _;
use plotters::style::FontStyle;

/// Where the font is looked for, in this order, after `PENUMBRA_BENCH_FONT`.
const FONT_PATHS: &[&str] = &[
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
    "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf",
];

/// Registers the first font found as plotters' "sans-serif".
pub fn register_font() -> anyhow::Result<()> {
    let from_env = std::env::var("PENUMBRA_BENCH_FONT").ok();
    let path = from_env
        .iter()
        .map(String::as_str)
        .chain(FONT_PATHS.iter().copied())
        .find(|p| Path::new(p).is_file())
        .context(
            "the plot needs a TrueType font: install fonts-dejavu-core or set PENUMBRA_BENCH_FONT",
        )?;
    let bytes: &'static [u8] = Vec::leak(std::fs::read(path)?);
    plotters::style::register_font("sans-serif", FontStyle::Normal, bytes)
        .map_err(|_| anyhow::anyhow!("{path} is not a usable TrueType font"))?;
    Ok(())
}

/// Saves a plotters RGB buffer of `width`×`height` pixels as a PNG.
pub fn save_png(pixels: Vec<u8>, width: u32, height: u32, path: &str) -> anyhow::Result<()> {
    image::RgbImage::from_raw(width, height, pixels)
        .ok_or_else(|| anyhow::anyhow!("plot buffer size"))?
        .save(path)?;
    Ok(())
}

/// A plotters error as an `anyhow` error (plotters' errors are generic over
/// the backend and not `Send`).
pub fn err<E: std::fmt::Debug>(e: E) -> anyhow::Error {
    anyhow::anyhow!("plot: {e:?}")
}
