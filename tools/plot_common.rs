//! What the plotting tools share: a font for plotters' text (loaded at run
//! time, so no system font lookup is compiled in) and PNG output of a
//! plotters RGB buffer through the `image` crate.

use plotters::style::FontStyle;

/// Registers DejaVu Sans as plotters' "sans-serif".
pub fn register_font() -> anyhow::Result<()> {
    let path = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";
    let font = std::fs::read(path).map_err(|e| {
        anyhow::anyhow!("{path}: the plots need it (apt-get install fonts-dejavu-core): {e}")
    })?;
    plotters::style::register_font(
        "sans-serif",
        FontStyle::Normal,
        Box::leak(font.into_boxed_slice()),
    )
    .map_err(|_| anyhow::anyhow!("{path}: not a usable font"))
}

/// Saves a plotters RGB buffer of `width`×`height` pixels as a PNG.
pub fn save_png(pixels: Vec<u8>, width: u32, height: u32, path: &str) -> anyhow::Result<()> {
    image::RgbImage::from_raw(width, height, pixels)
        .ok_or_else(|| anyhow::anyhow!("plot buffer size"))?
        .save(path)?;
    Ok(())
}
