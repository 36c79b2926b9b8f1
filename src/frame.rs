//! What a render produces and asks for, as plain data: the image, its AOVs,
//! the frame's statistics and the sampling settings. The GPU renderer
//! ([`crate::render`]) and the f64 reference ([`crate::reference`]) both
//! produce these, and output and metrics read them, without either judge
//! depending on the renderer it judges.

use std::time::Duration;

/// A linear-light RGBA image, row 0 at the top. Alpha is 1 where a primary
/// ray hit a surface and 0 where it saw the background.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width, pixels.
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
    /// `width * height` pixels, row-major.
    pub pixels: Vec<[f32; 4]>,
}

impl Image {
    /// The pixel at column `x`, row `y` (row 0 is the top).
    pub fn at(&self, x: u32, y: u32) -> [f32; 4] {
        self.pixels[(y * self.width + x) as usize]
    }
}

/// Wall-clock time of each phase of a frame.
#[derive(Clone, Copy, Debug, Default)]
pub struct Timings {
    /// naga: WGSL to SPIR-V (zero when the kernel came from the cache).
    pub shader_compile: Duration,
    /// vkCreateComputePipelines (zero when cached).
    pub pipeline_creation: Duration,
    /// The driver's own compile at the first dispatch (lavapipe compiles
    /// SPIR-V to machine code then), measured with an empty warm-up dispatch;
    /// zero when cached.
    pub driver_compile: Duration,
    /// Building the BVH on the host (zero for brute force).
    pub accel_build: Duration,
    /// Laying out the scene and uploading the buffers.
    pub upload: Duration,
    /// The render dispatch, submit to completion.
    pub render: Duration,
    /// Copying the image back.
    pub readback: Duration,
}

/// What one frame cost.
#[derive(Clone, Copy, Debug, Default)]
pub struct RenderStats {
    /// Primary rays traced (one per pixel).
    pub primary_rays: u64,
    /// Shadow rays traced.
    pub shadow_rays: u64,
    /// Time per phase.
    pub timings: Timings,
    /// Passes (samples per pixel) rendered.
    pub passes: u32,
    /// BVH nodes (0 for brute force).
    pub bvh_nodes: usize,
    /// BVH depth (root = 0).
    pub bvh_depth: usize,
    /// Bytes of the BVH on the GPU (the records' texel image, padding
    /// included, and the primitive references).
    pub bvh_bytes: usize,
    /// The frame reused the hit records (and shadow-ray visibility) of the
    /// previous render at the same view, size and sample: only the shade
    /// and gather stages ran, and no rays were traced.
    pub hits_reused: bool,
    /// Tiles the image was rendered in, and the bytes of stage memory
    /// (hit records, colour sums, queued light samples) one tile takes.
    pub tiles: usize,
    /// See [`RenderStats::tiles`].
    pub stage_bytes: u64,
    /// Bytes of the scene's textures on the device, mip chains included
    /// (0 without textures).
    pub texture_bytes: u64,
}

impl RenderStats {
    /// All rays traced.
    pub fn rays(&self) -> u64 {
        self.primary_rays + self.shadow_rays
    }

    /// Millions of rays per second of the render phase.
    pub fn mrays_per_second(&self) -> f64 {
        self.rays() as f64 / self.timings.render.as_secs_f64().max(1e-9) / 1e6
    }
}

/// A rendered frame.
#[derive(Clone, Debug)]
pub struct Frame {
    /// The image.
    pub image: Image,
    /// Rays and timings.
    pub stats: RenderStats,
    /// With [`crate::render::Renderer::set_profile_stages`]: the time of each pipeline of
    /// the frame (engine stages by name, `shade <file>`), each dispatch
    /// submitted and timed on its own; empty otherwise.
    pub stage_times: Vec<(String, Duration)>,
    /// The driver's compile of each pipeline this render built (engine
    /// stages by name, `shade <file>`), at its first dispatch; empty when
    /// every pipeline came from the cache. Their sum is
    /// `stats.timings.driver_compile`.
    pub driver_compiles: Vec<(String, Duration)>,
}

/// Most samples per pixel.
pub const MAX_SPP: u32 = 1 << 16;

/// How many samples per pixel, and when to stop.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sampling {
    /// Samples per pixel, one per pass, in 1..=[`MAX_SPP`]. One sample goes
    /// through the pixel centre; more are stratified over the pixel (box
    /// filter).
    pub spp: u32,
    /// Seed of every random choice: the same seed gives the same image.
    pub seed: u32,
    /// Stop after the pass in flight once this much time has passed.
    pub time_budget: Option<Duration>,
}

impl Sampling {
    /// The one check of `spp` in the library (the command line checks its
    /// arguments against the same [`MAX_SPP`]): `Err` says what is wrong.
    pub fn check(&self) -> Result<(), String> {
        match (1..=MAX_SPP).contains(&self.spp) {
            true => Ok(()),
            false => Err(format!("must be in 1..={MAX_SPP}, got {}", self.spp)),
        }
    }
}

impl Default for Sampling {
    fn default() -> Self {
        Sampling {
            spp: 1,
            seed: 0,
            time_budget: None,
        }
    }
}

/// Which rows and which passes of a render to do: one part of a render split
/// across processes or machines (`render --tile`, `--passes`; see
/// [`crate::farm`]). Every pixel's samples depend only on the pixel, the
/// pass index and the seed, so a part's pixels equal the same pixels of the
/// undivided render.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PartRange {
    /// Rows `start..end` of the full image (row 0 at the top).
    pub rows: std::ops::Range<u32>,
    /// Pass indices `start..end` of the `Sampling::spp` passes.
    pub passes: std::ops::Range<u32>,
}

/// Progress of a progressive render.
#[derive(Clone, Copy, Debug)]
pub struct PassInfo {
    /// Passes done.
    pub done: u32,
    /// Passes planned.
    pub total: u32,
    /// Rays traced so far.
    pub rays: u64,
    /// Time since the first pass started.
    pub elapsed: Duration,
}

/// Arbitrary output variables of each pixel's first primary ray, row-major
/// like the image.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Aovs {
    /// Distance along the primary ray; `f32::INFINITY` where it hit nothing.
    pub depth: Vec<f32>,
    /// Unit geometric normal facing the viewer (world space); 0 on misses.
    pub normal: Vec<[f32; 3]>,
    /// Barycentric (u, v) of triangle hits (weights of the second and third
    /// vertex); 0 elsewhere.
    pub uv: Vec<[f32; 2]>,
    /// Index of the scene object hit; `u32::MAX` on misses.
    pub object: Vec<u32>,
    /// Index of the triangle within its object (0 for planes and spheres);
    /// `u32::MAX` on misses.
    pub primitive: Vec<u32>,
}

/// How samples (pixel jitter, area-light points) are placed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Sampler {
    /// The R2 low-discrepancy sequence with a per-pixel random shift
    /// (stratified; the default).
    #[default]
    Stratified = 0,
    /// Independent uniform random samples (for comparison).
    Random = 1,
}

impl std::str::FromStr for Sampler {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "stratified" => Ok(Sampler::Stratified),
            "random" => Ok(Sampler::Random),
            _ => Err(format!("expected `stratified` or `random`, got `{s}`")),
        }
    }
}
