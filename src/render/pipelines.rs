//! The pipeline caches: engine stages by stage and kernel, shade programs
//! by file and feature variant, each compiled once per text of its files,
//! and made ready with a first dispatch (lavapipe compiles then).

use std::path::Path;
use std::time::{Duration, Instant};

use bytemuck::Zeroable;

use super::bindings::Bound;
use super::layout::{PushConstants, FLAG_WARM_UP};
use super::shade::{self, ProgramFile};
use super::stages::{self, Stage};
use super::{RenderError, Renderer, Settings, StageKernel, UploadedScene};
use crate::scene::Features;
use crate::vulkan::{BindingType, BufferUsage, ComputePipeline, VulkanError, DRIVER_COMPILE_LIMIT};

/// A compiled pipeline and the hash of the source it was compiled from
/// (for a shade pipeline also of the shader file's own text).
pub(super) struct Cached {
    pub(super) pipeline: ComputePipeline,
    pub(super) hash: u64,
    pub(super) file_hash: u64,
}

/// Compile times of the pipelines built for a frame, and their names.
#[derive(Clone, Debug, Default)]
pub(super) struct Compiled {
    pub(super) naga: Duration,
    pub(super) pipeline: Duration,
    pub(super) driver: Duration,
    pub(super) names: Vec<String>,
    /// Each pipeline's driver compile (its first dispatch), by name.
    pub(super) driver_each: Vec<(String, Duration)>,
}

impl Compiled {
    pub(super) fn add(&mut self, other: Compiled) {
        self.naga += other.naga;
        self.pipeline += other.pipeline;
        self.driver += other.driver;
        self.names.extend(other.names);
        self.driver_each.extend(other.driver_each);
    }
}

pub(super) fn text_hash(parts: &[&str]) -> u64 {
    use std::hash::{Hash, Hasher};
    let mut h = std::collections::hash_map::DefaultHasher::new();
    parts.hash(&mut h);
    h.finish()
}

impl Renderer {
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
    pub(super) fn build_pipeline(
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
    pub(super) fn stage_pipeline(
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
            driver_each: vec![(stage.name().to_string(), driver)],
        })
    }

    /// Compiles the shade pipeline of `program` unless the cache holds one
    /// compiled from the same text.
    pub(super) fn shade_pipeline(
        &mut self,
        program: &shade::Program,
        variant: Features,
    ) -> Result<Compiled, RenderError> {
        let t0 = Instant::now();
        let source = shade::assemble(&self.shaders, &program.file, &program.text)?;
        if source.fields != program.fields {
            return Err(RenderError::ParamsChanged {
                file: program.file.label(),
            });
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
            driver_each: vec![(format!("shade {}", program.file.label()), driver)],
        })
    }

    /// Every pipeline a frame of `scene` needs, compiled unless cached (with
    /// `reload`: recompiled where the files' text changed).
    pub(super) fn frame_pipelines(
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
}
