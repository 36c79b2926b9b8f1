//! The renderer: lays a scene out for the GPU, compiles (and caches) the
//! stages of a frame ([`stages`]) specialised to the scene's features, runs
//! them tile by tile ([`tiles`]) and reads the image back.

pub mod bands;
pub mod compile;
pub mod layout;
mod prune;
pub mod quantised_bvh;
mod reload;
pub mod shade;
mod spirv;
pub mod stages;
mod texture_edit;
pub mod tiles;
mod trace;

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use bytemuck::Zeroable;

pub use crate::frame::{
    Aovs, Frame, Image, PartRange, PassInfo, RenderStats, Sampler, Sampling, Timings, MAX_SPP,
};
use crate::scene::{Features, Scene};
use crate::vulkan::{
    BindingType, Buffer, BufferUsage, ComputePipeline, Context, ContextOptions, DeviceInfo,
    DeviceSelector, Dispatch, Resource, TexelImage, VulkanError, DRIVER_COMPILE_LIMIT,
};
use bands::ImageBands;
pub use compile::{
    Accel, CompileError, KernelOptions, Settings, ShaderSource, ShadowOffset, StageKernel,
    TriangleTest,
};
use layout::{GpuScene, PushConstants, FLAG_FRESH, FLAG_LAST_CHUNK, FLAG_WARM_UP};
pub use reload::ReloadReport;
use shade::{Materials, ProgramFile};
use stages::{Binding, Stage};
use tiles::TilePlan;
pub use trace::{HitKind, TraceHit, TraceRay};

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

/// Refuses a scene of more than [`MAX_OBJECTS`] objects, naming the field.
fn check_objects(n: usize) -> Result<(), RenderError> {
    if n > MAX_OBJECTS {
        return Err(RenderError::Scene {
            field: "objects".into(),
            message: format!("{n} objects, more than the {MAX_OBJECTS} a scene may have"),
        });
    }
    Ok(())
}
/// Rows per dispatch of [`Renderer::render_cancellable`] (a multiple of
/// `TILE`, so bands never overlap).
const BAND_ROWS: u32 = 8 * TILE;

/// How to set up a [`Renderer`].
#[derive(Clone, Debug, Default)]
pub struct RendererOptions {
    /// Which Vulkan device; `None` picks the first discrete or integrated
    /// GPU, else the CPU device (lavapipe).
    pub device: Option<DeviceSelector>,
    /// Enable the Khronos validation layer and fail on any error it reports.
    pub validation: bool,
    /// Where the WGSL comes from.
    pub shaders: ShaderSource,
    /// BVH or brute force, and the ray/triangle test.
    pub kernel: KernelOptions,
    /// The longest one submission may run ([`Renderer::set_time_limit`]);
    /// `None`: [`crate::vulkan::DEFAULT_TIME_LIMIT`].
    pub time_limit: Option<Duration>,
}

/// Why a frame could not be rendered.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// Vulkan failed or a device limit was exceeded.
    #[error(transparent)]
    Vulkan(#[from] VulkanError),
    /// The WGSL did not compile.
    /// (Not a `source()` as well: `anyhow`'s `{:#}` would print it twice.)
    #[error("shader error: {0}")]
    Compile(CompileError),
    /// The scene asks for more than the device can do; `field` names the
    /// scene field (e.g. `camera.width`).
    #[error("{field}: {message}")]
    Scene {
        /// The offending scene field.
        field: String,
        /// What limit it exceeds.
        message: String,
    },
    /// Work on the device ran past its time limit: a shader that does not
    /// end or far too much work in one submission, or (`compile`) a driver
    /// compile that did not end. The device keeps running it
    /// ([`VulkanError::TimedOut`]): only ending the process frees it.
    #[error("{}", timed_out_message(what, *.compile, *.limit))]
    TimedOut {
        /// What was running: `scenes/shaders/loop.wgsl: the shade stage` for
        /// user files, else the engine stages.
        what: String,
        /// The user shader files among them (empty: only engine stages).
        user_files: Vec<PathBuf>,
        /// Whether it was the driver's compile (the first dispatch of a
        /// pipeline) rather than a frame's work.
        compile: bool,
        /// The limit.
        limit: Duration,
    },
}

fn timed_out_message(what: &str, compile: bool, limit: Duration) -> String {
    let limit = crate::vulkan::describe_limit(limit);
    match compile {
        true => {
            format!("{what}: the driver's compile ran past {limit}: is the shader far too large?")
        }
        false => format!(
            "{what} ran past the time limit of {limit} (--time-limit): a loop that never ends?"
        ),
    }
}

impl RenderError {
    /// Whether the device is left running work it could not finish in time
    /// ([`RenderError::TimedOut`] or a [`VulkanError::TimedOut`] of a
    /// transfer): the process must end to free it.
    pub fn is_timeout(&self) -> bool {
        matches!(
            self,
            RenderError::TimedOut { .. } | RenderError::Vulkan(VulkanError::TimedOut { .. })
        )
    }
}

/// Whether `e` (or an error it wraps) is a time-out of the device
/// ([`RenderError::is_timeout`]).
pub fn is_timeout(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<RenderError>()
            .is_some_and(RenderError::is_timeout)
            || matches!(
                c.downcast_ref::<VulkanError>(),
                Some(VulkanError::TimedOut { .. })
            )
    })
}

impl From<CompileError> for RenderError {
    fn from(e: CompileError) -> Self {
        RenderError::Compile(e)
    }
}

impl Aovs {
    fn from_gpu(bytes: &[u8], n: usize, scene: &UploadedScene) -> Aovs {
        let raw: Vec<layout::Aov> = bytemuck::pod_collect_to_vec(&bytes[..n * 32]);
        let mut a = Aovs::default();
        for r in raw {
            a.depth.push(r.depth);
            a.normal.push([r.normal_x, r.normal_y, r.normal_z]);
            a.uv.push([r.u, r.v]);
            a.object.push(r.object);
            let first = scene
                .first_triangle
                .get(r.object as usize)
                .copied()
                .flatten();
            a.primitive.push(match (r.object, first) {
                (u32::MAX, _) => u32::MAX,
                (_, Some(f)) => r.primitive.wrapping_sub(f),
                (_, None) => 0,
            });
        }
        a
    }
}

/// What an uploaded scene binds at one binding (as [`stages::BINDINGS`] says).
enum Bound {
    Buffer(Buffer),
    Image(TexelImage),
}

impl Bound {
    fn resource(&self) -> Resource<'_> {
        match self {
            Bound::Buffer(b) => Resource::Buffer(b),
            Bound::Image(i) => Resource::Image(i),
        }
    }

    /// The buffer, for the bindings [`stages::BINDINGS`] declares as buffers.
    fn buffer(&self) -> Result<&Buffer, RenderError> {
        match self {
            Bound::Buffer(b) => Ok(b),
            Bound::Image(i) => Err(RenderError::Vulkan(VulkanError::InvalidArgument(format!(
                "'{}' is a texel image, not a buffer",
                i.label()
            )))),
        }
    }
}

/// A scene laid out and uploaded to the device, ready to render.
pub struct UploadedScene {
    /// One per binding of [`stages::BINDINGS`], in order (the tile's stage
    /// buffers are placeholders, replaced per render).
    bound: Vec<Bound>,
    /// Tells uploads apart (hit records are reused only for the same one).
    id: u64,
    /// The scene's shaders and texture uses, to rebuild the materials
    /// after a shader edit.
    shaders: Vec<crate::scene::Shader>,
    texture_uses: Vec<crate::scene::TextureRef>,
    /// [`layout::FLAG_ATTRIBUTES`] and [`layout::FLAG_EMISSION`] as the
    /// scene needs them.
    shade_flags: u32,
    /// Bytes of textures with their mip chains on the device.
    texture_bytes: u64,
    /// Where each texture lies in the texture texels (texture edits).
    texture_chains: Vec<layout::textures::TextureChain>,
    /// Shade programs and parameters.
    materials: Materials,
    /// Light samples per pixel and pass, over all lights.
    light_samples: u32,
    /// Lights (the host uploads a placeholder for a scene without any,
    /// which no stage may count).
    light_count: u32,
    features: Features,
    kernel: KernelOptions,
    /// The camera position the geometry is relative to.
    eye: glam::DVec3,
    /// Per object: index of its first triangle (None for planes, spheres).
    first_triangle: Vec<Option<u32>>,
    width: u32,
    height: u32,
    accel_build: Duration,
    upload: Duration,
    bvh_nodes: usize,
    bvh_depth: usize,
    bvh_bytes: usize,
}

impl UploadedScene {
    /// Lights the stages loop over (the host uploads a placeholder light
    /// for a scene without any, which no stage may count).
    fn light_count(&self) -> u32 {
        self.light_count
    }

    /// The scene's full image size.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// The kinds of primitive, light and shader the scene uses.
    pub fn features(&self) -> Features {
        self.features
    }

    /// Time of the BVH build and of the upload.
    pub fn upload_timings(&self) -> (Duration, Duration) {
        (self.accel_build, self.upload)
    }
}

/// One render of an uploaded scene ([`Renderer::render_request`]): size,
/// samples, which part, which outputs, and the caller's hooks.
pub struct RenderRequest<'a> {
    /// Image width, pixels (at most the uploaded size; smaller keeps the
    /// field of view: previews).
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Samples per pixel, seed and time budget.
    pub sampling: Sampling,
    /// Only these rows and passes of the full-size render (then width and
    /// height must be the uploaded size, and the image is the passes' sum).
    pub part: Option<PartRange>,
    /// Also return the AOVs of each pixel's first primary ray.
    pub aovs: bool,
    /// Called after every pass.
    pub on_pass: Option<&'a mut dyn FnMut(&PassInfo)>,
    /// Asked between bands of rows; a yes stops the render (`Ok(None)`).
    pub cancel: Option<&'a mut dyn FnMut() -> bool>,
}

impl RenderRequest<'_> {
    /// One sample per pixel through its centre at `width`×`height`, the
    /// whole image, no AOVs, no hooks.
    pub fn new(width: u32, height: u32) -> Self {
        RenderRequest {
            width,
            height,
            sampling: Sampling::default(),
            part: None,
            aovs: false,
            on_pass: None,
            cancel: None,
        }
    }
}

/// What [`Renderer::render_request`] returns.
#[derive(Clone, Debug)]
pub struct Rendered {
    /// The image and its statistics.
    pub frame: Frame,
    /// The AOVs, when asked for.
    pub aovs: Option<Aovs>,
}

/// A compiled pipeline and the hash of the source it was compiled from
/// (for a shade pipeline also of the shader file's own text).
struct Cached {
    pipeline: ComputePipeline,
    hash: u64,
    file_hash: u64,
}

/// Which hit records (and light-sample visibility) the stage buffers hold:
/// everything a shading edit leaves unchanged.
#[derive(Clone, Debug, PartialEq)]
struct HitKey {
    upload: u64,
    traversal: u64,
    size: [u32; 2],
    rows: std::ops::Range<u32>,
    pass_index: u32,
    seed: u32,
    kernel: StageKernel,
}

/// The stage buffers of one tile plan, and whose hits they hold.
struct StageBuffers {
    plan: TilePlan,
    hits: TexelImage,
    queue: TexelImage,
    resolved: TexelImage,
    radiance: Buffer,
    /// The image of the last whole render with these buffers (made when
    /// one needs it): a reused frame skips the hit stage, which writes the
    /// pixels that hit nothing, so they must still hold that render's.
    image: Option<Buffer>,
    holds: Option<HitKey>,
}

/// Stage buffers kept for hit reuse: the preview's and the full image's.
const KEPT_STAGE_BUFFERS: usize = 2;

/// Renders scenes on one Vulkan device. Create it once and call
/// [`Renderer::render`] per scene: stages are cached by feature set and by
/// the text of their shader files.
pub struct Renderer {
    // Field order matters: pipelines and buffers must drop before the context.
    stage_pipelines: HashMap<(Stage, StageKernel), Cached>,
    /// Per shader file and the scene's [`shade::variant`] (the shade stage
    /// compiles textures, attributes, colours and emission in only for
    /// scenes that have them).
    shade_pipelines: HashMap<(ProgramFile, Features), Cached>,
    stage_buffers: Vec<StageBuffers>,
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

/// Compile times of the pipelines built for a frame, and their names.
#[derive(Clone, Debug, Default)]
struct Compiled {
    naga: Duration,
    pipeline: Duration,
    driver: Duration,
    names: Vec<String>,
}

impl Compiled {
    fn add(&mut self, other: Compiled) {
        self.naga += other.naga;
        self.pipeline += other.pipeline;
        self.driver += other.driver;
        self.names.extend(other.names);
    }
}

/// One dispatch of a frame: its slot in the stage times, the pipeline, its
/// push constants and its workgroups.
type StagePush<'a> = (usize, &'a ComputePipeline, PushConstants, [u32; 3]);

/// Records `pending` with the bindings `refs` in one submission, waits for
/// it and empties `pending`, or, when `profile` is set, submits and times
/// each dispatch on its own (adding each to its slot of `stage_times`).
/// Returns the time spent (zero when nothing was pending).
fn submit(
    ctx: &Context,
    pending: &mut Vec<StagePush>,
    refs: &[Resource],
    profile: bool,
    stage_times: &mut [Duration],
    slots: &[SlotName],
) -> Result<Duration, RenderError> {
    submit_chain(ctx, pending, refs, profile, stage_times)
        .map_err(|e| name_timed_out_stages(e, pending, slots))
}

/// What a slot of the stage times runs, as a time-out names it: an engine
/// stage, or a shade program (its file's name, and its path if a user's).
enum SlotName {
    Engine(&'static str),
    Program(String, Option<PathBuf>),
}

/// Names the stages of the submission `pending` that ran past the time
/// limit: the user shader files among them (the only code in a frame whose
/// running time the engine does not bound), else the engine stages.
fn name_timed_out_stages(e: RenderError, pending: &[StagePush], slots: &[SlotName]) -> RenderError {
    let RenderError::Vulkan(VulkanError::TimedOut { limit }) = e else {
        return e;
    };
    let mut user_files: Vec<PathBuf> = Vec::new();
    let mut stages: Vec<String> = Vec::new();
    for (slot, ..) in pending {
        let name = match slots.get(*slot) {
            Some(SlotName::Program(label, user)) => {
                if let Some(p) = user.as_ref().filter(|p| !user_files.contains(p)) {
                    user_files.push(p.clone());
                }
                format!("the shade stage of {label}")
            }
            Some(SlotName::Engine(name)) => format!("the {name} stage"),
            None => continue,
        };
        if !stages.contains(&name) {
            stages.push(name);
        }
    }
    let what = match (user_files.is_empty(), stages.is_empty()) {
        (false, _) => {
            let files: Vec<String> = user_files.iter().map(|p| p.display().to_string()).collect();
            format!("{}: the shade stage", files.join(", "))
        }
        (true, false) => stages.join(" or "),
        (true, true) => "a submission".to_string(),
    };
    RenderError::TimedOut {
        what,
        user_files,
        compile: false,
        limit,
    }
}

/// [`submit`] before its time-out is named.
fn submit_chain(
    ctx: &Context,
    pending: &mut Vec<StagePush>,
    refs: &[Resource],
    profile: bool,
    stage_times: &mut [Duration],
) -> Result<Duration, RenderError> {
    let chain: Vec<Dispatch> = pending
        .iter()
        .map(|(_, pipeline, push, groups)| Dispatch {
            pipeline,
            resources: refs,
            push_constants: bytemuck::bytes_of(push),
            groups: *groups,
        })
        .collect();
    let mut total = Duration::ZERO;
    if profile {
        for ((slot, ..), d) in pending.iter().zip(&chain) {
            let t = ctx.dispatch_chain(std::slice::from_ref(d))?;
            stage_times[*slot] += t;
            total += t;
        }
    } else if !chain.is_empty() {
        total = ctx.dispatch_chain(&chain)?;
    }
    pending.clear();
    Ok(total)
}

fn text_hash(parts: &[&str]) -> u64 {
    use std::hash::{Hash, Hasher};
    let mut h = std::collections::hash_map::DefaultHasher::new();
    parts.hash(&mut h);
    h.finish()
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

    /// The most triangles a scene may have on this device: its triangle
    /// records must fit a texel image of `maxImageDimension2D` rows, and its
    /// BVH primitive references one storage buffer. Loaders check this
    /// before expanding a file (`LoadOptions::max_triangles`).
    pub fn max_triangles(&self) -> u64 {
        let limits = self.context.limits();
        let texels_per_triangle =
            (std::mem::size_of::<layout::Triangle>() / crate::vulkan::TEXEL_BYTES) as u64;
        let in_image = limits.max_image_dimension_2d as u64 * crate::vulkan::TEXEL_ROW as u64
            / texels_per_triangle;
        let in_buffer = limits.max_storage_buffer_range / std::mem::size_of::<u32>() as u64;
        in_image.min(in_buffer)
    }

    /// The most bytes the scene's textures may take with their mip chains
    /// on this device: one texel image of `maxImageDimension2D` rows of
    /// [`crate::vulkan::TEXEL_ROW`] texels, within its largest allocation
    /// (and [`Renderer::set_texture_capacity`]). Loaders check each image's
    /// header against it before decoding (`LoadOptions::max_texture_bytes`).
    pub fn texture_capacity(&self) -> u64 {
        let limits = self.context.limits();
        (u64::from(crate::vulkan::TEXEL_ROW)
            * u64::from(limits.max_image_dimension_2d)
            * crate::vulkan::TEXEL_BYTES as u64)
            .min(limits.max_memory_allocation_size)
            .min(self.texture_capacity)
    }

    /// The kernel variant in use.
    pub fn kernel(&self) -> KernelOptions {
        self.kernel
    }

    /// Switches the kernel variant (BVH or brute force, triangle test); the
    /// pipeline cache keeps every variant compiled so far.
    pub fn set_kernel(&mut self, kernel: KernelOptions) {
        self.kernel = kernel;
    }

    /// Forgets compiled pipelines and kept hit records.
    pub fn clear_pipeline_cache(&mut self) {
        self.stage_pipelines.clear();
        self.shade_pipelines.clear();
        self.stage_buffers.clear();
    }

    /// Creates a pipeline from `spirv` and makes the driver compile it now
    /// with an empty dispatch (lavapipe compiles at the first dispatch), so
    /// that render phases measure rendering only. Returns it and the times
    /// of pipeline creation and of the driver's compile.
    ///
    /// That first dispatch waits for the driver at most
    /// [`DRIVER_COMPILE_LIMIT`] (or the time limit if longer); past it, the
    /// error names `what` (and `user_file`, the user's shader file, if any).
    fn build_pipeline(
        &self,
        spirv: &[u32],
        entry: &str,
        what: &str,
        user_file: Option<&Path>,
    ) -> Result<(ComputePipeline, Duration, Duration), RenderError> {
        let t1 = Instant::now();
        let types = stages::binding_types();
        let pipeline = self.context.create_compute_pipeline(
            spirv,
            entry,
            &types,
            std::mem::size_of::<PushConstants>() as u32,
        )?;
        let t2 = Instant::now();
        let dummies: Vec<_> = types
            .iter()
            .map(|b| {
                let ctx = &self.context;
                Ok(match b {
                    BindingType::Uniform => {
                        Bound::Buffer(ctx.create_buffer("warm-up", BufferUsage::Uniform, 256)?)
                    }
                    BindingType::TexelImage | BindingType::StageImage => {
                        Bound::Image(ctx.create_texel_image("warm-up", &[])?)
                    }
                    _ => Bound::Buffer(ctx.create_buffer("warm-up", BufferUsage::Storage, 256)?),
                })
            })
            .collect::<Result<_, VulkanError>>()?;
        let refs: Vec<_> = dummies.iter().map(Bound::resource).collect();
        let push = PushConstants {
            flags: FLAG_WARM_UP,
            ..Zeroable::zeroed()
        };
        let limit = self.context.time_limit().max(DRIVER_COMPILE_LIMIT);
        let push = bytemuck::bytes_of(&push);
        match self
            .context
            .dispatch_within(&pipeline, &refs, push, [1, 1, 1], limit)
        {
            Err(VulkanError::TimedOut { limit }) => {
                return Err(RenderError::TimedOut {
                    what: what.to_string(),
                    user_files: user_file.map(Path::to_path_buf).into_iter().collect(),
                    compile: true,
                    limit,
                })
            }
            r => r?,
        };
        Ok((pipeline, t2 - t1, t2.elapsed()))
    }

    /// Compiles engine stage `stage` for `features` and `kernel` unless the
    /// cache has it; with `reload`, also when its files' text changed since.
    fn stage_pipeline(
        &mut self,
        stage: Stage,
        kernel: StageKernel,
        reload: bool,
    ) -> Result<Compiled, RenderError> {
        let key = (stage, kernel);
        if !reload && self.stage_pipelines.contains_key(&key) {
            return Ok(Compiled::default());
        }
        let t0 = Instant::now();
        let assembled = self.shaders.assemble_stage(stage)?;
        let hash = text_hash(&[&assembled.text]);
        if self
            .stage_pipelines
            .get(&key)
            .is_some_and(|c| c.hash == hash)
        {
            return Ok(Compiled::default());
        }
        let spirv = assembled.compile_entry(&kernel, stage.entry_point())?;
        let naga = t0.elapsed();
        let what = format!("the {} stage", stage.name());
        let (pipeline, creation, driver) =
            self.build_pipeline(&spirv, stage.entry_point(), &what, None)?;
        if stage != Stage::Trace {
            self.traversal_generation += 1;
        }
        self.stage_pipelines.insert(
            key,
            Cached {
                pipeline,
                hash,
                file_hash: 0,
            },
        );
        Ok(Compiled {
            naga,
            pipeline: creation,
            driver,
            names: vec![stage.name().to_string()],
        })
    }

    /// Compiles the shade pipeline of `program` unless the cache holds one
    /// compiled from the same text.
    fn shade_pipeline(
        &mut self,
        program: &shade::Program,
        variant: Features,
    ) -> Result<Compiled, RenderError> {
        let t0 = Instant::now();
        let source = shade::assemble(&self.shaders, &program.file, &program.text)?;
        if source.fields != program.fields {
            return Err(RenderError::Compile(CompileError {
                location: program.file.label(),
                message: shade::PARAMS_CHANGED.into(),
            }));
        }
        let hash = text_hash(&[&source.assembled.text]);
        let cache_key = (program.file.clone(), variant);
        if self
            .shade_pipelines
            .get(&cache_key)
            .is_some_and(|c| c.hash == hash)
        {
            return Ok(Compiled::default());
        }
        let key = StageKernel {
            features: variant,
            settings: self.with_device(Settings::default()),
            ..StageKernel::default()
        };
        let spirv = source
            .assembled
            .compile_entry(&key, shade::SHADE_ENTRY_POINT)?;
        let naga = t0.elapsed();
        let what = format!("{}: the shade stage", program.file.label_in(&self.shaders));
        let user_file = match &program.file {
            ProgramFile::User(p) => Some(p.as_path()),
            ProgramFile::Builtin(_) => None,
        };
        let (pipeline, creation, driver) =
            self.build_pipeline(&spirv, shade::SHADE_ENTRY_POINT, &what, user_file)?;
        self.shade_pipelines.insert(
            cache_key,
            Cached {
                pipeline,
                hash,
                file_hash: text_hash(&[&program.text]),
            },
        );
        Ok(Compiled {
            naga,
            pipeline: creation,
            driver,
            names: vec![format!("shade {}", program.file.label_in(&self.shaders))],
        })
    }

    /// Every pipeline a frame of `scene` needs, compiled unless cached (with
    /// `reload`: recompiled where the files' text changed).
    fn frame_pipelines(
        &mut self,
        scene: &UploadedScene,
        kernel: StageKernel,
        reload: bool,
    ) -> Result<Compiled, RenderError> {
        let mut done = Compiled::default();
        for &stage in Stage::frame(&kernel.settings) {
            done.add(self.stage_pipeline(stage, kernel, reload)?);
        }
        for program in &scene.materials.programs {
            // A user file is compiled from the text the scene loaded (two
            // uploads of one path may differ); built-ins are re-read on a
            // reload only.
            let variant = shade::variant(&scene.features);
            let current = self
                .shade_pipelines
                .get(&(program.file.clone(), variant))
                .is_some_and(|c| c.file_hash == text_hash(&[&program.text]));
            if reload || !current {
                done.add(self.shade_pipeline(program, variant)?);
            }
        }
        Ok(done)
    }

    /// The index of kept stage buffers for `plan`, allocating them (and
    /// dropping the least recently used) when none fit.
    fn stage_buffers_for(&mut self, plan: TilePlan) -> Result<usize, RenderError> {
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

    /// Checks the image against the device's limits and
    /// [`bands::MAX_IMAGE_BYTES`], naming the scene field. An image larger
    /// than one buffer binding is no limit: it is kept in bands of rows
    /// ([`ImageBands`]).
    /// Without `whole`, only the workgroup counts (parts check their rows).
    /// All textures share one texel image: they must fit the device's
    /// `maxImageDimension2D` rows of [`crate::vulkan::TEXEL_ROW`] texels (four
    /// texture texels each) and its largest allocation. The error names the
    /// first texture that does not fit.
    fn check_textures(&self, scene: &Scene) -> Result<(), RenderError> {
        let limits = self.context.limits();
        let capacity = self.texture_capacity();
        let mut total = 0u64;
        for (i, t) in scene.textures.iter().enumerate() {
            total += t
                .device_bytes()
                .next_multiple_of(crate::vulkan::TEXEL_BYTES as u64);
            if total > capacity {
                return Err(RenderError::Scene {
                    field: format!("textures[{i}] ({})", t.label),
                    message: format!(
                        "the scene's textures with their mip-maps need {:.1} MiB up to this one, more than the {:.1} MiB this device's texture image holds (maxImageDimension2D {} rows of {} texels, maxMemoryAllocationSize {})",
                        total as f64 / 1048576.0,
                        capacity as f64 / 1048576.0,
                        limits.max_image_dimension_2d,
                        crate::vulkan::TEXEL_ROW * 4,
                        limits.max_memory_allocation_size
                    ),
                });
            }
        }
        Ok(())
    }

    fn check_size(&self, width: u32, height: u32, whole: bool) -> Result<(), RenderError> {
        let limits = self.context.limits();
        let bytes = width as u64 * height as u64 * bands::PIXEL_BYTES;
        if whole && bytes > bands::MAX_IMAGE_BYTES {
            return Err(RenderError::Scene {
                field: "camera.width/camera.height".into(),
                message: format!(
                    "{width}x{height} pixels need a {:.0} MiB image, more than the {} MiB one render holds: render it in tiles (render --tile I/N, then penumbra merge)",
                    bytes as f64 / 1048576.0,
                    bands::MAX_IMAGE_BYTES >> 20
                ),
            });
        }
        for (field, side, max) in [
            (
                "camera.width",
                width,
                limits.max_compute_work_group_count[0],
            ),
            (
                "camera.height",
                height,
                limits.max_compute_work_group_count[1],
            ),
        ] {
            if side.div_ceil(TILE) > max {
                return Err(RenderError::Scene {
                    field: field.into(),
                    message: format!(
                        "{side} pixels exceed this device's limit of {} workgroups of {TILE}",
                        max
                    ),
                });
            }
        }
        Ok(())
    }

    /// [`Renderer::upload`] for the parts of a split render
    /// ([`Renderer::render_part`]): the image may be larger than one render
    /// holds ([`bands::MAX_IMAGE_BYTES`]), since each part renders only its
    /// rows.
    pub fn upload_for_parts(&mut self, scene: &Scene) -> Result<UploadedScene, RenderError> {
        self.upload_inner(scene, false)
    }

    /// Lays out a validated scene, builds its BVH and uploads it. The result
    /// can be rendered many times, at any size up to the scene's own, and
    /// survives shader edits (see [`Renderer::render_uploaded`]).
    pub fn upload(&mut self, scene: &Scene) -> Result<UploadedScene, RenderError> {
        self.upload_inner(scene, true)
    }

    fn upload_inner(&mut self, scene: &Scene, whole: bool) -> Result<UploadedScene, RenderError> {
        self.reuse_hits = false;
        let (width, height) = (scene.camera.width, scene.camera.height);
        self.check_size(width, height, whole)?;
        self.check_textures(scene)?;
        check_objects(scene.objects.len())?;
        let t0 = Instant::now();
        let mut gpu = GpuScene::new(scene);
        let materials =
            Materials::new(&scene.shaders, &scene.texture_uses(), &self.shaders, false)?;
        set_leaves(&mut gpu.shaders, &materials);
        let layout = t0.elapsed();
        let t_bvh = Instant::now();
        if self.kernel.accel == Accel::Bvh {
            gpu.build_bvh();
        }
        let accel_build = t_bvh.elapsed();
        let t0 = Instant::now();
        let ctx = &self.context;
        let storage = |label: &str, bytes: &[u8]| {
            ctx.create_buffer_with_data(label, BufferUsage::Storage, bytes)
        };
        // The kernel reads the first light before it knows whether there is
        // one (shaders/lights.wgsl, first_light): upload at least one.
        let no_light = [layout::Light::zeroed()];
        let lights = if gpu.lights.is_empty() {
            &no_light[..]
        } else {
            &gpu.lights[..]
        };
        let texels =
            |label: &str, bytes: &[u8]| ctx.create_texel_image(label, bytes).map(Bound::Image);
        let b = Bound::Buffer;
        let bound = vec![
            b(ctx.create_buffer_with_data(
                "globals",
                BufferUsage::Uniform,
                bytemuck::bytes_of(&gpu.globals),
            )?),
            b(storage("planes", bytemuck::cast_slice(&gpu.planes))?),
            b(storage("spheres", bytemuck::cast_slice(&gpu.spheres))?),
            texels("triangles", bytemuck::cast_slice(&gpu.triangles))?,
            b(storage(
                "vertex normals",
                bytemuck::cast_slice(&gpu.vertex_normals),
            )?),
            b(storage("lights", bytemuck::cast_slice(lights))?),
            texels("shaders", bytemuck::cast_slice(&gpu.shaders))?,
            // The image: a placeholder, replaced per render (ImageBands).
            b(ctx.create_buffer("image", BufferUsage::Storage, 16)?),
            b(ctx.create_buffer("counters", BufferUsage::Storage, 16)?),
            texels("BVH nodes", bytemuck::cast_slice(&gpu.bvh_nodes))?,
            texels("BVH primitives", bytemuck::cast_slice(&gpu.bvh_prims))?,
            // Ray-query buffers: placeholders, replaced per Renderer::trace.
            b(ctx.create_buffer("query rays", BufferUsage::Storage, 16)?),
            b(ctx.create_buffer("query hits", BufferUsage::Storage, 16)?),
            // AOV buffer: a placeholder, replaced when AOVs are asked for.
            b(ctx.create_buffer("AOVs", BufferUsage::Storage, 16)?),
            // The tile's stage buffers: placeholders, replaced per render.
            texels("hit records", &[])?,
            texels("queued samples", &[])?,
            texels("resolved materials", &[])?,
            b(ctx.create_buffer("colour sums", BufferUsage::Storage, 16)?),
            texels("shader parameters", bytemuck::cast_slice(&materials.words))?,
            texels(
                "light colours",
                bytemuck::cast_slice(&light_colours(lights)),
            )?,
            texels("texture texels", bytemuck::cast_slice(&gpu.textures.texels))?,
            texels("texture uses", bytemuck::cast_slice(&gpu.textures.uses))?,
            texels(
                "surface maps",
                bytemuck::cast_slice(&gpu.textures.surface_maps),
            )?,
            texels(
                "vertex attributes",
                bytemuck::cast_slice(&gpu.textures.attributes),
            )?,
            // The stage images' words: placeholders, replaced per render
            // where the stage images have them.
            b(ctx.create_buffer("hit record words", BufferUsage::Storage, 16)?),
            b(ctx.create_buffer("queue words", BufferUsage::Storage, 16)?),
            b(ctx.create_buffer("resolved words", BufferUsage::Storage, 16)?),
            // The image as words: a placeholder, replaced with the image.
            b(ctx.create_buffer("image words", BufferUsage::Storage, 16)?),
            b(ctx.create_buffer_with_data(
                "light block",
                BufferUsage::Uniform,
                bytemuck::cast_slice(&layout::light_block(lights)),
            )?),
        ];
        debug_assert_eq!(bound.len(), stages::BINDINGS.len());
        // The records' and references' images hold whole rows of texels
        // (brute force binds empty ones, which the BVH's memory does not
        // count).
        let image_bytes = |binding: Binding| match &bound[binding as usize] {
            Bound::Image(image) if !gpu.bvh_nodes.is_empty() => image.size() as usize,
            _ => 0,
        };
        let bvh_bytes = image_bytes(Binding::BvhNodes) + image_bytes(Binding::BvhPrims);
        // First triangle of each triangle-based object, to number AOV
        // primitives within their object.
        let mut next = 0u32;
        let first_triangle = scene
            .objects
            .iter()
            .map(|o| {
                let n = match &o.shape {
                    crate::scene::Shape::Triangle(_) => 1,
                    crate::scene::Shape::Mesh(m) => m.indices.len() as u32,
                    _ => return None,
                };
                next += n;
                Some(next - n)
            })
            .collect();
        self.uploads += 1;
        let light_samples = gpu.lights.iter().map(|l| l.samples).sum();
        Ok(UploadedScene {
            bound,
            id: self.uploads,
            shaders: scene.shaders.clone(),
            texture_uses: scene.texture_uses(),
            shade_flags: layout::shade_flags(scene),
            texture_bytes: gpu.textures.texture_bytes,
            texture_chains: gpu.textures.chains.clone(),
            materials,
            light_samples,
            light_count: gpu.lights.len() as u32,
            features: scene.features(),
            kernel: self.kernel,
            eye: scene.camera.position,
            first_triangle,
            width,
            height,
            accel_build,
            upload: layout + t0.elapsed(),
            bvh_nodes: gpu.bvh_nodes.len(),
            bvh_depth: gpu.bvh_depth,
            bvh_bytes,
        })
    }

    /// Renders an uploaded scene at `width`×`height` pixels (at most the
    /// scene's size; smaller sizes keep the field of view: previews), one
    /// sample per pixel through its centre: [`Renderer::render_request`] of
    /// [`RenderRequest::new`].
    pub fn render_uploaded(
        &mut self,
        scene: &UploadedScene,
        width: u32,
        height: u32,
    ) -> Result<Frame, RenderError> {
        self.render_whole(scene, RenderRequest::new(width, height))
            .map(|r| r.frame)
    }

    /// Renders an uploaded scene in passes of one sample per pixel each,
    /// accumulating in a float buffer, until `sampling.spp` passes are done
    /// or the time budget is spent (the pass in flight is finished). Calls
    /// `on_pass` after every pass. The image is the mean of the passes done.
    pub fn render_progressive(
        &mut self,
        scene: &UploadedScene,
        width: u32,
        height: u32,
        sampling: &Sampling,
        on_pass: &mut dyn FnMut(&PassInfo),
    ) -> Result<Frame, RenderError> {
        let request = RenderRequest {
            sampling: *sampling,
            on_pass: Some(on_pass),
            ..RenderRequest::new(width, height)
        };
        self.render_whole(scene, request).map(|r| r.frame)
    }

    /// Renders one part of a full-size render: the rows and passes of
    /// `part` (pass indices out of `sampling.spp`, which also decides the
    /// pixel jitter as in the undivided render). The image holds only those
    /// rows, and each pixel is the *sum* of the part's passes, not the mean,
    /// so that parts over different passes add up; `stats.passes` is their
    /// count. A part over all passes, multiplied by `1 / spp` (when spp > 1),
    /// is bit for bit the undivided render's rows.
    pub fn render_part(
        &mut self,
        scene: &UploadedScene,
        part: &PartRange,
        sampling: &Sampling,
        on_pass: &mut dyn FnMut(&PassInfo),
    ) -> Result<Frame, RenderError> {
        let request = RenderRequest {
            sampling: *sampling,
            part: Some(part.clone()),
            on_pass: Some(on_pass),
            ..RenderRequest::new(scene.width, scene.height)
        };
        self.render_whole(scene, request).map(|r| r.frame)
    }

    /// [`Renderer::render_progressive`] that also returns the arbitrary
    /// output variables of each pixel's first primary ray.
    pub fn render_with_aovs(
        &mut self,
        scene: &UploadedScene,
        width: u32,
        height: u32,
        sampling: &Sampling,
        on_pass: &mut dyn FnMut(&PassInfo),
    ) -> Result<(Frame, Aovs), RenderError> {
        let request = RenderRequest {
            sampling: *sampling,
            aovs: true,
            on_pass: Some(on_pass),
            ..RenderRequest::new(width, height)
        };
        let r = self.render_whole(scene, request)?;
        Ok((r.frame, r.aovs.unwrap_or_default()))
    }

    /// [`Renderer::render_request`] of a request without `cancel`.
    fn render_whole(
        &mut self,
        scene: &UploadedScene,
        request: RenderRequest,
    ) -> Result<Rendered, RenderError> {
        debug_assert!(request.cancel.is_none());
        let done = self.render_request(scene, request)?;
        Ok(done.unwrap_or_else(|| unreachable!("not cancellable")))
    }

    /// Renders an uploaded scene as `request` says: the one render entry
    /// point (the others are shorthands for common requests). With
    /// `cancel`, each tile is dispatched in bands of 64 rows and
    /// `cancel` is asked before each band (`Ok(None)` once it says yes);
    /// without, a tile is one submission (the fast path). With `part`, only
    /// its rows and passes are rendered and the image is their sum
    /// ([`Renderer::render_part`]).
    pub fn render_request(
        &mut self,
        scene: &UploadedScene,
        request: RenderRequest,
    ) -> Result<Option<Rendered>, RenderError> {
        let RenderRequest {
            width,
            height,
            sampling,
            part,
            aovs: with_aovs,
            on_pass,
            mut cancel,
        } = request;
        let sampling = &sampling;
        let mut no_report = |_: &PassInfo| {};
        let on_pass: &mut dyn FnMut(&PassInfo) = match on_pass {
            Some(f) => f,
            None => &mut no_report,
        };
        let part = part.as_ref();
        if let Some(part) = part {
            let h = scene.height;
            if part.rows.start >= part.rows.end || part.rows.end > h {
                return Err(RenderError::Scene {
                    field: "--tile".into(),
                    message: format!("rows {:?} are not within the image's {h} rows", part.rows),
                });
            }
            if part.passes.start >= part.passes.end || part.passes.end > sampling.spp {
                return Err(RenderError::Scene {
                    field: "--passes".into(),
                    message: format!(
                        "passes {}..{} are not within 0..{}",
                        part.passes.start, part.passes.end, sampling.spp
                    ),
                });
            }
        }
        if width == 0 || height == 0 || width > scene.width || height > scene.height {
            return Err(RenderError::Scene {
                field: "camera.width/camera.height".into(),
                message: format!(
                    "{width}x{height} pixels: must be between 1x1 and the uploaded size {}x{}",
                    scene.width, scene.height
                ),
            });
        }
        if sampling.spp == 0 || sampling.spp > MAX_SPP {
            return Err(RenderError::Scene {
                field: "--spp".into(),
                message: format!("must be in 1..={MAX_SPP}, got {}", sampling.spp),
            });
        }
        let mut settings = Settings::new(sampling.spp, with_aovs, scene.light_samples);
        settings.fused_shadows &= self.fuse_shadows;
        let settings = self.with_device(settings);
        // The BVH buffers are empty for a scene uploaded for brute force.
        let key_kernel = KernelOptions {
            accel: scene.kernel.accel,
            ..self.kernel
        };
        let stage_kernel = StageKernel {
            features: scene.features,
            settings,
            options: key_kernel,
        };
        let compiled = self.frame_pipelines(scene, stage_kernel, false)?;
        let rows = part.map_or(0..height, |p| p.rows.clone());
        let (first_pass, end_pass) =
            part.map_or((0, sampling.spp), |p| (p.passes.start, p.passes.end));
        let mut plan = TilePlan::new(
            [width, rows.end - rows.start],
            scene.light_samples,
            scene.features.checker,
            self.stage_memory,
            self.context.limits().max_storage_buffer_range,
        );
        let bytes = width as u64 * (rows.end - rows.start) as u64 * bands::PIXEL_BYTES;
        if bytes > bands::MAX_IMAGE_BYTES {
            return Err(RenderError::Scene {
                field: if part.is_some() { "--tile" } else { "camera.width/camera.height" }.into(),
                message: format!(
                    "rows {}..{} of {width} pixels need a {:.0} MiB image, more than the {} MiB one render holds: use more tiles",
                    rows.start,
                    rows.end,
                    bytes as f64 / 1048576.0,
                    bands::MAX_IMAGE_BYTES >> 20
                ),
            });
        }
        // A test's cap on the bands holds at least 8 rows of AOVs.
        let aov_size = std::mem::size_of::<layout::Aov>() as u64;
        let cap = self.band_bytes.max(width as u64 * 8 * aov_size);
        let max_buffer = self.context.limits().max_storage_buffer_range.min(cap);
        let bands = ImageBands::plan(width, rows.clone(), with_aovs, &mut plan, max_buffer)?;
        let kept = self.stage_buffers_for(plan)?;
        let tiles = bands.tiles(&plan);
        let chunks = plan.chunks();
        let fused = settings.fused_shadows;
        debug_assert!(!fused || chunks.len() == 1);
        // Hit records survive a shading edit: with one tile and one chunk,
        // the buffers still hold this exact frame's hits and visibility.
        let reusable = tiles.len() == 1 && chunks.len() == 1 && end_pass - first_pass == 1;
        let key = |pass_index: u32| HitKey {
            upload: scene.id,
            traversal: self.traversal_generation,
            size: [width, height],
            rows: rows.clone(),
            pass_index,
            seed: sampling.seed,
            kernel: stage_kernel,
        };
        // A render whose image fits one binding writes it into its stage
        // buffers' image; parts and larger images into bands made for them.
        let whole = part.is_none() && bands.rows.len() == 1;
        // The whole render's image: taken out of the stage buffers for the
        // render, put back when it completes (an error drops it, and its
        // frame with it).
        let mut whole_image = None;
        if whole {
            let bytes = width as u64 * height as u64 * bands::PIXEL_BYTES;
            let kept = &mut self.stage_buffers[kept];
            whole_image = kept.image.take().filter(|b| b.size() >= bytes);
            if whole_image.is_none() {
                kept.holds = None;
                whole_image = Some(self.context.create_buffer(
                    "image",
                    BufferUsage::Storage,
                    bytes,
                )?);
            }
        }
        let reuse = self.reuse_hits
            && reusable
            && whole
            && self.stage_buffers[kept].holds.as_ref() == Some(&key(first_pass));
        let holds = reusable.then(|| key(first_pass));
        // Until this render completes, the buffers hold no whole frame.
        self.stage_buffers[kept].holds = None;
        let ctx = &self.context;
        let mut band_buffers = bands.buffers(ctx, whole_image)?;
        let buffers = &self.stage_buffers[kept];
        let mut refs: Vec<_> = scene.bound.iter().map(Bound::resource).collect();
        refs[Binding::HitRecords as usize] = (&buffers.hits).into();
        refs[Binding::Queue as usize] = (&buffers.queue).into();
        refs[Binding::Resolved as usize] = (&buffers.resolved).into();
        refs[Binding::Radiance as usize] = (&buffers.radiance).into();
        let words = [
            (Binding::HitRecordWords, &buffers.hits),
            (Binding::QueueWords, &buffers.queue),
            (Binding::ResolvedWords, &buffers.resolved),
        ];
        for (binding, image) in words {
            if let Some(w) = image.words() {
                refs[binding as usize] = w.into();
            }
        }
        // Each band's bindings: its image rows and AOVs.
        let band_refs: Vec<Vec<Resource>> = band_buffers
            .iter()
            .map(|(image, aovs)| {
                let mut r = refs.clone();
                r[Binding::Image as usize] = image.into();
                r[Binding::ImageWords as usize] = image.into();
                if let Some(b) = aovs {
                    r[Binding::Aovs as usize] = b.into();
                }
                r
            })
            .collect();
        let stage = |s: Stage| &self.stage_pipelines[&(s, stage_kernel)].pipeline;
        let programs: Vec<&ComputePipeline> = scene
            .materials
            .programs
            .iter()
            .map(|p| {
                let variant = shade::variant(&scene.features);
                &self.shade_pipelines[&(p.file.clone(), variant)].pipeline
            })
            .collect();
        let read_counters = || -> Result<[u32; 2], RenderError> {
            let bytes = ctx.read_buffer(scene.bound[Binding::Counters as usize].buffer()?)?;
            Ok([0, 1].map(|i| {
                u32::from_le_bytes(bytes[i * 4..i * 4 + 4].try_into().unwrap_or_default())
            }))
        };
        // The counters wrap; per-pass differences in u64 do not.
        let mut before = read_counters()?;
        let (mut primary_rays, mut shadow_rays) = (0u64, 0u64);
        let mut render = Duration::ZERO;
        let start = Instant::now();
        let mut passes = 0;
        let light_count = scene.light_count();
        // Per pipeline: the engine stages, then the shade programs.
        let engine_stages = Stage::frame(&settings);
        let engine = engine_stages.len();
        let mut stage_times = vec![Duration::ZERO; engine + programs.len()];
        let slots: Vec<SlotName> = engine_stages
            .iter()
            .map(|s| SlotName::Engine(s.name()))
            .chain(scene.materials.programs.iter().map(|p| {
                let user = match &p.file {
                    ProgramFile::User(path) => Some(path.clone()),
                    ProgramFile::Builtin(_) => None,
                };
                SlotName::Program(p.file.label_in(&self.shaders), user)
            }))
            .collect();
        while first_pass + passes < end_pass {
            let base = PushConstants {
                size: [width, height],
                pass_index: first_pass + passes,
                seed: sampling.seed,
                flags: scene.shade_flags | if passes == 0 { FLAG_FRESH } else { 0 },
                light_count,
                ..Zeroable::zeroed()
            };
            // Dispatches not yet submitted, all of one band of the image:
            // without `cancel`, a pass's tiles go in one submission per band.
            let mut pending: Vec<StagePush> = Vec::new();
            let mut pending_band = 0;
            let profile = self.profile_stages;
            let mut flush = |pending: &mut Vec<StagePush>, band: usize| {
                submit(
                    ctx,
                    pending,
                    &band_refs[band],
                    profile,
                    &mut stage_times,
                    &slots,
                )
            };
            for &(origin, size) in &tiles {
                let band = bands.band_of(origin[1]);
                if band != pending_band {
                    render += flush(&mut pending, pending_band)?;
                }
                pending_band = band;
                let base = PushConstants {
                    slot_base: bands.rows[band].start * width,
                    ..base
                };
                // Bands of rows within the tile, to ask `cancel` between
                // submissions (without it, the pass's tiles of one image band
                // go in one submission).
                let band_rows = match cancel {
                    Some(_) => BAND_ROWS,
                    None => size[1],
                };
                for y0 in (origin[1]..origin[1] + size[1]).step_by(band_rows as usize) {
                    if let Some(cancel) = cancel.as_mut() {
                        if cancel() {
                            return Ok(None);
                        }
                    }
                    let rows_here = band_rows.min(origin[1] + size[1] - y0);
                    let groups = [size[0].div_ceil(TILE), rows_here.div_ceil(TILE), 1];
                    let band = PushConstants {
                        origin: [origin[0], y0],
                        tile_origin: origin,
                        tile_width: plan.tile[0],
                        ..base
                    };
                    // With fused shadows the hit stage queues the one
                    // chunk's samples, so it reads the chunk's bounds.
                    if !reuse {
                        let hit = match fused {
                            true => PushConstants {
                                sample_first: chunks[0].0,
                                sample_count: chunks[0].1,
                                ..band
                            },
                            false => band,
                        };
                        pending.push((0, stage(Stage::Hit), hit, groups));
                    }
                    for (c, &(first, count)) in chunks.iter().enumerate() {
                        let last = match c + 1 == chunks.len() {
                            true => FLAG_LAST_CHUNK,
                            false => 0,
                        };
                        let chunk = PushConstants {
                            sample_first: first,
                            sample_count: count,
                            flags: band.flags | last,
                            ..band
                        };
                        if !reuse && !fused {
                            pending.push((1, stage(Stage::Shadow), chunk, groups));
                        }
                        for (i, p) in programs.iter().enumerate() {
                            let push = PushConstants {
                                program: i as u32,
                                ..chunk
                            };
                            pending.push((engine + i, p, push, groups));
                        }
                    }
                    if cancel.is_some() {
                        render += flush(&mut pending, pending_band)?;
                    }
                }
            }
            render += flush(&mut pending, pending_band)?;
            let after = read_counters()?;
            primary_rays += after[0].wrapping_sub(before[0]) as u64;
            shadow_rays += after[1].wrapping_sub(before[1]) as u64;
            before = after;
            passes += 1;
            on_pass(&PassInfo {
                done: passes,
                total: end_pass - first_pass,
                rays: primary_rays + shadow_rays,
                elapsed: start.elapsed(),
            });
            if sampling.time_budget.is_some_and(|b| start.elapsed() >= b) {
                break;
            }
        }
        let holds = holds.filter(|_| passes == 1);
        let (shader_compile, pipeline_creation, driver_compile) =
            (compiled.naga, compiled.pipeline, compiled.driver);

        let t1 = Instant::now();
        let n = width as usize * (rows.end - rows.start) as usize;
        let mut pixels: Vec<[f32; 4]> = Vec::with_capacity(n);
        let mut aov_bytes = Vec::new();
        for ((image, aovs), band) in band_buffers.iter().zip(&bands.rows) {
            let texels = width as usize * (band.end - band.start) as usize;
            let at = pixels.len();
            pixels.resize(at + texels, [0.0; 4]);
            ctx.read_buffer_into(image, bytemuck::cast_slice_mut(&mut pixels[at..]))?;
            if let Some(b) = aovs {
                let size = texels * std::mem::size_of::<layout::Aov>();
                aov_bytes.extend_from_slice(&ctx.read_buffer(b)?[..size]);
            }
        }
        if passes > 1 && part.is_none() {
            let inv = 1.0 / passes as f32;
            for p in &mut pixels {
                *p = p.map(|c| c * inv);
            }
        }
        let aovs = with_aovs.then(|| Aovs::from_gpu(&aov_bytes, n, scene));
        let readback = t1.elapsed();
        ctx.check_validation()?;
        if whole {
            self.stage_buffers[kept].image = Some(band_buffers.swap_remove(0).0);
        }
        self.stage_buffers[kept].holds = holds;

        let stage_times = match self.profile_stages {
            false => Vec::new(),
            true => engine_stages
                .iter()
                .map(|s| s.name().to_string())
                .chain(
                    scene
                        .materials
                        .programs
                        .iter()
                        .map(|p| format!("shade {}", p.file.label())),
                )
                .zip(stage_times)
                .collect(),
        };
        Ok(Some(Rendered {
            frame: Frame {
                stage_times,
                image: Image {
                    width,
                    height: rows.end - rows.start,
                    pixels,
                },
                stats: RenderStats {
                    primary_rays,
                    shadow_rays,
                    passes,
                    bvh_nodes: scene.bvh_nodes,
                    bvh_depth: scene.bvh_depth,
                    bvh_bytes: scene.bvh_bytes,
                    texture_bytes: scene.texture_bytes,
                    hits_reused: reuse,

                    tiles: tiles.len(),
                    stage_bytes: plan.bytes(),
                    timings: Timings {
                        shader_compile,
                        pipeline_creation,
                        driver_compile,
                        accel_build: Duration::ZERO,
                        upload: Duration::ZERO,
                        render,
                        readback,
                    },
                },
            },
            aovs,
        }))
    }

    /// Renders an uploaded scene at `width`×`height` (one sample per pixel)
    /// in bands of rows, asking `cancel` between bands; returns `None` as
    /// soon as it says so. Hot reload uses it so that a newer edit stops the
    /// refinement in flight.
    pub fn render_cancellable(
        &mut self,
        scene: &UploadedScene,
        width: u32,
        height: u32,
        cancel: &mut dyn FnMut() -> bool,
    ) -> Result<Option<Frame>, RenderError> {
        let request = RenderRequest {
            cancel: Some(cancel),
            ..RenderRequest::new(width, height)
        };
        Ok(self.render_request(scene, request)?.map(|r| r.frame))
    }

    /// Renders one frame of a validated scene: [`Renderer::upload`] then
    /// [`Renderer::render_uploaded`] at the scene's size.
    pub fn render(&mut self, scene: &Scene) -> Result<Frame, RenderError> {
        let uploaded = self.upload(scene)?;
        let mut frame = self.render_uploaded(&uploaded, uploaded.width, uploaded.height)?;
        frame.stats.timings.accel_build = uploaded.accel_build;
        frame.stats.timings.upload = uploaded.upload;
        Ok(frame)
    }
}

/// Fills in each leaf node's program and first parameter word.
fn set_leaves(nodes: &mut [layout::ShaderNode], materials: &Materials) {
    for (node, leaf) in nodes.iter_mut().zip(&materials.leaves) {
        if let Some((program, params)) = leaf {
            node.program = *program;
            node.params = *params;
        }
    }
}

/// Each light's colours for the shade stage, three texels a light:
/// (diffuse, intensity), (specular, sample count), (ambient, 0), as bits
/// (the count as an integer: the shade stage finds each queued sample's
/// light from it).
fn light_colours(lights: &[layout::Light]) -> Vec<[u32; 4]> {
    let bits = |c: [f32; 3], w: u32| [c[0].to_bits(), c[1].to_bits(), c[2].to_bits(), w];
    lights
        .iter()
        .flat_map(|l| {
            [
                bits(l.diffuse, l.intensity.to_bits()),
                bits(l.specular, l.samples),
                bits(l.ambient, 0),
            ]
        })
        .collect()
}

#[cfg(test)]
mod tests {
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
