//! The passes of a frame, as pbrt-v4's wavefront integrator runs its
//! stages: for each pass and each tile (in bands of rows when the render can
//! be cancelled), trace the camera rays (the hit stage), trace the shadow
//! rays of each chunk of light samples (the shadow stage, unless the hit
//! stage traced them), and shade (one pipeline per shader file); then count
//! the rays of the pass.

use std::time::{Duration, Instant};

use bytemuck::Zeroable;

use super::bindings::Bindings;
use super::frame_plan::FramePlan;
use super::layout::{PushConstants, FLAG_FRESH, FLAG_LAST_CHUNK};
use super::shade::{self, ProgramFile};
use super::stages::{Binding, Stage};
use super::{PassInfo, RenderError, Renderer, Sampling, UploadedScene, BAND_ROWS, TILE};
use crate::vulkan::{Buffer, ComputePipeline, Context, Dispatch, Resource, VulkanError};
use std::path::PathBuf;

/// What the caller asked to hear of a render, and to stop it.
pub(super) struct Hooks<'p, 'c> {
    pub(super) on_pass: &'p mut dyn FnMut(&PassInfo),
    pub(super) cancel: Option<&'c mut dyn FnMut() -> bool>,
}

impl Hooks<'_, '_> {
    /// Whether the caller asks to stop now.
    fn cancelled(&mut self) -> bool {
        self.cancel.as_mut().is_some_and(|c| c())
    }
}

/// What the passes did.
pub(super) struct PassTotals {
    pub(super) passes: u32,
    pub(super) primary_rays: u64,
    pub(super) shadow_rays: u64,
    /// Time the device spent on the passes' submissions.
    pub(super) render: Duration,
    /// Per slot of [`FrameStages::slots`], when stages are profiled.
    pub(super) stage_times: Vec<Duration>,
}

/// The pipelines of a frame, and the slot of each in the stage times: the
/// engine stages the settings run, then the shade programs.
pub(super) struct FrameStages<'a> {
    hit: &'a ComputePipeline,
    shadow: Option<&'a ComputePipeline>,
    programs: Vec<&'a ComputePipeline>,
    slots: Vec<SlotName>,
    engine: &'static [Stage],
}

impl<'a> FrameStages<'a> {
    fn new(renderer: &'a Renderer, scene: &UploadedScene, plan: &FramePlan) -> FrameStages<'a> {
        let engine = Stage::frame(&plan.settings);
        let stage = |s: Stage| &renderer.stage_pipelines[&(s, plan.kernel)].pipeline;
        let variant = shade::variant(&scene.features);
        let programs = scene.materials.programs.iter();
        FrameStages {
            hit: stage(Stage::Hit),
            shadow: engine
                .contains(&Stage::Shadow)
                .then(|| stage(Stage::Shadow)),
            programs: programs
                .clone()
                .map(|p| &renderer.shade_pipelines[&(p.file.clone(), variant)].pipeline)
                .collect(),
            slots: engine
                .iter()
                .map(|s| SlotName::Engine(s.name()))
                .chain(programs.map(|p| {
                    let user = match &p.file {
                        ProgramFile::User(path) => Some(path.clone()),
                        ProgramFile::Builtin(_) => None,
                    };
                    SlotName::Program(p.file.label_in(&renderer.shaders), user)
                }))
                .collect(),
            engine,
        }
    }

    /// The slot of engine stage `stage` (one the frame runs).
    fn slot(&self, stage: Stage) -> usize {
        self.engine.iter().position(|&s| s == stage).unwrap_or(0)
    }
}

/// The names of the stage-time slots of `scene`'s frames with `plan`.
pub(super) fn slot_names(scene: &UploadedScene, plan: &FramePlan) -> Vec<String> {
    Stage::frame(&plan.settings)
        .iter()
        .map(|s| s.name().to_string())
        .chain(
            scene
                .materials
                .programs
                .iter()
                .map(|p| format!("shade {}", p.file.label())),
        )
        .collect()
}

/// Dispatches recorded but not yet submitted, all of one band of the image.
struct Queue<'q, 'a> {
    pending: Vec<StagePush<'a>>,
    band: usize,
    ctx: &'q Context,
    band_refs: &'q [Bindings<Resource<'q>>],
    stages: &'q FrameStages<'a>,
    profile: bool,
}

impl<'a> Queue<'_, 'a> {
    /// The hit stage: camera rays and their closest hits (and, with fused
    /// shadows, the shadow rays of the one chunk `first_chunk`).
    fn trace_camera_rays(
        &mut self,
        block: PushConstants,
        fused: Option<(u32, u32)>,
        groups: [u32; 3],
    ) {
        let push = match fused {
            Some((first, count)) => PushConstants {
                sample_first: first,
                sample_count: count,
                ..block
            },
            None => block,
        };
        let slot = self.stages.slot(Stage::Hit);
        self.pending.push((slot, self.stages.hit, push, groups));
    }

    /// The shadow stage: light samples and their shadow rays, for one chunk.
    fn trace_shadow_rays(&mut self, chunk: PushConstants, groups: [u32; 3]) {
        if let Some(shadow) = self.stages.shadow {
            let slot = self.stages.slot(Stage::Shadow);
            self.pending.push((slot, shadow, chunk, groups));
        }
    }

    /// The shade stage: every shade program over the chunk's samples.
    fn shade(&mut self, chunk: PushConstants, groups: [u32; 3]) {
        let engine = self.stages.engine.len();
        for (i, &p) in self.stages.programs.iter().enumerate() {
            let push = PushConstants {
                program: i as u32,
                ..chunk
            };
            self.pending.push((engine + i, p, push, groups));
        }
    }

    /// Submits what is pending and waits for it.
    fn flush(&mut self, stage_times: &mut [Duration]) -> Result<Duration, RenderError> {
        submit(
            self.ctx,
            &mut self.pending,
            self.band_refs[self.band].in_binding_order(),
            self.profile,
            stage_times,
            &self.stages.slots,
        )
    }

    /// Moves on to `band`, submitting what another band left pending.
    fn enter_band(
        &mut self,
        band: usize,
        stage_times: &mut [Duration],
    ) -> Result<Duration, RenderError> {
        let t = match band != self.band {
            true => self.flush(stage_times)?,
            false => Duration::ZERO,
        };
        self.band = band;
        Ok(t)
    }
}

impl Renderer {
    /// Runs the passes of `plan` into `band_buffers` (each band's image and
    /// AOVs). Stops after the pass in flight once the time budget is spent;
    /// [`RenderError::Cancelled`] as soon as `hooks.cancel` says so.
    pub(super) fn run_passes(
        &self,
        scene: &UploadedScene,
        plan: &FramePlan,
        band_buffers: &[(Buffer, Option<Buffer>)],
        sampling: &Sampling,
        hooks: &mut Hooks<'_, '_>,
    ) -> Result<PassTotals, RenderError> {
        let ctx = &self.context;
        let band_refs = self.band_bindings(scene, plan, band_buffers);
        let stages = FrameStages::new(self, scene, plan);
        let tiles = plan.bands.tiles(&plan.tiles);
        let chunks = plan.tiles.chunks();
        let fused = plan.settings.fused_shadows;
        debug_assert!(!fused || chunks.len() == 1);
        let mut totals = PassTotals {
            passes: 0,
            primary_rays: 0,
            shadow_rays: 0,
            render: Duration::ZERO,
            stage_times: vec![Duration::ZERO; stages.slots.len()],
        };
        // The counters wrap; per-pass differences in u64 do not.
        let mut before = read_counters(ctx, scene)?;
        let start = Instant::now();
        while plan.passes.start + totals.passes < plan.passes.end {
            let pass = PushConstants {
                size: [plan.width, plan.height],
                pass_index: plan.passes.start + totals.passes,
                seed: sampling.seed,
                flags: scene.shade_flags | if totals.passes == 0 { FLAG_FRESH } else { 0 },
                light_count: scene.light_count(),
                ..Zeroable::zeroed()
            };
            // Without `cancel`, a pass's tiles of one band of the image go
            // in one submission.
            let mut queue = Queue {
                pending: Vec::new(),
                band: 0,
                ctx,
                band_refs: &band_refs,
                stages: &stages,
                profile: self.profile_stages,
            };
            for &(origin, size) in &tiles {
                let band = plan.bands.band_of(origin[1]);
                totals.render += queue.enter_band(band, &mut totals.stage_times)?;
                let pass = PushConstants {
                    slot_base: plan.bands.rows[band].start * plan.width,
                    ..pass
                };
                // Bands of rows within the tile, to ask `cancel` between
                // submissions.
                let band_rows = match hooks.cancel {
                    Some(_) => BAND_ROWS,
                    None => size[1],
                };
                for y0 in (origin[1]..origin[1] + size[1]).step_by(band_rows as usize) {
                    if hooks.cancelled() {
                        return Err(RenderError::Cancelled);
                    }
                    let rows_here = band_rows.min(origin[1] + size[1] - y0);
                    let groups = [size[0].div_ceil(TILE), rows_here.div_ceil(TILE), 1];
                    let block = PushConstants {
                        origin: [origin[0], y0],
                        tile_origin: origin,
                        tile_width: plan.tiles.tile[0],
                        ..pass
                    };
                    if !plan.reuse {
                        queue.trace_camera_rays(block, fused.then_some(chunks[0]), groups);
                    }
                    for (c, &(first, count)) in chunks.iter().enumerate() {
                        let chunk = PushConstants {
                            sample_first: first,
                            sample_count: count,
                            flags: block.flags
                                | if c + 1 == chunks.len() {
                                    FLAG_LAST_CHUNK
                                } else {
                                    0
                                },
                            ..block
                        };
                        if !plan.reuse && !fused {
                            queue.trace_shadow_rays(chunk, groups);
                        }
                        queue.shade(chunk, groups);
                    }
                    if hooks.cancel.is_some() {
                        totals.render += queue.flush(&mut totals.stage_times)?;
                    }
                }
            }
            totals.render += queue.flush(&mut totals.stage_times)?;
            let after = read_counters(ctx, scene)?;
            totals.primary_rays += after[0].wrapping_sub(before[0]) as u64;
            totals.shadow_rays += after[1].wrapping_sub(before[1]) as u64;
            before = after;
            totals.passes += 1;
            (hooks.on_pass)(&PassInfo {
                done: totals.passes,
                total: plan.passes.end - plan.passes.start,
                rays: totals.primary_rays + totals.shadow_rays,
                elapsed: start.elapsed(),
            });
            if sampling.time_budget.is_some_and(|b| start.elapsed() >= b) {
                break;
            }
        }
        Ok(totals)
    }

    /// Each band's bindings: the scene's, with the tile's stage buffers, and
    /// the band's image rows and AOVs.
    fn band_bindings<'a>(
        &'a self,
        scene: &'a UploadedScene,
        plan: &FramePlan,
        band_buffers: &'a [(Buffer, Option<Buffer>)],
    ) -> Vec<Bindings<Resource<'a>>> {
        let buffers = &self.stage_buffers[plan.kept];
        let mut refs = scene.bound.resources();
        refs.set(Binding::HitRecords, (&buffers.hits).into());
        refs.set(Binding::Queue, (&buffers.queue).into());
        refs.set(Binding::Resolved, (&buffers.resolved).into());
        refs.set(Binding::Radiance, (&buffers.radiance).into());
        let words = [
            (Binding::HitRecordWords, &buffers.hits),
            (Binding::QueueWords, &buffers.queue),
            (Binding::ResolvedWords, &buffers.resolved),
        ];
        for (binding, image) in words {
            if let Some(w) = image.words() {
                refs.set(binding, w.into());
            }
        }
        band_buffers
            .iter()
            .map(|(image, aovs)| {
                let mut r = refs.clone();
                r.set(Binding::Image, image.into());
                r.set(Binding::ImageWords, image.into());
                if let Some(b) = aovs {
                    r.set(Binding::Aovs, b.into());
                }
                r
            })
            .collect()
    }
}

/// The ray counters (primary, shadow) as the device holds them.
fn read_counters(ctx: &Context, scene: &UploadedScene) -> Result<[u32; 2], RenderError> {
    let bytes = ctx.read_buffer(scene.bound.buffer(Binding::Counters)?)?;
    Ok([0, 1].map(|i| u32::from_le_bytes(bytes[i * 4..i * 4 + 4].try_into().unwrap_or_default())))
}

/// One dispatch of a frame: its slot in the stage times, the pipeline, its
/// push constants and its workgroups.
pub(super) type StagePush<'a> = (usize, &'a ComputePipeline, PushConstants, [u32; 3]);

/// Records `pending` with the bindings `refs` in one submission, waits for
/// it and empties `pending`, or, when `profile` is set, submits and times
/// each dispatch on its own (adding each to its slot of `stage_times`).
/// Returns the time spent (zero when nothing was pending).
pub(super) fn submit(
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
pub(super) enum SlotName {
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
