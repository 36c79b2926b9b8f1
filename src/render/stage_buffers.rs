//! The stage buffers of a tile plan (hit records, queued light samples,
//! resolved materials, colour sums), kept between renders so that a shading
//! edit can reuse the hits they hold.

use super::tiles::{self, TilePlan};
use super::{RenderError, Renderer, StageKernel};
use crate::vulkan::{Buffer, BufferUsage, TexelImage};

/// Which hit records (and light-sample visibility) the stage buffers hold:
/// everything a shading edit leaves unchanged.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct HitKey {
    pub(super) upload: u64,
    pub(super) traversal: u64,
    pub(super) size: [u32; 2],
    pub(super) rows: std::ops::Range<u32>,
    pub(super) pass_index: u32,
    pub(super) seed: u32,
    pub(super) kernel: StageKernel,
}

/// The stage buffers of one tile plan, and whose hits they hold.
pub(super) struct StageBuffers {
    pub(super) plan: TilePlan,
    pub(super) hits: TexelImage,
    pub(super) queue: TexelImage,
    pub(super) resolved: TexelImage,
    pub(super) radiance: Buffer,
    /// The image of the last whole render with these buffers (made when
    /// one needs it): a reused frame skips the hit stage, which writes the
    /// pixels that hit nothing, so they must still hold that render's.
    pub(super) image: Option<Buffer>,
    pub(super) holds: Option<HitKey>,
}

/// Stage buffers kept for hit reuse: the preview's and the full image's.
pub(super) const KEPT_STAGE_BUFFERS: usize = 2;

impl Renderer {
    /// The index of kept stage buffers for `plan`, allocating them (and
    /// dropping the least recently used) when none fit.
    pub(super) fn stage_buffers_for(&mut self, plan: TilePlan) -> Result<usize, RenderError> {
        if let Some(i) = self.stage_buffers.iter().position(|b| b.plan == plan) {
            // Most recently used last.
            let b = self.stage_buffers.remove(i);
            self.stage_buffers.push(b);
            return Ok(self.stage_buffers.len() - 1);
        }
        if self.stage_buffers.len() >= KEPT_STAGE_BUFFERS {
            self.stage_buffers.remove(0);
        }
        let ctx = &self.context;
        let px = plan.pixels();
        let entries = px * plan.chunk as u64;
        let words = self.stage_words();
        let image = |label: &str, texels: u64| match words {
            true => ctx.create_stage_image_with_words(label, texels),
            false => ctx.create_stage_image(label, texels),
        };
        self.stage_buffers.push(StageBuffers {
            plan,
            hits: image("hit records", px * tiles::RECORD_TEXELS)?,
            queue: image("queued samples", entries * tiles::QUEUE_TEXELS)?,
            // Without checkers nothing reads or writes them; the binding
            // still needs an image.
            resolved: image("resolved materials", if plan.resolved { px } else { 1 })?,
            radiance: ctx.create_buffer(
                "colour sums",
                BufferUsage::Storage,
                px * plan.radiance_bytes(),
            )?,
            image: None,
            holds: None,
        });
        Ok(self.stage_buffers.len() - 1)
    }
}
