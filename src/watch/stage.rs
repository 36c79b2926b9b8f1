//! What a reload rebuilds, and the staged render: a preview at reduced
//! resolution first, then the full image, with a check for newer edits
//! between the stages (a newer edit cancels the refinement).
//!
//! The session keeps the last good state: a scene that fails to load or
//! upload keeps the previous upload, a shader that fails to compile keeps the
//! previous kernel ([`Renderer::reload_shaders`]), and a failed render writes
//! nothing, so the output always holds the last good image.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use crate::loaders::{self, LoadOptions};
use crate::render::{Image, RenderError, Renderer, UploadedScene};

/// What changed since the last reload.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Changes {
    /// A shader source.
    pub shaders: bool,
    /// The scene file or a file it references.
    pub scene: bool,
}

/// Kernel compile times: naga (WGSL to SPIR-V), pipeline creation, and the
/// driver's own compile at the first dispatch.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct CompileTimes {
    /// naga.
    pub naga: Duration,
    /// vkCreateComputePipelines.
    pub pipeline: Duration,
    /// lavapipe's compile to machine code.
    pub driver: Duration,
    /// The pipelines recompiled ([`crate::render::ReloadReport::recompiled`]):
    /// a shading edit recompiles only its file's shade pipeline.
    pub recompiled: Vec<String>,
}

impl CompileTimes {
    /// All three.
    pub fn total(&self) -> Duration {
        self.naga + self.pipeline + self.driver
    }
}

/// What rebuilding after a change did.
#[derive(Debug, Default)]
pub struct Applied {
    /// Kernel compile time, when the kernel was recompiled.
    pub compile: Option<CompileTimes>,
    /// Time to load and upload the scene, when it was reloaded.
    pub upload: Option<Duration>,
    /// Errors, each ready to print (file:line:col, source line, caret).
    pub errors: Vec<String>,
    /// Whether there is something new to render.
    pub render: bool,
}

/// One rendered stage.
#[derive(Clone, Debug)]
pub struct StageFrame {
    /// The image, at the stage's resolution.
    pub image: Image,
    /// Compile time spent in this stage (a kernel not yet in the cache).
    pub compile: CompileTimes,
    /// The render dispatch and the readback.
    pub render: Duration,
}

/// The renderer, the scene upload and the errors of the current files.
pub struct Session {
    renderer: Renderer,
    scene_path: PathBuf,
    load: LoadOptions,
    uploaded: Option<UploadedScene>,
    /// Every file the last good scene read.
    scene_files: Vec<PathBuf>,
    /// The shaders on disk do not compile (the last good kernel is in use).
    pub shader_error: Option<String>,
    /// The scene on disk does not load (the last good upload is in use).
    pub scene_error: Option<String>,
}

impl Session {
    /// A session on an open renderer; nothing is loaded yet.
    pub fn new(renderer: Renderer, scene_path: &Path, load: LoadOptions) -> Session {
        Session {
            renderer,
            scene_path: scene_path.to_path_buf(),
            load,
            uploaded: None,
            scene_files: vec![scene_path.to_path_buf()],
            shader_error: None,
            scene_error: None,
        }
    }

    /// The files the last good scene read (the scene file alone before the
    /// first good load).
    pub fn scene_files(&self) -> &[PathBuf] {
        &self.scene_files
    }

    /// The full image size of the current upload.
    pub fn size(&self) -> Option<(u32, u32)> {
        self.uploaded.as_ref().map(UploadedScene::size)
    }

    /// Rebuilds what `changes` invalidates: reloads and re-uploads the scene
    /// (the kernel cache keys on the scene's features, so a scene edit that
    /// keeps them keeps the pipeline), and recompiles the kernel after a
    /// shader edit (keeping the upload).
    pub fn apply(&mut self, changes: Changes) -> Applied {
        let mut out = Applied::default();
        if changes.scene {
            let t0 = Instant::now();
            match loaders::load_scene(&self.scene_path, &self.load) {
                Err(e) => self.scene_error = Some(format!("scene error: {e}")),
                Ok(loaded) => match self.renderer.upload(&loaded.scene) {
                    Err(e) => {
                        self.scene_error = Some(format!("{}: {e}", self.scene_path.display()))
                    }
                    Ok(up) => {
                        self.uploaded = Some(up);
                        self.scene_files = loaded.files;
                        self.scene_error = None;
                        out.upload = Some(t0.elapsed());
                        out.render = true;
                    }
                },
            }
            out.errors.extend(self.scene_error.clone());
        }
        if changes.shaders {
            match &mut self.uploaded {
                Some(up) => match self.renderer.reload_shaders(up) {
                    Ok(report) => {
                        self.shader_error = None;
                        out.compile = Some(CompileTimes {
                            naga: report.shader_compile,
                            pipeline: report.pipeline_creation,
                            driver: report.driver_compile,
                            recompiled: report.recompiled,
                        });
                        out.render = true;
                    }
                    Err(e) => self.shader_error = Some(e.to_string()),
                },
                // Nothing to compile for yet: the first render compiles.
                None => {
                    self.renderer.clear_pipeline_cache();
                    self.shader_error = None;
                    out.render = self.scene_error.is_none();
                }
            }
            out.errors.extend(self.shader_error.clone());
        } else if changes.scene && out.render && self.shader_error.is_some() {
            // A scene edit while the shaders on disk are broken renders with
            // the last good kernel; say so.
            out.errors.extend(self.shader_error.clone());
        }
        out
    }

    /// Renders the stages, largest divisor first (e.g. `[4, 1]`: a quarter
    /// resolution preview, then the full image), handing each to `write`.
    /// Before each stage after the first, and between the bands of rows of
    /// those stages, `cancel()` is asked whether a newer edit arrived; then
    /// the rest is skipped and `Ok(true)` returned.
    pub fn render_stages(
        &mut self,
        divisors: &[u32],
        mut cancel: impl FnMut() -> bool,
        mut write: impl FnMut(StageFrame),
    ) -> Result<bool, String> {
        let Some(up) = &self.uploaded else {
            return Err(self
                .scene_error
                .clone()
                .unwrap_or_else(|| "no scene loaded".into()));
        };
        let (w, h) = up.size();
        for (i, d) in divisors.iter().enumerate() {
            if i > 0 && cancel() {
                return Ok(true);
            }
            let (sw, sh) = ((w / d).max(1), (h / d).max(1));
            // The first stage (the preview) always completes; later ones stop
            // between bands of rows as soon as a newer edit arrives.
            let result = if i == 0 {
                self.renderer.render_uploaded(up, sw, sh).map(Some)
            } else {
                self.renderer.render_cancellable(up, sw, sh, &mut cancel)
            };
            match result {
                Ok(None) => return Ok(true),
                Ok(Some(frame)) => {
                    let t = frame.stats.timings;
                    let c = CompileTimes {
                        naga: t.shader_compile,
                        pipeline: t.pipeline_creation,
                        driver: t.driver_compile,
                        recompiled: Vec::new(),
                    };
                    if c.total() > Duration::ZERO {
                        // A kernel compiled from the files on disk: they are good.
                        self.shader_error = None;
                    }
                    write(StageFrame {
                        image: frame.image,
                        compile: c,
                        render: t.render + t.readback,
                    });
                }
                Err(RenderError::Compile(e)) => {
                    let msg = RenderError::Compile(e).to_string();
                    self.shader_error = Some(msg.clone());
                    return Err(msg);
                }
                Err(e) => return Err(format!("render error: {e}")),
            }
        }
        Ok(false)
    }
}

/// Scales `image` up to `width`×`height` by repeating pixels, so a preview
/// written to the output has the final image's size.
pub fn upscale(image: &Image, width: u32, height: u32) -> Image {
    if image.width == width && image.height == height {
        return image.clone();
    }
    let mut pixels = Vec::with_capacity(width as usize * height as usize);
    for y in 0..height {
        let sy = (y as u64 * image.height as u64 / height as u64) as u32;
        for x in 0..width {
            let sx = (x as u64 * image.width as u64 / width as u64) as u32;
            pixels.push(image.at(sx, sy));
        }
    }
    Image {
        width,
        height,
        pixels,
    }
}
