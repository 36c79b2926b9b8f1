//! Image bands: the image (and its AOVs) in bands of rows, each small enough
//! for one storage-buffer binding, so that an image larger than the device's
//! `maxStorageBufferRange` (128 MiB on lavapipe: 2896² pixels of 16 bytes)
//! still renders in one process. The tiles of the [`TilePlan`] are cut at
//! band boundaries ([`ImageBands::tiles`]), so a tile's dispatches bind one
//! band's buffers, and the stages write pixel `p` at `p - push.slot_base` of
//! the bound band.

use std::ops::Range;

use super::layout::Aov;
use super::tiles::TilePlan;
use super::RenderError;
use crate::vulkan::{Buffer, BufferUsage, Context};

/// Bytes of one image pixel (linear RGBA, `f32`).
pub const PIXEL_BYTES: u64 = 16;

/// The largest image one render holds: 1 GiB, 8192² pixels. The image is
/// on the device and read back whole (host memory as much again), so this
/// bounds what one process takes; larger images render as tiles of a split
/// render (`render --tile`), which `penumbra merge` streams into one file.
pub const MAX_IMAGE_BYTES: u64 = 1 << 30;

/// The rows of a render cut into bands that each fit one buffer binding.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ImageBands {
    /// Image width in pixels.
    pub width: u32,
    /// The bands' rows, in order, covering the render's rows once.
    pub rows: Vec<Range<u32>>,
    /// Rows of every band but the last (a multiple of 8).
    pub band_rows: u32,
    /// Whether each band also has an AOV buffer.
    pub aovs: bool,
}

impl ImageBands {
    /// Plans bands of `rows` (of an image `width` wide) whose image buffer,
    /// and AOV buffer when `aovs`, are each at most `max_buffer` bytes.
    /// Lowers the plan's tile height where a band holds fewer rows.
    pub fn plan(
        width: u32,
        rows: Range<u32>,
        aovs: bool,
        plan: &mut TilePlan,
        max_buffer: u64,
    ) -> Result<ImageBands, RenderError> {
        let per_pixel = match aovs {
            true => PIXEL_BYTES.max(std::mem::size_of::<Aov>() as u64),
            false => PIXEL_BYTES,
        };
        // Whole 8-row groups of the image's width per buffer.
        let fit = (max_buffer / (width as u64 * per_pixel)) / 8 * 8;
        if fit == 0 {
            return Err(RenderError::Scene {
                field: "camera.width".into(),
                message: format!(
                    "8 rows of {width} pixels need more than this device's maxStorageBufferRange of {:.1} MiB",
                    max_buffer as f64 / 1048576.0
                ),
            });
        }
        let fit = fit.min(u32::MAX as u64) as u32;
        plan.tile[1] = plan.tile[1].min(fit);
        let band_rows = fit;
        let bands = (rows.start..rows.end)
            .step_by(band_rows as usize)
            .map(|y| y..(y + band_rows).min(rows.end))
            .collect();
        Ok(ImageBands {
            width,
            rows: bands,
            band_rows,
            aovs,
        })
    }

    /// The band that holds row `y` of the render's rows.
    pub fn band_of(&self, y: u32) -> usize {
        ((y - self.rows[0].start) / self.band_rows) as usize
    }

    /// The plan's tiles over every band's rows, band by band: (origin, size)
    /// as [`TilePlan::tiles`] gives them.
    pub fn tiles(&self, plan: &TilePlan) -> Vec<([u32; 2], [u32; 2])> {
        self.rows
            .iter()
            .flat_map(|r| plan.tiles(self.width, r.clone()))
            .collect()
    }

    /// Each band's image buffer and, when asked for, AOV buffer. `whole`
    /// is the image of a render of one band that the caller keeps between
    /// renders; other bands get new buffers.
    pub(super) fn buffers(
        &self,
        ctx: &Context,
        mut whole: Option<Buffer>,
    ) -> Result<Vec<(Buffer, Option<Buffer>)>, RenderError> {
        self.rows
            .iter()
            .map(|r| {
                let pixels = self.width as u64 * (r.end - r.start) as u64;
                let image = match whole.take() {
                    Some(b) => b,
                    None => {
                        ctx.create_buffer("image band", BufferUsage::Storage, pixels * PIXEL_BYTES)?
                    }
                };
                let aovs = match self.aovs {
                    true => Some(ctx.create_buffer(
                        "AOVs",
                        BufferUsage::Storage,
                        pixels * std::mem::size_of::<Aov>() as u64,
                    )?),
                    false => None,
                };
                Ok((image, aovs))
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::tiles::DEFAULT_STAGE_MEMORY;

    #[test]
    fn bands_fit_one_binding_and_hold_whole_tiles() {
        let max = 128u64 << 20;
        for (size, aovs) in [
            ([640u32, 360u32], false),
            ([4096, 4096], false),
            ([4096, 4096], true),
            ([16384, 16384], false),
            ([16384, 9000], true),
            ([1000, 7], false),
        ] {
            let mut plan = TilePlan::new(size, 4, true, DEFAULT_STAGE_MEMORY, max);
            let bands = ImageBands::plan(size[0], 0..size[1], aovs, &mut plan, max).unwrap();
            let per_pixel = if aovs { 32 } else { 16 };
            let mut next = 0;
            for r in &bands.rows {
                assert_eq!(r.start, next, "{size:?}");
                next = r.end;
                assert!(size[0] as u64 * (r.end - r.start) as u64 * per_pixel <= max);
            }
            assert_eq!(next, size[1]);
            let tiles = bands.tiles(&plan);
            let covered: u64 = tiles.iter().map(|(_, s)| s[0] as u64 * s[1] as u64).sum();
            assert_eq!(covered, size[0] as u64 * size[1] as u64);
            for (origin, tile) in tiles {
                let band = &bands.rows[bands.band_of(origin[1])];
                assert!(band.start <= origin[1] && origin[1] + tile[1] <= band.end);
            }
        }
        // 640x360 is one band; 4096² of 16-byte pixels is two, with
        // 32-byte AOVs four.
        let one = |size: [u32; 2], aovs| {
            let mut plan = TilePlan::new(size, 1, true, DEFAULT_STAGE_MEMORY, max);
            ImageBands::plan(size[0], 0..size[1], aovs, &mut plan, max)
                .unwrap()
                .rows
                .len()
        };
        assert_eq!(one([640, 360], true), 1);
        assert_eq!(one([4096, 4096], false), 2);
        assert_eq!(one([4096, 4096], true), 4);
    }

    #[test]
    fn parts_band_their_own_rows() {
        let max = 128u64 << 20;
        let mut plan = TilePlan::new([4096, 1000], 1, true, DEFAULT_STAGE_MEMORY, max);
        let bands = ImageBands::plan(4096, 3000..4000, false, &mut plan, max).unwrap();
        assert_eq!(bands.rows, vec![3000..4000]);
        assert_eq!(bands.band_of(3999), 0);
    }
}
