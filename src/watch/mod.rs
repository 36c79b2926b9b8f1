//! `penumbra watch`: shader and scene hot reload.
//!
//! The loop ([`run`]) watches the scene file, every file it read, and the
//! shader sources ([`files`]): the engine's (with `--shaders`) and the
//! user WGSL files the scene refers to; waits for a batch of changes
//! (until the writers have closed the files, or a debounce window for
//! files still being written: [`files::FileWatcher::next_batch`]); rebuilds only what changed ([`stage::Session::apply`]: a shader
//! edit recompiles only the pipelines whose files changed and keeps the
//! scene upload, and after a shading edit the hit records too; a scene edit
//! re-uploads and keeps the pipelines unless the scene's features change; a
//! texture file edit replaces that texture's texels only); renders a
//! quarter-resolution preview and then the full image, writing the output
//! atomically after each ([`stage::Session::render_stages`]); and reports
//! each reload as an [`Event`]. Errors (a broken shader or scene, a failed
//! render) are reported and the last good kernel, upload and image kept.
//! With a server address, the latest image, error and timing line are also
//! published to a live page ([`server`]).
//!
//! Cancellation: a change that arrives while the preview renders skips the
//! full-resolution stage, and one that arrives during the full-resolution
//! stage stops it between two bands of 64 rows
//! ([`crate::render::RenderRequest::cancellable`]); the preview itself
//! always completes. With the preview process ([`preview`]) the loop's full
//! image is its only stage, and a newer edit stops it between bands too.

pub mod files;
pub mod preview;
pub mod restart;
pub mod server;
pub mod stage;

use std::collections::BTreeSet;
use std::io::Write as _;
use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::Sender;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use crate::loaders::LoadOptions;
use crate::output::{self, Durability, Format};
use crate::render::compile::SHADER_FILES;
use crate::render::{Renderer, RendererOptions, ShaderSource};
use crate::tonemap::Display;
use files::{normalise, FileWatcher, WatchSet};
use stage::{Changes, CompileTimes, Session, StageFrame};

/// `watch`'s default bound on one submission of work to the device: its
/// renders go in bands of rows (64 at the full size), each far below it
/// (docs/watchdog.md), and a shader that never ends is reported this soon.
pub const DEFAULT_TIME_LIMIT: Duration = Duration::from_secs(10);

/// How to run the loop.
#[derive(Clone, Debug)]
pub struct WatchOptions {
    /// The scene file.
    pub scene: PathBuf,
    /// The output image (.png or .exr), rewritten after every stage.
    pub output: PathBuf,
    /// The renderer: device, validation, kernel variant, and where the WGSL
    /// comes from (a directory is watched; embedded shaders are not).
    pub renderer: RendererOptions,
    /// Image size overrides, limits and lighting flags.
    pub load: LoadOptions,
    /// `--exposure` and `--tonemap` of PNG output and the live page.
    pub display: Display,
    /// Serve the live page here.
    pub serve: Option<SocketAddr>,
    /// The preview's resolution divisor (1: no preview stage).
    pub preview_divisor: u32,
    /// A burst of writes closer together than this gives one reload, unless
    /// every file was closed after its write or renamed into place: the
    /// reload then starts [`files::SETTLE`] after the last of them.
    pub debounce: Duration,
    /// What a restart after a hung device left ([`restart`]): where the
    /// reload numbers go on, the page's address, the files not to render
    /// again until they change.
    pub resume: restart::Resume,
    /// Render the preview in a second process whose driver compiles quickly
    /// ([`preview`]); None: the loop renders it.
    pub preview_process: Option<preview::WorkerCommand>,
    /// After a shader edit, how long the loop lets the preview process
    /// compile alone before it compiles too ([`preview::HEAD_START`]; zero:
    /// both at once).
    pub preview_head_start: Duration,
}

impl WatchOptions {
    /// Defaults: a 1/4-resolution preview, a 30 ms debounce window, no
    /// server, embedded shaders.
    pub fn new(scene: impl Into<PathBuf>, output: impl Into<PathBuf>) -> WatchOptions {
        WatchOptions {
            scene: scene.into(),
            output: output.into(),
            renderer: RendererOptions {
                time_limit: Some(DEFAULT_TIME_LIMIT),
                ..RendererOptions::default()
            },
            load: LoadOptions::default(),
            display: Display::default(),
            serve: None,
            preview_divisor: 4,
            debounce: Duration::from_millis(30),
            resume: restart::Resume::default(),
            preview_process: None,
            preview_head_start: preview::HEAD_START,
        }
    }
}

/// One written stage of a reload.
#[derive(Clone, Debug)]
pub struct StageReport {
    /// The stage's render size (the file holds it scaled up to the full size).
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
    /// Kernel compile time spent in this stage (zero when cached).
    pub compile: CompileTimes,
    /// The render dispatch and readback.
    pub render: Duration,
    /// The render reused the last render's hit records: a shading edit ran
    /// only the shade and gather stages.
    pub hits_reused: bool,
    /// Encoding the image (PNG or EXR).
    pub encode: Duration,
    /// Writing and renaming the file.
    pub write: Duration,
    /// From the first file event (or the start) to the image on disk.
    pub latency: Duration,
    /// When the image was on disk.
    pub written_at: Instant,
    /// A preview (smaller than the full image).
    pub preview: bool,
    /// Rendered by the preview process ([`preview`]).
    pub worker: bool,
}

/// What one reload did.
#[derive(Clone, Debug)]
pub struct Reload {
    /// 0 for the first render at start-up, then 1, 2, …
    pub number: u64,
    /// The files whose change triggered it (empty at start-up).
    pub changed: Vec<PathBuf>,
    /// What changed.
    pub changes: Changes,
    /// Kernel recompile after a shader edit.
    pub compile: Option<CompileTimes>,
    /// Loading and uploading the scene after a scene edit.
    pub upload: Option<Duration>,
    /// The texture files whose change triggered it (normalised; also in
    /// `changed`): a texture edit alone replaces those textures and does not
    /// count as a scene change in `changes`.
    pub textures: Vec<PathBuf>,
    /// Decoding and replacing the edited textures, when a texture edit was
    /// applied without reloading the scene.
    pub texture_replace: Option<Duration>,
    /// The stages written, preview first.
    pub stages: Vec<StageReport>,
    /// A newer edit cancelled the refinement.
    pub cancelled: bool,
    /// Errors: each names the file (and for shaders `file:line:col`, the
    /// source line and a caret). The output keeps the last good image.
    pub errors: Vec<String>,
    /// The one-line summary printed for this reload.
    pub line: String,
}

/// What the loop reports.
// One event per reload: the size of the `Reload` variant costs nothing, and
// boxing it would only complicate every receiver.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug)]
pub enum Event {
    /// The watcher is armed: edits from now on are seen.
    Watching {
        /// The watched files.
        files: Vec<PathBuf>,
    },
    /// The live page is up.
    Serving {
        /// Its URL.
        url: String,
    },
    /// A reload finished (or failed).
    Reload(Reload),
    /// The device is hung (a shader ran past the time limit and cannot be
    /// stopped): the loop has ended, and only a new process can go on
    /// ([`restart::Restart::exec`]). Sent after that reload's
    /// [`Event::Reload`], which reported the error.
    Restart(restart::Restart),
}

impl Event {
    /// Prints the event as `penumbra watch` does: errors to stderr, one line
    /// per reload to stdout.
    pub fn print(&self) {
        match self {
            Event::Watching { files } => {
                println!("watching {} files (Ctrl-C to stop)", files.len())
            }
            Event::Serving { url } => println!("serving the live preview at {url}"),
            Event::Reload(r) => {
                let mut err = std::io::stderr().lock();
                for e in &r.errors {
                    let _ = writeln!(err, "error: {}", crate::terminal::diagnostic(e));
                }
                drop(err);
                println!("{}", r.line);
            }
            Event::Restart(_) => println!(
                "restarting: the device still runs the shader that did not end, and only a new process frees it; the next save renders"
            ),
        }
        let _ = std::io::stdout().flush();
    }
}

fn ms(d: Duration) -> String {
    format!("{:.1} ms", d.as_secs_f64() * 1e3)
}

/// The loop: renders once, then reloads on every change until `stop` is
/// set, sending an [`Event`] per reload. Returns an error only when it cannot
/// start (no Vulkan device, unwritable output, address in use, no watcher);
/// broken files and failed renders are reported and survived.
pub fn run(
    opts: &WatchOptions,
    stop: Arc<AtomicBool>,
    events: Sender<Event>,
) -> anyhow::Result<()> {
    let mut watch = Watch::start(opts, events)?;
    // The first render, then one reload per batch of changes.
    let mut batch = Some(files::Batch {
        first_event: Instant::now(),
        last_event: Instant::now(),
        paths: Default::default(),
    });
    while let Some(b) = batch {
        watch.reload(b);
        if let Some(restart) = watch.hung() {
            let _ = watch.events.send(Event::Restart(restart));
            return Ok(());
        }
        batch = watch.watcher.next_batch(&stop);
    }
    Ok(())
}

/// What the loop keeps from one reload to the next.
struct Watch {
    /// The renderer, the scene upload and the last good pipelines.
    session: Session,
    /// The watched files and their debounced events.
    watcher: FileWatcher,
    /// The canonical `--shaders` directory (None: embedded shaders).
    shader_dir: Option<PathBuf>,
    /// The engine's shader files in `shader_dir`, normalised.
    shader_files: Vec<PathBuf>,
    /// Where stages go (the preview process's reader thread writes too).
    out: Arc<Mutex<Output>>,
    /// The preview process, while one runs.
    worker: Option<preview::Worker>,
    /// How to start one (None: the loop renders its previews).
    worker_command: Option<preview::WorkerCommand>,
    /// How many were started.
    worker_starts: u32,
    /// [`WatchOptions::preview_head_start`].
    head_start: Duration,
    /// How long the full image waits for the preview process's answer
    /// before the process counts as hung.
    preview_wait: Duration,
    /// The stages' resolution divisors, preview first.
    divisors: Vec<u32>,
    /// Where events go.
    events: Sender<Event>,
    /// The number of the next reload (0: the first render).
    number: u64,
    /// Whether [`Event::Watching`] was sent.
    announced: bool,
    /// Whether the scene was loaded once (until then every reload applies
    /// everything).
    loaded: bool,
    /// Files that hung the device before a restart, not rendered again
    /// until one of them changes.
    quarantine: Option<restart::Quarantine>,
    /// The live page's bound address.
    serving: Option<SocketAddr>,
    /// The live page's server, kept running as long as the loop.
    _server: Option<server::Server>,
}

impl Watch {
    /// Set-up: checks the output, creates the renderer and the session,
    /// arms the file watcher on the scene's files and the shaders, and starts
    /// the live page's server (sending [`Event::Serving`]). Renders nothing.
    fn start(opts: &WatchOptions, events: Sender<Event>) -> anyhow::Result<Watch> {
        let format = output::check_writable(&opts.output)?;
        let scene_path = normalise(&opts.scene);
        let shader_dir = match &opts.renderer.shaders {
            ShaderSource::Directory(d) => Some(
                d.canonicalize()
                    .map_err(|e| anyhow::anyhow!("--shaders {}: {e}", d.display()))?,
            ),
            ShaderSource::Embedded => None,
        };
        let mut ropts = opts.renderer.clone();
        if let Some(d) = &shader_dir {
            ropts.shaders = ShaderSource::Directory(d.clone());
        }
        let renderer = Renderer::new(&ropts)?;
        // A GPU's driver compiles in milliseconds: no preview process
        // unless asked for.
        let worker_command = opts.preview_process.clone().filter(|c| {
            opts.preview_divisor > 1 && (c.on_gpus || renderer.device().device_type == "CPU")
        });
        let session = Session::new(renderer, &scene_path, opts.load.clone());

        let shader_files: Vec<PathBuf> = match &shader_dir {
            Some(d) => SHADER_FILES
                .iter()
                .map(|(f, _)| normalise(&d.join(f)))
                .collect(),
            None => Vec::new(),
        };
        let quarantine = opts.resume.quarantine.clone();
        let mut set = watch_set(&session, &shader_files);
        if let Some(q) = &quarantine {
            // The scene is not loaded before a change: watch what hung.
            let hung: Vec<PathBuf> = q
                .files
                .iter()
                .filter(|f| !set.shaders.contains(*f))
                .cloned()
                .collect();
            set.scene.extend(hung);
        }
        let watcher = FileWatcher::new(set, opts.debounce)?;

        let live = Arc::new(server::Live::default());
        // After a restart, the address the page had (the port may have been 0).
        let serve = opts.serve.map(|a| opts.resume.serve.unwrap_or(a));
        let server = match serve {
            Some(addr) => {
                let s = server::Server::start(addr, live.clone())?;
                let _ = events.send(Event::Serving {
                    url: format!("http://{}/", s.addr),
                });
                Some(s)
            }
            None => None,
        };
        if quarantine.is_some() && format == Format::Png {
            // The last good image, kept on disk across the restart.
            if let Ok(png) = std::fs::read(&opts.output) {
                live.set_image(png);
            }
        }
        let serving = server.as_ref().map(|s| s.addr);
        Ok(Watch {
            session,
            watcher,
            shader_dir,
            shader_files,
            out: Arc::new(Mutex::new(Output {
                path: opts.output.clone(),
                format,
                display: opts.display,
                live: opts.serve.map(|_| live),
            })),
            worker: None,
            worker_command,
            worker_starts: 0,
            head_start: opts.preview_head_start,
            // The preview process's own watchdog answers by then.
            preview_wait: opts.renderer.time_limit.unwrap_or(DEFAULT_TIME_LIMIT)
                + Duration::from_secs(2),
            divisors: if opts.preview_divisor > 1 {
                vec![opts.preview_divisor, 1]
            } else {
                vec![1]
            },
            events,
            number: opts.resume.next_reload,
            announced: false,
            loaded: false,
            quarantine,
            serving,
            _server: server,
        })
    }

    /// After a reload: whether the device hung, and if so what a new
    /// process needs to go on ([`restart`]).
    fn hung(&self) -> Option<restart::Restart> {
        if !self.session.is_hung() {
            return None;
        }
        let files = hashed_files(&self.session, &self.shader_files);
        let error = self
            .session
            .timed_out()
            .unwrap_or("the device ran past the time limit")
            .to_string();
        Some(restart::Restart {
            quarantine: restart::Quarantine {
                snapshot: restart::snapshot(&files),
                files,
                error,
            },
            next_reload: self.number,
            serve: self.serving,
        })
    }

    /// Whether the files are still those that hung the device before the
    /// restart (then nothing is applied or rendered).
    fn quarantined(&mut self) -> Option<String> {
        let q = self.quarantine.as_ref()?;
        if restart::snapshot(&q.files) == q.snapshot {
            return Some(format!(
                "{} (at the last save; not rendered again until a file changes)",
                q.error
            ));
        }
        self.quarantine = None;
        None
    }

    /// One reload: applies the batch's changes (everything for the first
    /// render), follows the scene to the files it now reads, renders and
    /// writes the stages, publishes the status to the live page and sends
    /// the [`Event::Reload`].
    fn reload(&mut self, b: files::Batch) {
        let number = self.number;
        if let Some(error) = self.quarantined() {
            self.report_quarantined(b, error);
            return;
        }
        let first = !self.loaded;
        self.loaded = true;
        // The last good scene's texture files (watched with the scene's):
        // an edit of one alone replaces that texture.
        let texture_files: BTreeSet<PathBuf> = self
            .session
            .texture_files()
            .iter()
            .map(|p| normalise(p))
            .collect();
        let changes = if first {
            Changes {
                shaders: true,
                scene: true,
            }
        } else {
            let set = self.watcher.set();
            Changes {
                shaders: b.paths.iter().any(|p| set.shaders.contains(p)),
                scene: b
                    .paths
                    .iter()
                    .any(|p| set.scene.contains(p) && !texture_files.contains(p)),
            }
        };
        let textures: Vec<PathBuf> = if first {
            Vec::new()
        } else {
            b.paths
                .iter()
                .filter(|p| texture_files.contains(*p))
                .cloned()
                .collect()
        };
        // The preview process compiles and renders the preview (and after a
        // shader edit the full image too, on its kept hits); this one
        // applies the same changes and renders the full image, unless the
        // preview process wrote it first.
        let shader_edit = !first && changes.shaders && !changes.scene && textures.is_empty();
        let started = self.request_preview(number, b.first_event, changes, &textures, shader_edit);
        let previewing = started.is_some();
        if started == Some(false) && shader_edit && !self.head_start.is_zero() {
            // A shader edit's preview is a compile: the preview process gets
            // the cores to itself, then this one compiles (two compiles at
            // once slowed both: docs/watch.md).
            if let Some(w) = &self.worker {
                w.head_start(self.head_start);
            }
        }
        let applied = self.session.apply_edits(changes, &textures);
        // The scene may now reference other files.
        let new_set = watch_set(&self.session, &self.shader_files);
        if &new_set != self.watcher.set() {
            if let Err(e) = self.watcher.update(new_set) {
                eprintln!("warning: cannot watch every scene file: {e}");
            }
        }
        if !self.announced {
            let set = self.watcher.set();
            let _ = self.events.send(Event::Watching {
                files: set.scene.iter().chain(&set.shaders).cloned().collect(),
            });
            self.announced = true;
        }

        let mut errors = applied.errors;
        let (mut stages, cancelled) = if applied.render {
            self.render(b.first_event, previewing, &mut errors)
        } else {
            (Vec::new(), false)
        };
        if let Some(w) = self.worker.as_mut() {
            stages.extend(w.close());
            stages.sort_by_key(|s| s.written_at);
        }
        let mut reload = Reload {
            number,
            changed: b.paths.into_iter().collect(),
            changes,
            compile: applied.compile,
            upload: applied.upload,
            textures,
            texture_replace: applied.texture_replace,
            stages,
            cancelled,
            errors,
            line: String::new(),
        };
        reload.line = reload.summary(applied.render, |p| describe(self.shader_dir.as_deref(), p));
        if let Some(live) = &self.live() {
            let current = self
                .session
                .scene_error
                .iter()
                .chain(&self.session.shader_error)
                .chain(self.session.texture_errors())
                .cloned()
                .chain(
                    reload
                        .errors
                        .iter()
                        .filter(|e| e.starts_with("render error"))
                        .cloned(),
                )
                .collect::<Vec<_>>();
            let current = (!current.is_empty()).then(|| current.join("\n\n"));
            live.set_status(current, reload.line.clone());
        }
        let _ = self.events.send(Event::Reload(reload));
        self.number += 1;
    }

    /// The live page, if the loop serves one.
    fn live(&self) -> Option<Arc<server::Live>> {
        self.out
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .live
            .clone()
    }

    /// Asks the preview process for the preview of reload `number`,
    /// starting one if there is none (a new one gets everything as
    /// changed). Returns None if no preview process renders it, else
    /// whether the process was started for it.
    fn request_preview(
        &mut self,
        number: u64,
        first_event: Instant,
        changes: Changes,
        textures: &[PathBuf],
        full: bool,
    ) -> Option<bool> {
        let cmd = self.worker_command.as_ref()?;
        if self.worker.as_ref().is_some_and(preview::Worker::is_dead) {
            self.worker = None;
        }
        let mut request = preview::Request {
            number,
            changes,
            textures: textures.to_vec(),
            full,
        };
        let started = self.worker.is_none();
        if started {
            if self.worker_starts >= preview::MAX_STARTS {
                return None;
            }
            self.worker_starts += 1;
            match preview::Worker::start(cmd, self.out.clone()) {
                Ok(w) => self.worker = Some(w),
                Err(e) => {
                    eprintln!("warning: cannot start the preview process: {e}");
                    return None;
                }
            }
            // A new process has loaded nothing yet.
            request.changes = Changes {
                shaders: true,
                scene: true,
            };
            request.textures.clear();
            // Nor does it hold full-size hit records to shade.
            request.full = false;
        }
        let w = self.worker.as_mut()?;
        w.request(&request, first_event);
        (!w.is_dead()).then_some(started)
    }

    /// A reload while the files are those that hung the device: reports
    /// the error again and keeps the last good image.
    fn report_quarantined(&mut self, b: files::Batch, error: String) {
        let mut reload = Reload {
            number: self.number,
            changed: b.paths.into_iter().collect(),
            changes: Changes::default(),
            compile: None,
            upload: None,
            textures: Vec::new(),
            texture_replace: None,
            stages: Vec::new(),
            cancelled: false,
            errors: vec![error.clone()],
            line: String::new(),
        };
        reload.line = reload.summary(false, |p| describe(self.shader_dir.as_deref(), p));
        if let Some(live) = &self.live() {
            live.set_status(Some(error), reload.line.clone());
        }
        if !self.announced {
            let set = self.watcher.set();
            let _ = self.events.send(Event::Watching {
                files: set.scene.iter().chain(&set.shaders).cloned().collect(),
            });
            self.announced = true;
        }
        let _ = self.events.send(Event::Reload(reload));
        self.number += 1;
    }

    /// Renders and writes the stages of one reload, the preview first;
    /// returns the stages written and whether a newer edit cancelled the
    /// refinement. Render and write errors are added to `errors`.
    fn render(
        &mut self,
        first_event: Instant,
        previewing: bool,
        errors: &mut Vec<String>,
    ) -> (Vec<StageReport>, bool) {
        let full = self.session.size().unwrap_or((1, 1));
        let mut stages = Vec::new();
        let mut write_errors = Vec::new();
        let lit_by_default = self.session.lit_by_default();
        let (watcher, out, worker) = (&mut self.watcher, &self.out, &mut self.worker);
        let preview_wait = self.preview_wait;
        // With the preview process, this process renders the full image
        // only, and stops when the preview process wrote it first.
        let divisors: &[u32] = if previewing { &[1] } else { &self.divisors };
        let worker_full = worker
            .as_ref()
            .filter(|_| previewing)
            .map(preview::Worker::full_done);
        let done = || worker_full.as_ref().is_some_and(preview::FullDone::get);
        if done() {
            return (stages, false);
        }
        // The full image stops between bands for a newer edit even when it
        // is this process's only stage: the preview process showed one.
        let rendered = self.session.render_stages_with(
            divisors,
            previewing,
            || watcher.pending() || done(),
            |frame: StageFrame| {
                if let Some(w) = worker.as_mut().filter(|_| previewing) {
                    // The preview of this reload first, never after; and
                    // the full image once.
                    if !w.claim_full(preview_wait) {
                        return;
                    }
                }
                let written = out.lock().unwrap_or_else(|e| e.into_inner()).write_stage(
                    frame,
                    full,
                    lit_by_default,
                    first_event,
                );
                match written {
                    Ok(stage) => stages.push(stage),
                    Err(e) => write_errors.push(e),
                }
            },
        );
        let mut cancelled = false;
        match rendered {
            // Stopped because the preview process's full image is on disk:
            // nothing was cancelled.
            Ok(c) => cancelled = c && !done(),
            Err(e) => {
                if !errors.contains(&e) {
                    errors.push(e)
                }
            }
        }
        errors.extend(write_errors);
        (stages, cancelled)
    }
}

impl Reload {
    /// The one-line summary of this reload: what changed, the compile (or
    /// that the kernel was kept), the upload, each stage's render, write and
    /// latency, a cancellation and whether there were errors. `rendered`:
    /// the reload rendered (it had something good to show); `divisors`: the
    /// stages' resolution divisors, preview first; `describe` names a
    /// changed file.
    fn summary(&self, rendered: bool, describe: impl Fn(&Path) -> String) -> String {
        let what = if self.number == 0 {
            "start".to_string()
        } else if self.changed.is_empty() {
            // The first reload of a process that restarted after a hang.
            "restart".to_string()
        } else {
            let mut kinds = Vec::new();
            if self.changes.shaders {
                kinds.push("shaders");
            }
            if self.changes.scene {
                kinds.push("scene");
            }
            if !self.textures.is_empty() {
                kinds.push("textures");
            }
            let names: Vec<String> = self.changed.iter().map(|p| describe(p)).collect();
            format!("{} ({})", kinds.join("+"), names.join(", "))
        };
        let mut parts = vec![format!("reload {}: {what}", self.number)];
        let compile = self.compile.clone().or_else(|| {
            self.stages
                .iter()
                .map(|s| s.compile.clone())
                .find(|c| c.total() > Duration::ZERO)
        });
        if let Some(c) = &compile {
            let what = if c.recompiled.is_empty() {
                String::new()
            } else {
                format!(": {}", c.recompiled.join(", "))
            };
            parts.push(format!(
                "compile {} (naga {}, pipeline {}, driver {}{what})",
                ms(c.total()),
                ms(c.naga),
                ms(c.pipeline),
                ms(c.driver)
            ));
        } else if rendered {
            parts.push("kernel kept".into());
        }
        if let Some(u) = self.upload {
            parts.push(format!("load+upload {}", ms(u)));
        }
        if let Some(t) = self.texture_replace {
            parts.push(format!("texture replace {}", ms(t)));
        }
        for s in &self.stages {
            let name = if s.preview { "preview" } else { "full" };
            let by = if s.worker { " (preview process)" } else { "" };
            // The preview process's compile is not in the line's compile.
            let compile = match s.worker && s.compile.total() > Duration::ZERO {
                true => format!("compile {}, ", ms(s.compile.total())),
                false => String::new(),
            };
            parts.push(format!(
                "{name} {}x{}{by}: {compile}render {}{}, encode+write {}, latency {}",
                s.width,
                s.height,
                ms(s.render),
                if s.hits_reused { " (hits reused)" } else { "" },
                ms(s.encode + s.write),
                ms(s.latency)
            ));
        }
        if self.cancelled {
            parts.push("refinement cancelled by a newer edit".into());
        }
        if !self.errors.is_empty() {
            parts.push(if self.stages.is_empty() {
                "ERROR: kept the last good image".into()
            } else {
                "ERROR: see above".into()
            });
        }
        parts.join(" | ")
    }
}

/// The files to watch: the scene's as scene files (its texture files among
/// them: [`Watch::reload`] tells their edits apart), and as shaders the
/// engine's `shader_files` and the scene's user shader files (an edit of one
/// recompiles only its shade pipelines and keeps the upload and the hit
/// records).
fn watch_set(session: &Session, shader_files: &[PathBuf]) -> WatchSet {
    let user: Vec<PathBuf> = session
        .user_shader_files()
        .iter()
        .map(|p| normalise(p))
        .collect();
    WatchSet {
        scene: session
            .scene_files()
            .iter()
            .map(|p| normalise(p))
            .filter(|p| !user.contains(p))
            .collect(),
        shaders: shader_files.iter().cloned().chain(user).collect(),
    }
}

/// A changed file as the summary line names it: relative to the shader
/// directory, otherwise its file name.
fn describe(shader_dir: Option<&Path>, p: &Path) -> String {
    shader_dir
        .and_then(|d| p.strip_prefix(d).ok())
        .or_else(|| p.file_name().map(Path::new))
        .unwrap_or(p)
        .display()
        .to_string()
}

/// Where stages go: the output file, and the live page.
struct Output {
    path: PathBuf,
    format: Format,
    display: Display,
    live: Option<Arc<server::Live>>,
}

impl Output {
    /// Writes a stage ([`Output::write`]) and reports it: its latency from
    /// `first_event`, and whether it is a preview (smaller than `full`).
    fn write_stage(
        &mut self,
        frame: StageFrame,
        full: (u32, u32),
        lit_by_default: bool,
        first_event: Instant,
    ) -> Result<StageReport, String> {
        let (encode, write) = self.write(&frame, full, lit_by_default)?;
        let written_at = Instant::now();
        Ok(StageReport {
            width: frame.image.width,
            height: frame.image.height,
            compile: frame.compile,
            render: frame.render,
            hits_reused: frame.hits_reused,
            encode,
            write,
            latency: written_at - first_event,
            written_at,
            preview: (frame.image.width, frame.image.height) != full,
            worker: false,
        })
    }

    /// Writes a stage (scaled up to `full`) atomically, without a sync
    /// ([`Durability::NoSync`]: the next stage or save rewrites it); returns
    /// the encode and write times.
    fn write(
        &mut self,
        frame: &StageFrame,
        full: (u32, u32),
        lit_by_default: bool,
    ) -> Result<(Duration, Duration), String> {
        let t0 = Instant::now();
        let linear = stage::upscale(&frame.image, full.0, full.1);
        let image = self
            .display
            .for_format(&linear, self.format, lit_by_default);
        // A preview is overwritten by the next stage: the faster encode.
        let compression = match (frame.image.width, frame.image.height) == full {
            true => png::Compression::Balanced,
            false => png::Compression::Fast,
        };
        let bytes = output::encode_with(&image, self.format, compression)
            .map_err(|e| format!("{}: cannot encode: {e}", self.path.display()))?;
        let encode = t0.elapsed();
        let t1 = Instant::now();
        output::write_atomic(&self.path, &bytes, Durability::NoSync).map_err(|e| e.to_string())?;
        let write = t1.elapsed();
        if let Some(live) = &self.live {
            let png = if self.format == Format::Png {
                bytes
            } else {
                let shown = self
                    .display
                    .for_format(&linear, Format::Png, lit_by_default);
                output::encode(&shown, Format::Png).unwrap_or_default()
            };
            live.set_image(png);
        }
        Ok((encode, write))
    }
}

/// The files whose contents a [`restart::Quarantine`] holds: the scene's
/// files and user shaders, and the engine's shader files when they are
/// watched (`shader_files`); not the textures (a texture does not run).
fn hashed_files(session: &Session, shader_files: &[PathBuf]) -> Vec<PathBuf> {
    let textures: BTreeSet<PathBuf> = session
        .texture_files()
        .iter()
        .map(|p| normalise(p))
        .collect();
    session
        .scene_files()
        .iter()
        .chain(session.user_shader_files())
        .map(|p| normalise(p))
        .chain(shader_files.iter().cloned())
        .filter(|p| !textures.contains(p))
        .collect()
}

/// Runs the loop until `stop` is set, printing as the command line does.
/// Returns the [`restart::Restart`] to carry out when the device hung.
pub fn run_printing(
    opts: &WatchOptions,
    stop: Arc<AtomicBool>,
) -> anyhow::Result<Option<restart::Restart>> {
    let (tx, rx) = std::sync::mpsc::channel();
    let opts = opts.clone();
    let stop2 = stop.clone();
    let looped = std::thread::Builder::new()
        .name("watch".into())
        .spawn(move || run(&opts, stop2, tx))?;
    let mut restart = None;
    for ev in rx {
        ev.print();
        if let Event::Restart(r) = ev {
            restart = Some(r);
        }
    }
    stop.store(true, Ordering::Relaxed);
    looped
        .join()
        .map_err(|_| anyhow::anyhow!("the watch loop panicked"))??;
    Ok(restart)
}
