//! Shader hot reload (`penumbra watch`): recompile the kernel after a shader
//! edit without losing the last good one when the edit does not compile.

use std::time::Duration;

use super::{KernelOptions, RenderError, Renderer, UploadedScene};

impl Renderer {
    /// Recompiles the kernel for `scene` from the current shader files (call
    /// it after a shader edit; the scene upload is kept). On success the new
    /// kernel replaces every cached one and the time of (naga, pipeline
    /// creation, driver compile) is returned; on failure the cache keeps the
    /// last good kernels, so the next render still works.
    pub fn reload_shaders(
        &mut self,
        scene: &UploadedScene,
    ) -> Result<(Duration, Duration, Duration), RenderError> {
        let old = std::mem::take(&mut self.pipelines);
        let kernel = KernelOptions {
            accel: scene.kernel.accel,
            ..self.kernel
        };
        let saved = std::mem::replace(&mut self.kernel, kernel);
        let compiled = self.pipeline(scene.features);
        self.kernel = saved;
        if compiled.is_err() {
            self.pipelines = old;
        }
        compiled
    }
}
