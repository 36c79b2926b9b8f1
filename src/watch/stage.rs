//! What a reload rebuilds, and the staged render: a preview at reduced
//! resolution first, then the full image, with a check for newer edits
//! between the stages (a newer edit cancels the refinement).
//!
//! The session keeps the last good state: a scene that fails to load or
//! upload keeps the previous upload, a shader that fails to compile keeps the
//! previous pipelines ([`Renderer::reload_shaders`]), and a failed render
//! writes nothing, so the output always holds the last good image.
//!
//! The user WGSL files a scene refers to (`"type": "wgsl"`) are shaders, not
//! scene files: an edit recompiles only that file's shade pipeline and the
//! next render reuses the hit records. An edit that changes a file's
//! `struct Params` cannot keep the uploaded parameters, so it reloads the
//! scene as well, which checks the JSON's `params` against the new fields.
//!
//! Texture files ([`crate::scene::Texture::file`]) are watched with the
//! scene's files, but an edit of one alone decodes the file again and
//! replaces that texture's texels on the device ([`Renderer::replace_texture`]), keeping the upload, the pipelines
//! and everything else. A texture whose size or colour space changed cannot
//! be replaced in place, so then the scene is reloaded. A file that no
//! longer decodes is reported, like a broken scene, and the last good
//! texture (and image) kept.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use super::files::normalise;
use crate::loaders::{self, LoadOptions};
use crate::render::shade::UserTexts;
use crate::render::{
    CompileError, Image, ReloadReport, RenderError, RenderRequest, Renderer, UploadedScene,
};
use crate::scene::{Shader, Texture};

/// Whether a reload failed because a user shader's `Params` changed.
fn params_changed(e: &RenderError) -> bool {
    matches!(e, RenderError::ParamsChanged { .. })
}

/// What changed since the last reload.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Changes {
    /// A shader source.
    pub shaders: bool,
    /// The scene file or a file it references (other than the texture
    /// files, which [`Session::apply_edits`] takes apart).
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
    fn from_report(report: ReloadReport) -> CompileTimes {
        CompileTimes {
            naga: report.shader_compile,
            pipeline: report.pipeline_creation,
            driver: report.driver_compile,
            recompiled: report.recompiled,
        }
    }
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
    /// Time to decode and replace the edited textures, when they were
    /// replaced without reloading the scene.
    pub texture_replace: Option<Duration>,
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
    /// The render reused the previous render's hit records (only the shade
    /// and gather stages ran: [`crate::render::RenderStats::hits_reused`]).
    pub hits_reused: bool,
}

/// The renderer, the scene upload and the errors of the current files.
pub struct Session {
    renderer: Renderer,
    scene_path: PathBuf,
    load: LoadOptions,
    uploaded: Option<UploadedScene>,
    /// Every file the last good scene read.
    scene_files: Vec<PathBuf>,
    /// The user WGSL files among them (the scene's `wgsl` shaders).
    user_shaders: Vec<PathBuf>,
    /// The last good scene's textures as uploaded (edits replace them).
    textures: Vec<Texture>,
    /// Texture files that do not decode now, by normalised path: the error
    /// (the upload keeps their last good texels).
    texture_errors: BTreeMap<PathBuf, String>,
    /// The shaders on disk do not compile (the last good kernel is in use).
    pub shader_error: Option<String>,
    /// The scene on disk does not load (the last good upload is in use).
    pub scene_error: Option<String>,
    /// The error of a time-out, once one hung the device
    /// ([`RenderError::is_timeout`]): what `watch` carries over its restart.
    timed_out: Option<String>,
    /// The last good scene is lit by the default environment
    /// ([`crate::loaders::Loaded::lit_by_default`]).
    lit_by_default: bool,
}

impl Session {
    /// A session on an open renderer; nothing is loaded yet.
    pub fn new(renderer: Renderer, scene_path: &Path, mut load: LoadOptions) -> Session {
        // Images that cannot fit the device are refused from their headers.
        load.max_texture_bytes = renderer.texture_capacity();
        Session {
            renderer,
            scene_path: scene_path.to_path_buf(),
            load,
            uploaded: None,
            lit_by_default: false,
            scene_files: vec![scene_path.to_path_buf()],
            user_shaders: Vec::new(),
            textures: Vec::new(),
            texture_errors: BTreeMap::new(),
            shader_error: None,
            scene_error: None,
            timed_out: None,
        }
    }

    /// Whether the device is hung: a shader ran past the time limit and
    /// cannot be stopped ([`crate::render::Renderer::is_hung`]).
    pub fn is_hung(&self) -> bool {
        self.renderer.is_hung()
    }

    /// The message of the time-out that hung the device, if one did.
    pub fn timed_out(&self) -> Option<&str> {
        self.timed_out.as_deref()
    }

    /// Keeps `message` if `e` is the time-out that hung the device (the
    /// first one: every later submission fails the same way).
    fn note_timeout(&mut self, e: &RenderError, message: &str) {
        if e.is_timeout() && self.timed_out.is_none() {
            self.timed_out = Some(message.to_string());
        }
    }

    /// The files the last good scene read (the scene file alone before the
    /// first good load).
    pub fn scene_files(&self) -> &[PathBuf] {
        &self.scene_files
    }

    /// The user shader files (`"type": "wgsl"`) of the last good scene, as
    /// the scene gives them (resolved against its folder); also in
    /// [`Session::scene_files`]. The loop watches them as shaders.
    pub fn user_shader_files(&self) -> &[PathBuf] {
        &self.user_shaders
    }

    /// The image files of the last good scene's textures, as the scene
    /// gives them (textures embedded in other files have none); also in
    /// [`Session::scene_files`]. The loop watches them as textures.
    pub fn texture_files(&self) -> Vec<PathBuf> {
        let mut files: Vec<PathBuf> = self
            .textures
            .iter()
            .filter_map(|t| t.file.clone())
            .collect();
        files.sort();
        files.dedup();
        files
    }

    /// The errors of texture files that do not decode now (the last good
    /// texture of each is in use), in file order.
    pub fn texture_errors(&self) -> impl Iterator<Item = &String> {
        self.texture_errors.values()
    }

    /// The full image size of the current upload.
    pub fn size(&self) -> Option<(u32, u32)> {
        self.uploaded.as_ref().map(UploadedScene::size)
    }

    /// Rebuilds what `changes` invalidates.
    ///
    /// A scene edit reloads and re-uploads the scene (the stage pipelines
    /// are cached by the scene's features, so an edit that keeps them keeps
    /// them). A shader edit re-reads the shader files and recompiles only
    /// the pipelines whose text changed, keeping the upload (and, when only
    /// shade pipelines changed, the hit records). A shader edit also retries
    /// a scene that failed to load (it may have failed on a shader file), and
    /// one that changes a user shader's `Params` reloads the scene, so that
    /// its JSON `params` are checked against the new fields.
    ///
    pub fn apply(&mut self, changes: Changes) -> Applied {
        self.apply_edits(changes, &[])
    }

    /// [`Session::apply`] with texture edits: `textures` are the changed
    /// texture files (normalised, [`super::files::normalise`]; see
    /// [`Session::texture_files`]). Without a scene edit they replace those
    /// textures only ([`Session::replace_textures`]); they also retry a scene
    /// that failed to load (it may have failed on one of them).
    pub fn apply_edits(&mut self, changes: Changes, textures: &[PathBuf]) -> Applied {
        let mut out = Applied::default();
        let edited = !textures.is_empty();
        let retry = (changes.shaders || edited) && self.scene_error.is_some();
        let mut scene = changes.scene || retry;
        if edited && !scene && !self.replace_textures(textures, &mut out) {
            // A texture that cannot be replaced in place: upload it all.
            scene = true;
        }
        let mut retried = false;
        loop {
            let reloaded = scene && self.reload_scene(&mut out);
            if reloaded {
                // The scene's textures were read again, and any texture
                // timing is part of the upload's.
                out.texture_replace = None;
            }
            // After a Params change, a scene that does not load (its JSON
            // no longer fits the file) is the error to show.
            if !reloaded && (retried || !changes.shaders) {
                break;
            }
            let Some(up) = &mut self.uploaded else {
                // Nothing to compile for yet: the first render compiles.
                self.renderer.clear_pipeline_cache();
                self.shader_error = None;
                out.render = self.scene_error.is_none();
                break;
            };
            let guard = loaders::guard::Guard::new(&self.scene_path, &self.load);
            let texts: Result<UserTexts, _> = up
                .user_shader_files()
                .into_iter()
                .map(|p| loaders::read_shader_file(&p, &guard).map(|t| (p, t)))
                .collect();
            let reloaded = match texts {
                Ok(texts) => self.renderer.reload_shaders(up, &texts),
                Err(refused) => Err(RenderError::Compile(CompileError {
                    location: "reload".into(),
                    message: refused.0,
                })),
            };
            match reloaded {
                Ok(report) => {
                    self.shader_error = None;
                    // After a scene edit alone, report a compile only when
                    // one happened (new features, or a file that changed).
                    if changes.shaders || !report.recompiled.is_empty() {
                        out.compile = Some(CompileTimes::from_report(report));
                    }
                    out.render = true;
                }
                Err(e) if params_changed(&e) && !scene => {
                    // The uploaded parameters no longer fit the file: reload
                    // the scene too (once).
                    scene = true;
                    retried = true;
                    continue;
                }
                Err(e) => {
                    self.note_timeout(&e, &e.to_string());
                    self.shader_error = Some(e.to_string());
                    // A scene edit still renders, with the last good
                    // pipelines; a shader edit has nothing new to show.
                }
            }
            break;
        }
        if let Some(e) = &self.shader_error {
            if changes.shaders || out.render {
                out.errors.push(e.clone());
            }
        }
        out
    }

    /// Decodes the texture files `paths` (normalised) again and replaces
    /// the textures read from them in the upload. A file that does not
    /// decode is an error (and its texture keeps its last good texels);
    /// `out.render` is set when a texture was replaced. Returns false when a
    /// texture cannot be replaced in place (its size or colour space
    /// changed) or nothing is uploaded yet: then the scene must be reloaded.
    fn replace_textures(&mut self, paths: &[PathBuf], out: &mut Applied) -> bool {
        let t0 = Instant::now();
        let Some(up) = &mut self.uploaded else {
            return false;
        };
        let guard = loaders::guard::Guard::new(&self.scene_path, &self.load);
        for path in paths {
            let ids: Vec<usize> = (0..self.textures.len())
                .filter(|&i| self.textures[i].file.as_deref().map(normalise).as_ref() == Some(path))
                .collect();
            let mut failed = None;
            for &id in &ids {
                let old = &self.textures[id];
                let file = old.file.clone().unwrap_or_else(|| path.clone());
                let new = match loaders::json::read_texture(&file, old.srgb, &guard) {
                    Ok(t) => Texture {
                        label: old.label.clone(),
                        ..t
                    },
                    Err(e) => {
                        failed = Some(format!(
                            "texture error: {}; the last good texture is kept",
                            e.0
                        ));
                        break;
                    }
                };
                if self.renderer.replace_texture(up, id, &new).is_err() {
                    return false;
                }
                self.textures[id] = new;
                out.render = true;
            }
            match failed {
                Some(e) => {
                    out.errors.push(e.clone());
                    self.texture_errors.insert(path.clone(), e);
                }
                None => {
                    self.texture_errors.remove(path);
                }
            }
        }
        if out.render {
            out.texture_replace = Some(t0.elapsed());
        }
        true
    }

    /// Loads and uploads the scene; on success replaces the upload and
    /// returns true, else keeps the last good one and records the error.
    fn reload_scene(&mut self, out: &mut Applied) -> bool {
        let t0 = Instant::now();
        let result = match loaders::load_scene(&self.scene_path, &self.load) {
            Err(e) => Err(format!("scene error: {e}")),
            Ok(loaded) => match self.renderer.upload(&loaded.scene) {
                Err(e) => {
                    let msg = format!("{}: {e}", self.scene_path.display());
                    self.note_timeout(&e, &msg);
                    Err(msg)
                }
                Ok(up) => Ok((loaded, up)),
            },
        };
        match result {
            Err(e) => {
                out.errors.push(e.clone());
                self.scene_error = Some(e);
                false
            }
            Ok((loaded, up)) => {
                self.uploaded = Some(up);
                self.user_shaders = loaded
                    .scene
                    .shaders
                    .iter()
                    .filter_map(|s| match s {
                        Shader::Wgsl(w) => Some(w.path.clone()),
                        _ => None,
                    })
                    .collect();
                self.user_shaders.sort();
                self.user_shaders.dedup();
                self.scene_files = loaded.files;
                self.lit_by_default = loaded.lit_by_default;
                self.textures = loaded.scene.textures;
                self.texture_errors.clear();
                self.scene_error = None;
                out.upload = Some(t0.elapsed());
                out.render = true;
                true
            }
        }
    }

    /// Whether the last good scene is lit by the default environment (its
    /// images are tone-mapped by default).
    pub fn lit_by_default(&self) -> bool {
        self.lit_by_default
    }

    /// Renders the stages, largest divisor first (e.g. `[4, 1]`: a quarter
    /// resolution preview, then the full image), handing each to `write`.
    /// Before each stage after the first, and between the bands of rows of
    /// those stages, `cancel()` is asked whether a newer edit arrived; then
    /// the rest is skipped and `Ok(true)` returned.
    pub fn render_stages(
        &mut self,
        divisors: &[u32],
        cancel: impl FnMut() -> bool,
        write: impl FnMut(StageFrame),
    ) -> Result<bool, String> {
        self.render_stages_with(divisors, false, cancel, write)
    }

    /// [`Session::render_stages`], whose first stage also stops between
    /// bands when `first_cancellable` (the loop's full image when the
    /// preview process renders the preview: something is on screen
    /// already).
    pub fn render_stages_with(
        &mut self,
        divisors: &[u32],
        first_cancellable: bool,
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
            let request = match i == 0 && !first_cancellable {
                true => RenderRequest::new(sw, sh),
                false => RenderRequest::cancellable(sw, sh, &mut cancel),
            };
            match self.renderer.render(up, request).map(|r| r.frame) {
                Err(RenderError::Cancelled) => return Ok(true),
                Ok(frame) => {
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
                        hits_reused: frame.stats.hits_reused,
                    });
                }
                Err(RenderError::Compile(e)) => {
                    let msg = RenderError::Compile(e).to_string();
                    self.shader_error = Some(msg.clone());
                    return Err(msg);
                }
                Err(e) => {
                    let msg = format!("render error: {e}");
                    self.note_timeout(&e, &msg);
                    return Err(msg);
                }
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
