//! Part files: one OpenEXR file per part of a split render. The data window
//! is the tile's rows, the display window the full image, the channels
//! `R`, `G`, `B` hold the *sum* of the part's passes in `f32` (a tile over
//! all passes divides by the pass count only at the merge, exactly as the
//! undivided render does), and text attributes say which render and which
//! part it is:
//!
//! | attribute | value |
//! |---|---|
//! | `penumbra.render` | [`super::identity::render_id`], 64 hex digits |
//! | `penumbra.scene` | the scene file's name (for messages only) |
//! | `penumbra.tile` | `I/N` |
//! | `penumbra.passes` | `A..B` |
//! | `penumbra.spp` | passes of the whole render |

use std::ops::Range;
use std::path::Path;

use exr::prelude::*;
use std::result::Result;

use super::split::{Passes, Tile};
use crate::frame::Image;

/// What a part file says about itself (its header; no pixels).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PartInfo {
    /// The render's identity ([`super::identity::render_id`]).
    pub render: String,
    /// The scene file's name, for messages.
    pub scene: String,
    /// Which band of rows.
    pub tile: Tile,
    /// Which passes.
    pub passes: Passes,
    /// Passes of the whole render.
    pub spp: u32,
    /// Full image width.
    pub width: u32,
    /// Full image height.
    pub height: u32,
    /// The rows the file holds (its data window).
    pub rows: Range<u32>,
}

impl PartInfo {
    /// The part `tile` × `passes` of the render `render` (its identity) of
    /// `scene` under `settings`: its rows follow from the tile and the image
    /// height. An error when the image has too few rows for the tiles.
    pub fn new(
        render: String,
        scene: &Path,
        tile: Tile,
        passes: Passes,
        settings: &super::identity::RenderSettings,
    ) -> Result<PartInfo, String> {
        Ok(PartInfo {
            render,
            scene: scene
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default(),
            tile,
            passes,
            spp: settings.spp,
            width: settings.width,
            height: settings.height,
            rows: tile.rows(settings.height)?,
        })
    }
}

const RENDER: &str = "penumbra.render";
const SCENE: &str = "penumbra.scene";
const TILE: &str = "penumbra.tile";
const PASSES: &str = "penumbra.passes";
const SPP: &str = "penumbra.spp";

fn text(s: &str) -> AttributeValue {
    AttributeValue::Text(Text::new_or_panic(s))
}

/// Writes a part atomically: `image` holds the part's rows (`info.rows`) of
/// pass sums, as [`crate::render::Renderer::render`] returns them for a
/// [`crate::render::RenderRequest::part`].
pub fn write(path: &Path, info: &PartInfo, image: &Image) -> anyhow::Result<()> {
    let rows = info.rows.end - info.rows.start;
    anyhow::ensure!(
        image.width == info.width && image.height == rows,
        "{}: internal error: part image is {}x{}, expected {}x{rows}",
        path.display(),
        image.width,
        image.height,
        info.width
    );
    let mut attrs = LayerAttributes::named("penumbra");
    attrs.layer_position = Vec2(0, info.rows.start as i32);
    // Scene names are the user's: keep them to the bytes EXR text allows.
    let scene: String = info
        .scene
        .chars()
        .filter(|c| c.is_ascii() && !c.is_ascii_control())
        .collect();
    for (k, v) in [
        (RENDER, info.render.clone()),
        (SCENE, scene),
        (TILE, info.tile.to_string()),
        (PASSES, info.passes.to_string()),
        (SPP, info.spp.to_string()),
    ] {
        attrs.other.insert(Text::new_or_panic(k), text(&v));
    }
    let w = image.width as usize;
    let layer = Layer::new(
        (w, rows as usize),
        attrs,
        Encoding::FAST_LOSSLESS,
        SpecificChannels::rgb(|p: Vec2<usize>| {
            let px = image.pixels[p.y() * w + p.x()];
            (px[0], px[1], px[2])
        }),
    );
    let display = IntegerBounds::from_dimensions((info.width as usize, info.height as usize));
    let exr_image = exr::image::Image::new(ImageAttributes::new(display), layer);
    // The exr crate writes to a seekable stream: encode in memory (a part
    // is one tile), then write the bytes atomically.
    let mut bytes = Vec::new();
    exr_image
        .write()
        .to_buffered(std::io::Cursor::new(&mut bytes))
        .map_err(|e| anyhow::anyhow!("{}: cannot encode: {e}", path.display()))?;
    crate::output::persist_with(path, |out| {
        use std::io::Write;
        out.write_all(&bytes)?;
        Ok(())
    })
}

/// Why a part file cannot be used; the message names the file.
#[derive(Debug, thiserror::Error)]
#[error("{path}: {message}")]
pub struct PartError {
    /// The part file.
    pub path: String,
    /// What is wrong with it.
    pub message: String,
}

fn part_error(path: &Path, message: impl Into<String>) -> PartError {
    PartError {
        path: path.display().to_string(),
        message: message.into(),
    }
}

/// Reads a part's header: the attributes and windows, checked against each
/// other (a file that is not a penumbra part, or whose windows disagree with
/// its tile, is an error naming the field).
pub fn read_info(path: &Path) -> Result<PartInfo, PartError> {
    if !path.is_file() {
        return Err(part_error(path, "not a regular file"));
    }
    let meta = exr::meta::MetaData::read_from_file(path, false)
        .map_err(|e| part_error(path, format!("not a readable OpenEXR part file: {e}")))?;
    let [header] = meta.headers.as_slice() else {
        return Err(part_error(
            path,
            "expected one layer (a penumbra part file)",
        ));
    };
    let attr = |key: &str| -> Result<String, PartError> {
        match header.own_attributes.other.get(&Text::new_or_panic(key)) {
            Some(AttributeValue::Text(t)) => Ok(t.to_string()),
            _ => Err(part_error(
                path,
                format!("{key}: missing: not a part file of `penumbra render --tile/--passes`"),
            )),
        }
    };
    let field = |key: &str, e: String| part_error(path, format!("{key}: {e}"));
    let render = attr(RENDER)?;
    if render.len() != 64 || !render.bytes().all(|b| b.is_ascii_hexdigit()) {
        return Err(field(
            RENDER,
            format!("expected 64 hex digits, got `{render}`"),
        ));
    }
    let tile: Tile = attr(TILE)?.parse().map_err(|e| field(TILE, e))?;
    let passes: Passes = attr(PASSES)?.parse().map_err(|e| field(PASSES, e))?;
    let spp: u32 = attr(SPP)?
        .parse()
        .map_err(|_| field(SPP, "expected a number of passes".into()))?;
    if passes.end > spp {
        return Err(field(
            PASSES,
            format!("{passes} is not within the render's {spp} passes"),
        ));
    }
    let display = header.shared_attributes.display_window;
    if display.position != Vec2(0, 0) || display.size.0 == 0 || display.size.1 == 0 {
        return Err(field(
            "displayWindow",
            "expected a full image at (0, 0)".into(),
        ));
    }
    // A render is at most MAX_IMAGE_SIDE a side: a header claiming more is
    // not from penumbra, and reading its pixels would allocate for them.
    let side = crate::scene::MAX_IMAGE_SIDE as usize;
    if display.size.0 > side || display.size.1 > side {
        return Err(field(
            "displayWindow",
            format!(
                "{}x{} is larger than a render can be ({side} pixels a side)",
                display.size.0, display.size.1
            ),
        ));
    }
    let (width, height) = (display.size.0 as u32, display.size.1 as u32);
    let rows = tile.rows(height).map_err(|e| field(TILE, e))?;
    let pos = header.own_attributes.layer_position;
    let size = header.layer_size;
    if pos != Vec2(0, rows.start as i32)
        || size != Vec2(width as usize, (rows.end - rows.start) as usize)
    {
        return Err(field(
            "dataWindow",
            format!(
                "{}x{} at ({}, {}) is not tile {tile}'s rows {}..{} of {width}x{height}",
                size.0, size.1, pos.0, pos.1, rows.start, rows.end
            ),
        ));
    }
    Ok(PartInfo {
        render,
        scene: attr(SCENE).unwrap_or_default(),
        tile,
        passes,
        spp,
        width,
        height,
        rows,
    })
}

/// Reads a part's pixels: `width * rows` RGB triples of pass sums, row-major.
/// A truncated or corrupt file is an error naming it.
pub fn read_pixels(path: &Path, info: &PartInfo) -> Result<Vec<[f32; 3]>, PartError> {
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .rgb_channels(
            |size: Vec2<usize>, _: &RgbChannels| (size.0, vec![[0f32; 3]; size.0 * size.1]),
            |(w, px): &mut (usize, Vec<[f32; 3]>), p: Vec2<usize>, (r, g, b): (f32, f32, f32)| {
                px[p.y() * *w + p.x()] = [r, g, b];
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .map_err(|e| part_error(path, format!("truncated or corrupt pixels: {e}")))?;
    let (w, pixels) = image.layer_data.channel_data.pixels;
    let rows = (info.rows.end - info.rows.start) as usize;
    if w != info.width as usize || pixels.len() != w * rows {
        return Err(part_error(
            path,
            "pixels do not match the header's data window",
        ));
    }
    Ok(pixels)
}
