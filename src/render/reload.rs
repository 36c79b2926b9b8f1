//! Shader hot reload (`penumbra watch`): recompile only the pipelines whose
//! shader files changed, without losing the last good ones when an edit
//! does not compile.

use std::time::Duration;

use super::shade::{Materials, UserTexts};
use super::{RenderError, Renderer, UploadedScene};

/// What a reload recompiled and what it cost.
#[derive(Clone, Debug, Default)]
pub struct ReloadReport {
    /// The pipelines recompiled: engine stages by name (`hit`, `shadow`, …),
    /// shade pipelines as `shade <file>`. Empty when nothing changed.
    pub recompiled: Vec<String>,
    /// naga: WGSL to SPIR-V.
    pub shader_compile: Duration,
    /// vkCreateComputePipelines.
    pub pipeline_creation: Duration,
    /// The driver's compile at the first (warm-up) dispatch.
    pub driver_compile: Duration,
}

impl Renderer {
    /// Reads the engine's shader files again after an edit, takes the user's
    /// shader files as `user` holds them (the loader read them again through
    /// its guard: [`crate::loaders::read_shader_file`];
    /// [`UploadedScene::user_shader_files`] lists them), and recompiles the
    /// pipelines `scene` needs whose files changed (the scene upload is
    /// kept; hit records are kept too when only shade pipelines changed).
    /// On failure the pipelines that failed keep their last good versions,
    /// so the next render still works; [`RenderError::ParamsChanged`] says
    /// that the scene must be loaded again. After a successful reload,
    /// renders of `scene` at the size, seed and sample of a previous render
    /// reuse its hit records when no stage before shading changed
    /// ([`super::RenderStats::hits_reused`]).
    pub fn reload_shaders(
        &mut self,
        scene: &mut UploadedScene,
        user: &UserTexts,
    ) -> Result<ReloadReport, RenderError> {
        // The shader files' texts (and Params) as they are now.
        let materials = Materials::new(
            &scene.shaders,
            &scene.texture_uses,
            &self.shaders,
            Some(user),
        )?;
        // The parameter words were uploaded for the Params the files had.
        for (new, old) in materials.programs.iter().zip(&scene.materials.programs) {
            if new.fields != old.fields {
                return Err(RenderError::ParamsChanged {
                    file: new.file.label(),
                });
            }
        }
        self.reuse_hits = false;
        let old = std::mem::replace(&mut scene.materials, materials);
        // Watch renders one sample per pixel without AOVs.
        let key = self.stage_kernel(scene, 1, false);
        match self.frame_pipelines(scene, key, true) {
            Ok(c) => {
                // The next renders of this upload may reuse their hits (the
                // key keeps them from doing so if a traversal stage changed).
                self.reuse_hits = true;
                Ok(ReloadReport {
                    recompiled: c.names,
                    shader_compile: c.naga,
                    pipeline_creation: c.pipeline,
                    driver_compile: c.driver,
                })
            }
            Err(e) => {
                scene.materials = old;
                Err(e)
            }
        }
    }
}
