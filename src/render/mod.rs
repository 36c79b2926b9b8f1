//! The renderer, along the life of a frame:
//! - [`request`]: what a renderer is opened with and what a render asks for;
//! - [`upload`]: a scene laid out, checked against the device and uploaded,
//!   its resources bound by name ([`bindings`]);
//! - the program: the stage files ([`stages`]), their assembly and compile
//!   ([`compile`], [`prune`], [`spirv`]) and the generated shade loader
//!   ([`shade`]); [`pipelines`] caches what they compile to;
//! - the frame: [`frame_plan`] (tiles, bands, stage buffers, hit reuse),
//!   [`passes`] (the stages of each pass), [`readback`] (image, statistics).
//!
//! [`Renderer::render`] runs them in that order.

pub mod bands;
mod bindings;
pub mod compile;
mod error;
mod frame_plan;
pub mod layout;
mod passes;
mod pipelines;
mod prune;
pub mod quantised_bvh;
mod readback;
mod reload;
mod request;
pub mod shade;
mod spirv;
mod stage_buffers;
pub mod stages;
mod texture_edit;
pub mod tiles;
mod trace;
mod upload;

use std::collections::HashMap;
use std::time::Duration;

pub use crate::frame::{
    Aovs, Frame, Image, PartRange, PassInfo, RenderStats, Sampler, Sampling, Timings, MAX_SPP,
};
use crate::scene::{Features, Scene};
use crate::vulkan::{Context, ContextOptions, DeviceInfo};
pub use compile::{
    Accel, CompileError, KernelOptions, Settings, ShaderSource, ShadowOffset, StageKernel,
    Traversal, TriangleTest,
};
pub use error::{is_timeout, RenderError};
pub use reload::ReloadReport;
pub use request::{RenderRequest, Rendered, RendererOptions};
use shade::ProgramFile;
use stages::Stage;
pub use trace::{HitKind, TraceHit, TraceRay};
pub use upload::UploadedScene;

/// Pixels per side of a workgroup's block: the stages' workgroups of 64
/// invocations (`@workgroup_size(64, 1, 1)`) each take an 8×8 block
/// (`shaders/render.wgsl`'s `stage_pixel`).
const TILE: u32 = 8;

/// Bits of a hit record's kind: the rest of its word holds the scene object
/// (`KIND_BITS` in `shaders/stages/records.wgsl`).
pub const KIND_BITS: u32 = 2;
/// Most objects a scene may have: their index shares a word of the hit
/// record with the kind.
pub const MAX_OBJECTS: usize = 1 << (32 - KIND_BITS);

/// Rows per dispatch of a render that can be cancelled ([`RenderRequest::cancel`]) (a multiple of
/// `TILE`, so bands never overlap).
const BAND_ROWS: u32 = 8 * TILE;

/// Renders scenes on one Vulkan device. Create it once and call
/// [`Renderer::render`] per scene: stages are cached by feature set and by
/// the text of their shader files.
pub struct Renderer {
    // Field order matters: pipelines and buffers must drop before the context.
    stage_pipelines: HashMap<(Stage, StageKernel), pipelines::Cached>,
    /// Per shader file and the scene's [`shade::variant`] (the shade stage
    /// compiles textures, attributes, colours and emission in only for
    /// scenes that have them).
    shade_pipelines: HashMap<(ProgramFile, Features), pipelines::Cached>,
    stage_buffers: Vec<stage_buffers::StageBuffers>,
    /// Bumped when a stage before shading is recompiled (stale hits).
    traversal_generation: u64,
    /// Time each pipeline of a frame on its own (benchmarks).
    profile_stages: bool,
    /// Whether the hit stage may trace the shadow rays of one-chunk frames
    /// ([`Renderer::set_fused_shadows`]).
    fuse_shadows: bool,
    /// Whether the stages may write their images as words where the device
    /// allows it ([`Renderer::set_stage_words`]).
    allow_stage_words: bool,
    /// Whether the stages may find their pixels by subgroup and lane where
    /// the device allows it ([`Renderer::set_lane_pixels`]).
    allow_lane_pixels: bool,
    /// Set by a successful [`Renderer::reload_shaders`], cleared by an
    /// upload: renders may then reuse the hit records they find (every other
    /// render traces its rays, and counts them).
    reuse_hits: bool,
    uploads: u64,
    stage_memory: u64,
    /// The largest image band, at most the device's buffer binding.
    band_bytes: u64,
    /// A cap on texture bytes below the device's (tests).
    texture_capacity: u64,
    shaders: ShaderSource,
    kernel: KernelOptions,
    context: Context,
}

impl Renderer {
    /// Opens the Vulkan device.
    pub fn new(opts: &RendererOptions) -> Result<Renderer, RenderError> {
        let context = Context::new(&ContextOptions {
            device: opts.device.clone(),
            validation: opts.validation,
        })?;
        if let Some(limit) = opts.time_limit {
            context.set_time_limit(limit);
        }
        Ok(Renderer {
            stage_pipelines: HashMap::new(),
            shade_pipelines: HashMap::new(),
            stage_buffers: Vec::new(),
            traversal_generation: 0,
            reuse_hits: false,
            profile_stages: false,
            fuse_shadows: true,
            allow_stage_words: true,
            allow_lane_pixels: true,
            uploads: 0,
            stage_memory: tiles::DEFAULT_STAGE_MEMORY,
            band_bytes: u64::MAX,
            texture_capacity: u64::MAX,
            shaders: opts.shaders.clone(),
            kernel: opts.kernel,
            context,
        })
    }

    /// Renders an uploaded scene as `request` says: the one render entry
    /// point ([`RenderRequest`]'s constructors give the common requests).
    /// With `cancel`, each tile is dispatched in bands of 64 rows and
    /// `cancel` is asked before each band ([`RenderError::Cancelled`] once
    /// it says yes); without, a tile is one submission (the fast path). With
    /// `part`, only its rows and passes are rendered and the image is their
    /// sum, so that parts over different passes add up (`stats.passes` is
    /// their count); a part over all passes, times `1 / spp` (when spp > 1),
    /// is bit for bit the undivided render's rows.
    pub fn render(
        &mut self,
        scene: &UploadedScene,
        request: RenderRequest,
    ) -> Result<Rendered, RenderError> {
        frame_plan::check_request(scene, &request)?;
        let (plan, whole_image) = self.plan_frame(scene, &request)?;
        let band_buffers = plan.bands.buffers(&self.context, whole_image)?;
        let mut no_report = |_: &PassInfo| {};
        let RenderRequest {
            sampling,
            on_pass,
            cancel,
            ..
        } = request;
        let mut hooks = passes::Hooks {
            on_pass: match on_pass {
                Some(f) => f,
                None => &mut no_report,
            },
            cancel,
        };
        let totals = self.run_passes(scene, &plan, &band_buffers, &sampling, &mut hooks)?;
        self.read_back(scene, plan, band_buffers, totals)
    }

    /// Uploads a validated scene and renders one frame of it at its size,
    /// one sample per pixel ([`Renderer::upload`], then [`Renderer::render`]
    /// of [`RenderRequest::new`]), with the upload's timings in its stats.
    pub fn render_scene(&mut self, scene: &Scene) -> Result<Frame, RenderError> {
        let uploaded = self.upload(scene)?;
        let (width, height) = uploaded.size();
        let mut frame = self
            .render(&uploaded, RenderRequest::new(width, height))?
            .frame;
        (frame.stats.timings.accel_build, frame.stats.timings.upload) = uploaded.upload_timings();
        Ok(frame)
    }

    /// Bounds every wait on the device ([`Context::set_time_limit`]): a
    /// frame whose submission runs longer fails with
    /// [`RenderError::TimedOut`], naming its shader files.
    pub fn set_time_limit(&self, limit: Duration) {
        self.context.set_time_limit(limit)
    }

    /// The longest one submission has run since the last call
    /// ([`Context::take_longest_wait`]).
    pub fn take_longest_wait(&self) -> Duration {
        self.context.take_longest_wait()
    }

    /// Whether a wait ran past the time limit: the device still runs that
    /// work, and every later frame fails ([`RenderError::is_timeout`]).
    pub fn is_hung(&self) -> bool {
        self.context.is_hung()
    }

    /// The bound on one tile's stage memory (hit records, colour sums and
    /// queued light samples), in bytes ([`tiles::DEFAULT_STAGE_MEMORY`]
    /// unless set).
    pub fn stage_memory(&self) -> u64 {
        self.stage_memory
    }

    /// Submits and times every dispatch of a frame on its own, filling
    /// [`Frame::stage_times`] (for benchmarks: a frame is then a little
    /// slower than one submission of the whole chain).
    pub fn set_profile_stages(&mut self, on: bool) {
        self.profile_stages = on;
    }

    /// Whether the hit stage traces the shadow rays when one chunk holds
    /// every light sample of a pixel ([`Settings::fused_shadows`]; on by
    /// default). Off, the shadow stage runs as for several chunks: the same
    /// image, bit for bit (tests, and benchmarks of the fusion).
    pub fn set_fused_shadows(&mut self, on: bool) {
        self.fuse_shadows = on;
    }

    /// Whether the stages write hit records, resolved materials and queued
    /// samples as storage-buffer words over the memory of the texel images
    /// that the next stage reads ([`Settings::stage_words`]). On by default
    /// where the device allows it (`vulkan::Context::stage_words`: lavapipe);
    /// off, they use texel stores: the same image, bit for bit (tests, and
    /// benchmarks of the difference).
    pub fn set_stage_words(&mut self, on: bool) {
        if on != self.allow_stage_words {
            self.allow_stage_words = on;
            self.stage_buffers.clear();
            // The shade pipelines store their colours as words or not.
            self.shade_pipelines.clear();
        }
    }

    /// Whether this renderer's stages write words ([`Renderer::set_stage_words`]).
    pub fn stage_words(&self) -> bool {
        self.allow_stage_words && self.context.stage_words()
    }

    /// Whether a stage invocation finds its pixel in its workgroup's block
    /// by its subgroup and lane ([`Settings::lane_pixels`]). On by default
    /// where the device allows it (`vulkan::Context::lane_pixels`: lavapipe);
    /// off, by its index in the workgroup: the same image, bit for bit
    /// (tests, and benchmarks of the difference).
    pub fn set_lane_pixels(&mut self, on: bool) {
        if on != self.allow_lane_pixels {
            self.allow_lane_pixels = on;
            // The shade pipelines' cache key holds no settings.
            self.shade_pipelines.clear();
        }
    }

    /// Whether this renderer's stages find their pixels by subgroup and lane
    /// ([`Renderer::set_lane_pixels`]).
    pub fn lane_pixels(&self) -> bool {
        self.allow_lane_pixels && self.context.lane_pixels()
    }

    /// `settings` with the settings this renderer and its device decide:
    /// stage words and lane pixels.
    fn with_device(&self, settings: Settings) -> Settings {
        Settings {
            stage_words: self.stage_words(),
            lane_pixels: self.lane_pixels(),
            ..settings
        }
    }

    /// Sets the bound on one tile's stage memory (at least
    /// [`tiles::MIN_STAGE_MEMORY`]); a lower bound means more, smaller tiles
    /// and the same image.
    pub fn set_stage_memory(&mut self, bytes: u64) {
        self.stage_memory = bytes.max(tiles::MIN_STAGE_MEMORY);
        self.stage_buffers.clear();
    }

    /// Caps each band of the image (and of its AOVs) at `bytes` (at most
    /// the device's `maxStorageBufferRange`, at least 8 rows), so that an
    /// image of any size shows that its bands join without a seam; a lower
    /// cap means more bands and the same image.
    pub fn set_image_band_bytes(&mut self, bytes: u64) {
        self.band_bytes = bytes;
    }

    /// Caps the bytes the scene's textures may take below the device's
    /// limit, so that the limit's error can be shown without a gigabyte of
    /// textures (tests); `u64::MAX` restores the device's.
    pub fn set_texture_capacity(&mut self, bytes: u64) {
        self.texture_capacity = bytes;
    }

    /// The device in use.
    pub fn device(&self) -> &DeviceInfo {
        self.context.info()
    }

    /// The kernel variant in use.
    pub fn kernel(&self) -> KernelOptions {
        self.kernel
    }

    /// Switches the kernel variant (BVH or brute force, triangle test); the
    /// pipeline cache keeps every variant compiled so far. The acceleration
    /// structure and the traversal are those a scene was uploaded with.
    pub fn set_kernel(&mut self, kernel: KernelOptions) {
        self.kernel = kernel;
    }
}

#[cfg(test)]
mod tests {
    use super::upload::check_objects;
    use super::*;

    /// Every object index of a scene that passes the check fits beside any
    /// kind (0 to 2: the WGSL's KIND_* constants are checked against the
    /// kind bits in layout's `shared_constants_match_wgsl`) without making
    /// the word KIND_NONE (all bits set); one object more is refused with
    /// the field named.
    #[test]
    fn object_indices_share_the_record_word_with_the_kind() {
        let last = (MAX_OBJECTS - 1) as u32;
        for kind in 0..3u32 {
            let word = kind | (last << KIND_BITS);
            assert_ne!(word, u32::MAX);
            assert_eq!(word >> KIND_BITS, last);
            assert_eq!(word & ((1 << KIND_BITS) - 1), kind);
        }
        assert!(check_objects(MAX_OBJECTS).is_ok());
        let e = check_objects(MAX_OBJECTS + 1).unwrap_err().to_string();
        assert!(e.starts_with("objects: "), "{e}");
    }
}
