//! The plan of one render: the request checked against the uploaded scene,
//! the stages' settings and pipelines, the tiles and bands of rows, the
//! stage buffers, and whether the hits they hold can be reused.

use std::ops::Range;

use super::bands::{self, ImageBands};
use super::layout;
use super::pipelines::Compiled;
use super::stage_buffers::HitKey;
use super::tiles::TilePlan;
use super::{
    KernelOptions, RenderError, RenderRequest, Renderer, Settings, StageKernel, UploadedScene,
};
use crate::vulkan::{Buffer, BufferUsage};

/// Everything a render decides before its first dispatch.
pub(super) struct FramePlan {
    /// Image size, pixels.
    pub(super) width: u32,
    pub(super) height: u32,
    /// The rows rendered (all of them, or a part's).
    pub(super) rows: Range<u32>,
    /// The pass indices rendered (all of `spp`, or a part's).
    pub(super) passes: Range<u32>,
    /// Whether the image is a part's sum of passes (not their mean).
    pub(super) is_part: bool,
    pub(super) with_aovs: bool,
    pub(super) settings: Settings,
    /// The engine stages' key in the pipeline cache.
    pub(super) kernel: StageKernel,
    /// Compile times of the pipelines this render built.
    pub(super) compiled: Compiled,
    /// Tiles, chunks of light samples and stage memory.
    pub(super) tiles: TilePlan,
    /// The bands of rows the image is kept in.
    pub(super) bands: ImageBands,
    /// Which of the renderer's kept stage buffers the render uses.
    pub(super) kept: usize,
    /// Whether the image is one band that the stage buffers keep between
    /// renders ([`super::stage_buffers::StageBuffers::image`]).
    pub(super) whole: bool,
    /// Whether the hit stage is skipped: the stage buffers hold this exact
    /// frame's hits and visibility.
    pub(super) reuse: bool,
    /// What the stage buffers will hold once the render completes.
    pub(super) holds: Option<HitKey>,
}

/// Checks `request` against the uploaded scene, naming the option or field.
pub(super) fn check_request(
    scene: &UploadedScene,
    request: &RenderRequest,
) -> Result<(), RenderError> {
    let (width, height) = (request.width, request.height);
    let sampling = &request.sampling;
    if let Some(part) = &request.part {
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
    sampling.check().map_err(|message| RenderError::Scene {
        field: "--spp".into(),
        message,
    })
}

impl Renderer {
    /// Plans the render of `request` (checked by [`check_request`]):
    /// settings, pipelines (compiled unless cached), tiles and bands, stage
    /// buffers, hit reuse. Returns the plan and, for a whole image kept
    /// between renders, its buffer.
    pub(super) fn plan_frame(
        &mut self,
        scene: &UploadedScene,
        request: &RenderRequest,
    ) -> Result<(FramePlan, Option<Buffer>), RenderError> {
        let (width, height) = (request.width, request.height);
        let sampling = &request.sampling;
        let part = request.part.as_ref();
        let with_aovs = request.aovs;
        let kernel = self.stage_kernel(scene, sampling.spp, with_aovs);
        let settings = kernel.settings;
        let compiled = self.frame_pipelines(scene, kernel, false)?;
        let rows = part.map_or(0..height, |p| p.rows.clone());
        let passes = part.map_or(0..sampling.spp, |p| p.passes.clone());
        let (tiles, bands) =
            self.plan_tiles(scene, width, rows.clone(), part.is_some(), with_aovs)?;
        let kept = self.stage_buffers_for(tiles)?;
        // Hit records survive a shading edit: with one tile and one chunk,
        // the buffers still hold this exact frame's hits and visibility.
        let reusable = bands.tiles(&tiles).len() == 1
            && tiles.chunks().len() == 1
            && passes.end - passes.start == 1;
        let key = HitKey {
            upload: scene.id,
            traversal: self.traversal_generation,
            size: [width, height],
            rows: rows.clone(),
            pass_index: passes.start,
            seed: sampling.seed,
            kernel,
        };
        // A render whose image fits one binding writes it into its stage
        // buffers' image; parts and larger images into bands made for them.
        let whole = part.is_none() && bands.rows.len() == 1;
        let whole_image = match whole {
            true => Some(self.whole_image(kept, width, height)?),
            false => None,
        };
        let reuse = self.reuse_hits
            && reusable
            && whole
            && self.stage_buffers[kept].holds.as_ref() == Some(&key);
        // Until this render completes, the buffers hold no whole frame.
        self.stage_buffers[kept].holds = None;
        let plan = FramePlan {
            width,
            height,
            rows,
            passes,
            is_part: part.is_some(),
            with_aovs,
            settings,
            kernel,
            compiled,
            tiles,
            bands,
            kept,
            whole,
            reuse,
            holds: reusable.then_some(key),
        };
        Ok((plan, whole_image))
    }

    /// The key of the engine stages a render of `scene` with `spp` passes
    /// runs: the scene's features, the settings (with what this renderer
    /// and its device decide) and the kernel options. The one place that
    /// decides it, for renders and for reloads.
    pub(super) fn stage_kernel(
        &self,
        scene: &UploadedScene,
        spp: u32,
        with_aovs: bool,
    ) -> StageKernel {
        let mut settings = Settings::new(spp, with_aovs, scene.light_samples);
        settings.fused_shadows &= self.fuse_shadows;
        StageKernel {
            features: scene.features,
            settings: self.with_device(settings),
            // The BVH buffers are empty for a scene uploaded for brute force,
            // its words for one uploaded for the per-lane traversal.
            options: KernelOptions {
                accel: scene.kernel.accel,
                traversal: scene.kernel.traversal,
                ..self.kernel
            },
        }
    }

    /// The tiles of `rows` of an image `width` pixels wide within the stage
    /// memory, and the bands of rows its image is kept in.
    fn plan_tiles(
        &self,
        scene: &UploadedScene,
        width: u32,
        rows: Range<u32>,
        is_part: bool,
        with_aovs: bool,
    ) -> Result<(TilePlan, ImageBands), RenderError> {
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
                field: if is_part { "--tile" } else { "camera.width/camera.height" }.into(),
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
        let bands = ImageBands::plan(width, rows, with_aovs, &mut plan, max_buffer)?;
        Ok((plan, bands))
    }

    /// The image of a whole render, taken out of stage buffers `kept` (put
    /// back when the render completes; an error drops it, and its frame
    /// with it), or a new one.
    fn whole_image(&mut self, kept: usize, width: u32, height: u32) -> Result<Buffer, RenderError> {
        let bytes = width as u64 * height as u64 * bands::PIXEL_BYTES;
        let kept = &mut self.stage_buffers[kept];
        if let Some(image) = kept.image.take().filter(|b| b.size() >= bytes) {
            return Ok(image);
        }
        kept.holds = None;
        Ok(self
            .context
            .create_buffer("image", BufferUsage::Storage, bytes)?)
    }
}
