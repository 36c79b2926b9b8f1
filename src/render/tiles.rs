//! Tiles: the stages pass hit records and queued light samples through
//! buffers sized for one tile of the image, so that an image of any size,
//! with any number of light samples, renders within a fixed memory bound.
//!
//! A tile is a rectangle of whole 8×8 workgroups. Its stage memory is
//! `pixels × (hit record + samples per chunk × queue entry)`; when a pixel
//! has more light samples than a chunk holds, the shadow and shade stages
//! run once per chunk of samples, and each pixel's colour sums over the
//! chunks in a colour sum of its own (one chunk writes the image directly).

/// Texels of one hit record (`RECORD_TEXELS` in
/// `shaders/stages/records.wgsl`).
pub const RECORD_TEXELS: u64 = 4;
/// Texels of one queued light sample (`QUEUE_TEXELS`).
pub const QUEUE_TEXELS: u64 = 1;
/// Bytes of one pixel's hit record.
pub const RECORD_BYTES: u64 = RECORD_TEXELS * 16;
/// Bytes of one pixel's resolved material (only when the scene has
/// checkers: without them the shade stage reads a hit's shader from the
/// shader table).
pub const RESOLVED_BYTES: u64 = 16;
/// Bytes of one pixel's colour sum (only when there is more than one chunk).
pub const RADIANCE_BYTES: u64 = 16;
/// Bytes of one queued light sample: direction and falloff.
pub const QUEUE_ENTRY_BYTES: u64 = QUEUE_TEXELS * 16;
/// Most light samples per pixel one chunk holds.
pub const MAX_CHUNK: u32 = 64;
/// The default bound on a tile's stage memory: 128 MiB.
pub const DEFAULT_STAGE_MEMORY: u64 = 128 << 20;
/// The smallest bound a renderer accepts: one 8×8 tile with a full chunk
/// and resolved materials.
pub const MIN_STAGE_MEMORY: u64 =
    64 * (RECORD_BYTES + RESOLVED_BYTES + RADIANCE_BYTES + MAX_CHUNK as u64 * QUEUE_ENTRY_BYTES);

/// Whether one chunk holds all of a pixel's `samples` light samples (then
/// the hit stage traces the shadow rays: `render::Settings::fused_shadows`).
pub fn one_chunk(samples: u32) -> bool {
    samples <= MAX_CHUNK
}

/// How a render's image is cut into tiles and its light samples into chunks.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TilePlan {
    /// Tile width and height in pixels (multiples of 8).
    pub tile: [u32; 2],
    /// Light samples per pixel and pass, over all lights.
    pub samples: u32,
    /// Samples per chunk (the queue holds this many per pixel; at least 1).
    pub chunk: u32,
    /// Whether each pixel has a resolved material (the scene has checkers).
    pub resolved: bool,
}

impl TilePlan {
    /// Plans tiles for an image region of `size` pixels with `samples`
    /// light samples per pixel, with a resolved material per pixel where
    /// `resolved` (the scene has checkers), within `bound` bytes of stage
    /// memory and buffers of at most `max_buffer` bytes each.
    pub fn new(
        size: [u32; 2],
        samples: u32,
        resolved: bool,
        bound: u64,
        max_buffer: u64,
    ) -> TilePlan {
        let chunk = samples.clamp(1, MAX_CHUNK);
        let per_pixel = per_pixel(samples, chunk, resolved);
        let largest = RECORD_BYTES.max(chunk as u64 * QUEUE_ENTRY_BYTES);
        let pixels = (bound.max(MIN_STAGE_MEMORY) / per_pixel)
            .min(max_buffer / largest)
            .max(64);
        let align = |v: u64| (v.div_ceil(8) * 8) as u32;
        let down = |v: u64| ((v / 8).max(1) * 8) as u32;
        let width = align(size[0] as u64).min(down(pixels / 8));
        let height = align(size[1] as u64).min(down(pixels / width as u64));
        TilePlan {
            tile: [width, height],
            samples,
            chunk,
            resolved,
        }
    }

    /// Pixels of one tile.
    pub fn pixels(&self) -> u64 {
        self.tile[0] as u64 * self.tile[1] as u64
    }

    /// Bytes of stage memory the plan's buffers take.
    pub fn bytes(&self) -> u64 {
        self.pixels() * per_pixel(self.samples, self.chunk, self.resolved)
    }

    /// Bytes of one tile pixel's colour sum: 0 when one chunk holds all
    /// samples (the shade stage then writes the image directly).
    pub fn radiance_bytes(&self) -> u64 {
        radiance_bytes(self.samples, self.chunk)
    }

    /// The sample chunks: (first sample, samples in the chunk); one empty
    /// chunk when there are no light samples (the shade stage still runs).
    pub fn chunks(&self) -> Vec<(u32, u32)> {
        if self.samples == 0 {
            return vec![(0, 0)];
        }
        (0..self.samples)
            .step_by(self.chunk as usize)
            .map(|first| (first, self.chunk.min(self.samples - first)))
            .collect()
    }

    /// The tiles covering columns `0..width` and rows `rows`: (origin, size)
    /// of each, in row-major order; edge tiles are smaller.
    pub fn tiles(&self, width: u32, rows: std::ops::Range<u32>) -> Vec<([u32; 2], [u32; 2])> {
        let mut out = Vec::new();
        for y in (rows.start..rows.end).step_by(self.tile[1] as usize) {
            for x in (0..width).step_by(self.tile[0] as usize) {
                let w = self.tile[0].min(width - x);
                let h = self.tile[1].min(rows.end - y);
                out.push(([x, y], [w, h]));
            }
        }
        out
    }
}

/// Stage memory of one pixel for `samples` light samples in chunks of
/// `chunk`, with a resolved material where `resolved`.
fn per_pixel(samples: u32, chunk: u32, resolved: bool) -> u64 {
    RECORD_BYTES
        + if resolved { RESOLVED_BYTES } else { 0 }
        + radiance_bytes(samples, chunk)
        + chunk as u64 * QUEUE_ENTRY_BYTES
}

/// A pixel's colour sum: only when its samples take more than one chunk.
fn radiance_bytes(samples: u32, chunk: u32) -> u64 {
    match samples > chunk {
        true => RADIANCE_BYTES,
        false => 0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn small_images_are_one_tile_and_the_bound_holds() {
        let p = TilePlan::new([640, 360], 3, true, DEFAULT_STAGE_MEMORY, 128 << 20);
        assert_eq!(p.tiles(640, 0..360).len(), 1);
        assert_eq!(p.chunks(), vec![(0, 3)]);
        let sizes = [([16384, 16384], 1), ([4096, 4096], 256), ([1, 9000], 1000)];
        for ((size, samples), resolved) in sizes.into_iter().flat_map(|s| [(s, false), (s, true)]) {
            for bound in [MIN_STAGE_MEMORY, 1 << 20, DEFAULT_STAGE_MEMORY] {
                let p = TilePlan::new(size, samples, resolved, bound, 128 << 20);
                assert!(
                    p.bytes() <= bound,
                    "{size:?} {samples} {bound}: {}",
                    p.bytes()
                );
                assert!(p.tile[0].is_multiple_of(8) && p.tile[1].is_multiple_of(8));
                let tiles = p.tiles(size[0], 0..size[1]);
                let covered: u64 = tiles.iter().map(|(_, s)| s[0] as u64 * s[1] as u64).sum();
                assert_eq!(covered, size[0] as u64 * size[1] as u64);
                let chunked: u32 = p.chunks().iter().map(|c| c.1).sum();
                assert_eq!(chunked, samples);
                assert_eq!(one_chunk(samples), p.chunks().len() == 1);
            }
        }
    }

    #[test]
    fn only_scenes_with_checkers_have_resolved_materials() {
        // One sample: a 64-byte record and a 16-byte queue entry a pixel,
        // and 16 bytes more for the resolved material.
        let untiled = |resolved| TilePlan::new([1024, 1024], 1, resolved, 1 << 40, 1 << 40);
        assert_eq!(untiled(false).bytes(), 1024 * 1024 * 80);
        assert_eq!(untiled(true).bytes(), 1024 * 1024 * 96);
    }
}
