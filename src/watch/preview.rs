//! The preview in a second process, whose driver compiles quickly.
//!
//! On lavapipe a shading edit waits for the driver to compile the shade
//! pipeline at its first dispatch, and that compile is most of the edit
//! loop (docs/watch.md). How long it takes is a setting of the whole
//! process, read once when the driver loads: `GALLIVM_PERF=nopt` skips
//! LLVM's optimisation passes, and `LP_NATIVE_VECTOR_WIDTH=128` halves the
//! code to select and schedule. Together they more than halved the shade
//! pipeline's compile, gave the same image bit for bit, and ran the code
//! nearly three times as slowly (docs/watch.md, `tools/measure/quick_compile.sh`):
//! right for a 1/16-size preview, wrong for the full image.
//!
//! So `watch` on a CPU device starts a second `penumbra watch` with the same
//! arguments, [`ENV_WORKER`] and those two settings in its environment: the
//! *worker*. The worker loads the same scene and renders only the preview.
//! For every reload the loop sends the worker the changes ([`Request`]),
//! then applies them itself and renders only the full image. A thread of the
//! loop reads the worker's answer ([`Answer`]) and writes the preview as
//! soon as it comes. The full image waits for the preview of its own reload
//! (or the worker's failure), so a preview never overwrites the full image;
//! a preview of a reload the loop has finished is dropped.
//!
//! After a shader edit the loop gives the worker a head start
//! ([`HEAD_START`] at most): it compiles only once the preview is on disk
//! (two compiles at once slowed each other on a 2-core machine:
//! docs/watch.md). The worker then renders the full image too, on the
//! full-size hit records it keeps ([`Request::full`]): its code runs
//! slower but is compiled already, so its full image usually lands long
//! before the loop's compile ends. The first full image on disk wins: the
//! loop's render stops between bands once the worker's is written, and a
//! worker's full image that comes after the loop's is dropped; a newer
//! request stops the worker's between bands. A scene or texture edit and
//! the first render, whose time goes to loading, run in both processes at
//! once, and the loop renders their full image.
//!
//! The worker's failures do not reach the user: the loop reports its own
//! errors for the same files. A worker that dies or stops answering is
//! killed and another started at the next reload, [`MAX_STARTS`] in all;
//! after that, and on a GPU (whose drivers compile in a few
//! milliseconds) unless asked for, the loop renders the preview itself as
//! before. The worker dies with the loop's thread (`PR_SET_PDEATHSIG`), so a
//! restart after a hung device or Ctrl-C leaves no worker behind.

use std::ffi::OsString;
use std::io::{BufReader, BufWriter, Read, Write};
use std::path::PathBuf;
use std::process::{Child, ChildStdin, ChildStdout, Command, Stdio};
use std::sync::{Arc, Condvar, Mutex};
use std::time::{Duration, Instant};

use super::stage::{Changes, CompileTimes, Session, StageFrame};
use super::{files, Output, StageReport, WatchOptions};
use crate::frame::Image;
use crate::render::{Renderer, ShaderSource};
use crate::scene::MAX_IMAGE_SIDE;

/// Set (to `1`) in the worker's environment: `penumbra watch` then serves
/// [`Request`]s on its standard input instead of running the loop.
pub const ENV_WORKER: &str = "PENUMBRA_PREVIEW_WORKER";

/// How often a loop starts a worker before it renders its previews itself.
pub const MAX_STARTS: u32 = 3;

/// How long the loop lets the worker compile alone after a shader edit
/// before it compiles too: a preview compiles in well under it, and a shader
/// that never ends costs the loop no more than this before its own watchdog
/// runs.
pub const HEAD_START: Duration = Duration::from_secs(1);

/// The environment that makes lavapipe compile quickly (module docs).
pub const QUICK_COMPILE: [(&str, &str); 2] =
    [("GALLIVM_PERF", "nopt"), ("LP_NATIVE_VECTOR_WIDTH", "128")];

/// How to start a worker: a `penumbra watch` command line of the same scene,
/// shaders and options as the loop's.
#[derive(Clone, Debug)]
pub struct WorkerCommand {
    /// The penumbra binary.
    pub program: PathBuf,
    /// Its arguments, from `watch` on.
    pub args: Vec<OsString>,
    /// Start one on a GPU too (`--preview-process on`); by default only on
    /// a CPU device, whose compile is the edit loop's bottleneck.
    pub on_gpus: bool,
}

impl WorkerCommand {
    /// The command line of this process (the worker is `penumbra watch`
    /// again, with the same arguments).
    pub fn this_process(on_gpus: bool) -> std::io::Result<WorkerCommand> {
        Ok(WorkerCommand {
            program: std::env::current_exe()?,
            args: std::env::args_os().skip(1).collect(),
            on_gpus,
        })
    }
}

/// Whether this process is a worker ([`ENV_WORKER`]).
pub fn is_worker() -> bool {
    std::env::var_os(ENV_WORKER).is_some_and(|v| v == "1")
}

/// What the loop asks of the worker: apply these changes, render the
/// preview of reload `number`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Request {
    /// The loop's reload number.
    pub number: u64,
    /// What changed ([`Session::apply_edits`]).
    pub changes: Changes,
    /// The changed texture files, normalised.
    pub textures: Vec<PathBuf>,
    /// Render the full image too, after the preview (a second answer).
    pub full: bool,
}

/// The worker's answer to a [`Request`].
#[derive(Clone, Debug, PartialEq)]
pub enum Answer {
    /// The preview.
    Image(Preview),
    /// Nothing to show: the files did not load or compile, or the render
    /// failed (the loop reports its own error for the same files).
    Nothing,
    /// The device ran past the time limit: the worker must be ended.
    Hung,
}

/// A rendered preview and what it took.
#[derive(Clone, Debug, PartialEq)]
pub struct Preview {
    /// At the preview's resolution.
    pub image: Image,
    /// The full image's size, which the written preview is scaled up to.
    pub full: (u32, u32),
    /// The scene is lit by the default environment (its tone mapping).
    pub lit_by_default: bool,
    /// The worker's compile: naga, pipeline creation, driver.
    pub compile: [Duration; 3],
    /// Render and readback.
    pub render: Duration,
    /// The render reused the worker's hit records.
    pub hits_reused: bool,
}

fn put_u32(w: &mut impl Write, v: u32) -> std::io::Result<()> {
    w.write_all(&v.to_le_bytes())
}

fn put_u64(w: &mut impl Write, v: u64) -> std::io::Result<()> {
    w.write_all(&v.to_le_bytes())
}

fn get<const N: usize>(r: &mut impl Read) -> std::io::Result<[u8; N]> {
    let mut b = [0u8; N];
    r.read_exact(&mut b)?;
    Ok(b)
}

fn get_u32(r: &mut impl Read) -> std::io::Result<u32> {
    get::<4>(r).map(u32::from_le_bytes)
}

fn get_u64(r: &mut impl Read) -> std::io::Result<u64> {
    get::<8>(r).map(u64::from_le_bytes)
}

fn invalid(what: &str) -> std::io::Error {
    std::io::Error::new(
        std::io::ErrorKind::InvalidData,
        format!("preview worker: {what}"),
    )
}

impl Request {
    /// The longest path a request carries, in bytes.
    const MAX_PATH: u32 = 1 << 16;
    /// The most texture files a request carries.
    const MAX_TEXTURES: u32 = 1 << 16;

    /// Writes the request: number, change flags, then each texture path
    /// with its length.
    pub fn write(&self, w: &mut impl Write) -> std::io::Result<()> {
        use std::os::unix::ffi::OsStrExt as _;
        put_u64(w, self.number)?;
        let flags =
            self.changes.shaders as u8 | (self.changes.scene as u8) << 1 | (self.full as u8) << 2;
        w.write_all(&[flags])?;
        put_u32(w, self.textures.len() as u32)?;
        for t in &self.textures {
            let b = t.as_os_str().as_bytes();
            put_u32(w, b.len() as u32)?;
            w.write_all(b)?;
        }
        w.flush()
    }

    /// Reads a request; `Ok(None)` at the end of the stream (the loop ended).
    pub fn read(r: &mut impl Read) -> std::io::Result<Option<Request>> {
        use std::os::unix::ffi::OsStringExt as _;
        let number = match get_u64(r) {
            Ok(n) => n,
            Err(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => return Ok(None),
            Err(e) => return Err(e),
        };
        let [flags] = get::<1>(r)?;
        let n = get_u32(r)?;
        if n > Self::MAX_TEXTURES {
            return Err(invalid("too many texture files"));
        }
        let mut textures = Vec::with_capacity(n as usize);
        for _ in 0..n {
            let len = get_u32(r)?;
            if len > Self::MAX_PATH {
                return Err(invalid("a path too long"));
            }
            let mut b = vec![0u8; len as usize];
            r.read_exact(&mut b)?;
            textures.push(PathBuf::from(OsString::from_vec(b)));
        }
        Ok(Some(Request {
            number,
            changes: Changes {
                shaders: flags & 1 != 0,
                scene: flags & 2 != 0,
            },
            textures,
            full: flags & 4 != 0,
        }))
    }
}

impl Answer {
    /// Writes the answer to request `number`.
    pub fn write(&self, number: u64, w: &mut impl Write) -> std::io::Result<()> {
        put_u64(w, number)?;
        match self {
            Answer::Nothing => w.write_all(&[0])?,
            Answer::Hung => w.write_all(&[1])?,
            Answer::Image(p) => {
                w.write_all(&[2, p.lit_by_default as u8, p.hits_reused as u8])?;
                for v in [p.image.width, p.image.height, p.full.0, p.full.1] {
                    put_u32(w, v)?;
                }
                for d in p.compile.iter().chain([&p.render]) {
                    put_u64(w, d.as_nanos().min(u64::MAX as u128) as u64)?;
                }
                w.write_all(bytemuck::cast_slice(&p.image.pixels))?;
            }
        }
        w.flush()
    }

    /// Reads an answer and the number of its request.
    pub fn read(r: &mut impl Read) -> std::io::Result<(u64, Answer)> {
        let number = get_u64(r)?;
        let [kind] = get::<1>(r)?;
        let answer = match kind {
            0 => Answer::Nothing,
            1 => Answer::Hung,
            2 => {
                let [lit_by_default, hits_reused] = get::<2>(r)?;
                let [width, height, fw, fh] = [get_u32(r)?, get_u32(r)?, get_u32(r)?, get_u32(r)?];
                // No larger than the full image, which no scene can make
                // larger than MAX_IMAGE_SIDE a side: anything else is a
                // broken worker, refused before the allocation.
                let pixels = width as u64 * height as u64;
                if pixels == 0 || fw < width || fh < height || fw.max(fh) > MAX_IMAGE_SIDE {
                    return Err(invalid("an image of an impossible size"));
                }
                let mut t = [Duration::ZERO; 4];
                for d in &mut t {
                    *d = Duration::from_nanos(get_u64(r)?);
                }
                let mut px = vec![[0f32; 4]; pixels as usize];
                r.read_exact(bytemuck::cast_slice_mut(&mut px))?;
                Answer::Image(Preview {
                    image: Image {
                        width,
                        height,
                        pixels: px,
                    },
                    full: (fw, fh),
                    lit_by_default: lit_by_default != 0,
                    compile: [t[0], t[1], t[2]],
                    render: t[3],
                    hits_reused: hits_reused != 0,
                })
            }
            _ => return Err(invalid("an unknown answer")),
        };
        Ok((number, answer))
    }
}

/// The worker: serves [`Request`]s from standard input until it closes,
/// answering each on standard output. `opts` are the loop's (the worker
/// was started with the same arguments); only the scene, the renderer, the
/// load options and the preview divisor matter here.
pub fn serve(opts: &WatchOptions) -> anyhow::Result<()> {
    let mut ropts = opts.renderer.clone();
    if let ShaderSource::Directory(d) = &ropts.shaders {
        ropts.shaders = ShaderSource::Directory(d.canonicalize()?);
    }
    let renderer = Renderer::new(&ropts)?;
    let mut session = Session::new(renderer, &files::normalise(&opts.scene), opts.load.clone());
    let divisor = opts.preview_divisor.max(1);
    let mut input = BufReader::new(std::io::stdin().lock());
    let mut output = BufWriter::new(std::io::stdout().lock());
    while let Some(req) = Request::read(&mut input)? {
        let mut answer = preview_of(&mut session, &req, divisor);
        answer.write(req.number, &mut output)?;
        if req.full && matches!(answer, Answer::Image(_)) {
            // The full image, which a newer request stops between bands.
            answer = full_of(&mut session, || input_pending(&input));
            answer.write(req.number, &mut output)?;
        }
        if matches!(answer, Answer::Hung) {
            // The dispatch that never ends keeps a driver thread: only the
            // end of the process frees it, and the loop kills this one.
            return Ok(());
        }
    }
    Ok(())
}

/// Whether the loop has sent another request (buffered, or waiting on the
/// pipe).
fn input_pending<R: std::io::Read + std::os::fd::AsRawFd>(input: &BufReader<R>) -> bool {
    if !input.buffer().is_empty() {
        return true;
    }
    let mut fd = libc::pollfd {
        fd: input.get_ref().as_raw_fd(),
        events: libc::POLLIN,
        revents: 0,
    };
    // SAFETY: poll(2) on one valid pollfd, without waiting.
    unsafe { libc::poll(&mut fd, 1, 0) > 0 }
}

/// Renders the full image on the kept hit records (after a preview of the
/// same files); `Nothing` when `cancel` stopped it or it failed.
fn full_of(session: &mut Session, cancel: impl FnMut() -> bool) -> Answer {
    rendered(session, 1, true, cancel, CompileTimes::default())
}

/// Applies one request's changes and renders the preview.
fn preview_of(session: &mut Session, req: &Request, divisor: u32) -> Answer {
    let applied = session.apply_edits(req.changes, &req.textures);
    if session.is_hung() {
        return Answer::Hung;
    }
    if !applied.render {
        return Answer::Nothing;
    }
    // The compile of the edit (apply_edits') and of the first dispatch
    // (the render's) together.
    let compiled = applied.compile.unwrap_or_default();
    rendered(session, divisor, false, || false, compiled)
}

/// Renders one stage at 1/`divisor` of the full size (stopped between
/// bands by `cancel` if `cancellable`) as an answer; `compiled` is compile
/// time spent before it.
fn rendered(
    session: &mut Session,
    divisor: u32,
    cancellable: bool,
    cancel: impl FnMut() -> bool,
    compiled: CompileTimes,
) -> Answer {
    let Some(full) = session.size() else {
        return Answer::Nothing;
    };
    let mut frame = None;
    let result = session.render_stages_with(&[divisor], cancellable, cancel, |f: StageFrame| {
        frame = Some(f)
    });
    if session.is_hung() {
        return Answer::Hung;
    }
    match (result, frame) {
        (Ok(false), Some(f)) => Answer::Image(Preview {
            image: f.image,
            full,
            lit_by_default: session.lit_by_default(),
            compile: [
                compiled.naga + f.compile.naga,
                compiled.pipeline + f.compile.pipeline,
                compiled.driver + f.compile.driver,
            ],
            render: f.render,
            hits_reused: f.hits_reused,
        }),
        _ => Answer::Nothing,
    }
}

/// What the loop and its reader thread share.
struct Shared {
    state: Mutex<State>,
    answered: Condvar,
}

#[derive(Default)]
struct State {
    /// The reload whose answers are awaited.
    open: Option<Open>,
    /// The worker ended or broke the protocol.
    dead: bool,
}

/// Who wrote a reload's full image: the first to claim it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum By {
    Loop,
    Worker,
}

struct Open {
    number: u64,
    first_event: Instant,
    preview_answered: bool,
    /// A second answer, the full image, will come.
    full_expected: bool,
    full_by: Option<By>,
    stages: Vec<StageReport>,
}

/// Whether the preview process wrote the open reload's full image (the
/// loop's render then stops: it has nothing to add).
pub struct FullDone(Arc<Shared>);

impl FullDone {
    /// Whether it did.
    pub fn get(&self) -> bool {
        let st = self.0.state.lock().unwrap_or_else(|e| e.into_inner());
        st.open
            .as_ref()
            .is_some_and(|o| o.full_by == Some(By::Worker))
    }
}

/// The loop's side of a worker: the child process, the pipe to it, and the
/// thread that writes its previews.
pub struct Worker {
    child: Child,
    input: BufWriter<ChildStdin>,
    shared: Arc<Shared>,
    reader: Option<std::thread::JoinHandle<()>>,
}

impl Worker {
    /// Starts a worker; its previews are written to `out`.
    pub(super) fn start(cmd: &WorkerCommand, out: Arc<Mutex<Output>>) -> std::io::Result<Worker> {
        let mut c = Command::new(&cmd.program);
        c.args(&cmd.args)
            .env(ENV_WORKER, "1")
            // Two processes must not rewrite one pipeline cache file.
            .env("PENUMBRA_PIPELINE_CACHE", "0")
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            // The loop reports the errors of the same files itself.
            .stderr(Stdio::null());
        for (k, v) in QUICK_COMPILE {
            c.env(k, v);
        }
        // SAFETY: prctl is async-signal-safe and touches no Rust state.
        unsafe {
            use std::os::unix::process::CommandExt as _;
            c.pre_exec(|| {
                // Killed when the thread that started it (the loop's) ends.
                if libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGKILL) != 0 {
                    return Err(std::io::Error::last_os_error());
                }
                Ok(())
            });
        }
        let mut child = c.spawn()?;
        let input = BufWriter::new(child.stdin.take().expect("piped"));
        let output = child.stdout.take().expect("piped");
        let shared = Arc::new(Shared {
            state: Mutex::new(State::default()),
            answered: Condvar::new(),
        });
        let reader = {
            let shared = shared.clone();
            std::thread::Builder::new()
                .name("preview".into())
                .spawn(move || read_answers(output, &shared, &out))?
        };
        Ok(Worker {
            child,
            input,
            shared,
            reader: Some(reader),
        })
    }

    fn state(&self) -> std::sync::MutexGuard<'_, State> {
        self.shared.state.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Whether the worker ended or broke the protocol.
    pub(super) fn is_dead(&self) -> bool {
        self.state().dead
    }

    /// Asks for the preview of reload `number` (and its full image, if
    /// `req.full`).
    pub(super) fn request(&mut self, req: &Request, first_event: Instant) {
        self.state().open = Some(Open {
            number: req.number,
            first_event,
            preview_answered: false,
            full_expected: req.full,
            full_by: None,
            stages: Vec::new(),
        });
        if req.write(&mut self.input).is_err() {
            self.mark_dead();
        }
    }

    /// Waits until the worker answered the open request's preview (it is
    /// then on disk, if it rendered one), died, or `limit` passed; returns
    /// whether it answered.
    fn wait_preview(&self, limit: Duration) -> bool {
        let deadline = Instant::now() + limit;
        let mut st = self.state();
        loop {
            if st.dead || st.open.as_ref().is_none_or(|o| o.preview_answered) {
                return !st.dead;
            }
            let now = Instant::now();
            if now >= deadline {
                return false;
            }
            st = self
                .shared
                .answered
                .wait_timeout(st, deadline - now)
                .unwrap_or_else(|e| e.into_inner())
                .0;
        }
    }

    /// The head start after a shader edit: waits for the preview for at most
    /// `limit` (a worker that takes longer goes on, in parallel).
    pub(super) fn head_start(&self, limit: Duration) {
        self.wait_preview(limit);
    }

    /// Before the loop writes its full image: waits for the preview (a
    /// worker that has not answered within `limit` counts as hung and is
    /// killed), then claims the full image. False: the worker wrote it.
    pub(super) fn claim_full(&mut self, limit: Duration) -> bool {
        if !self.wait_preview(limit) && !self.is_dead() {
            self.mark_dead();
        }
        let mut st = self.state();
        match st.open.as_mut() {
            Some(o) if o.full_by == Some(By::Worker) => false,
            Some(o) => {
                o.full_by = Some(By::Loop);
                true
            }
            None => true,
        }
    }

    /// Whether the worker wrote the open reload's full image, for the
    /// loop's render to ask between bands.
    pub(super) fn full_done(&self) -> FullDone {
        FullDone(self.shared.clone())
    }

    /// Closes the open request: returns the stages the worker wrote for it
    /// (preview, then full image); an answer that comes later is dropped.
    pub(super) fn close(&mut self) -> Vec<StageReport> {
        self.state()
            .open
            .take()
            .map(|o| o.stages)
            .unwrap_or_default()
    }

    fn mark_dead(&mut self) {
        let _ = self.child.kill();
        self.state().dead = true;
        self.shared.answered.notify_all();
    }
}

impl Drop for Worker {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
        if let Some(r) = self.reader.take() {
            let _ = r.join();
        }
    }
}

/// The reader thread: writes each image of the open reload as it comes:
/// the preview, then the full image unless the loop claimed it first.
fn read_answers(output: ChildStdout, shared: &Shared, out: &Mutex<Output>) {
    let mut output = BufReader::new(output);
    loop {
        let answer = Answer::read(&mut output);
        let mut st = shared.state.lock().unwrap_or_else(|e| e.into_inner());
        let (number, answer) = match answer {
            Ok(a) => a,
            Err(_) => {
                st.dead = true;
                shared.answered.notify_all();
                return;
            }
        };
        let hung = matches!(answer, Answer::Hung);
        if let Some(o) = st.open.as_mut().filter(|o| o.number == number) {
            if !o.preview_answered {
                o.preview_answered = true;
                // Only a rendered preview is followed by the full image.
                o.full_expected &= matches!(answer, Answer::Image(_));
                if let Answer::Image(p) = answer {
                    o.stages.extend(write_preview(p, o.first_event, out));
                }
            } else if o.full_expected {
                o.full_expected = false;
                if let (Answer::Image(p), None) = (answer, o.full_by) {
                    o.full_by = Some(By::Worker);
                    o.stages.extend(write_preview(p, o.first_event, out));
                }
            }
        }
        st.dead |= hung;
        shared.answered.notify_all();
    }
}

/// Writes a worker's image (a preview, or the full image) to the output;
/// its stage report, or None if it could not be written.
fn write_preview(p: Preview, first_event: Instant, out: &Mutex<Output>) -> Option<StageReport> {
    let frame = StageFrame {
        image: p.image,
        compile: CompileTimes {
            naga: p.compile[0],
            pipeline: p.compile[1],
            driver: p.compile[2],
            recompiled: Vec::new(),
        },
        render: p.render,
        hits_reused: p.hits_reused,
    };
    let stage = out
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .write_stage(frame, p.full, p.lit_by_default, first_event)
        .ok()?;
    Some(StageReport {
        worker: true,
        ..stage
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn requests_and_answers_survive_the_pipe() {
        let req = Request {
            number: 7,
            changes: Changes {
                shaders: true,
                scene: false,
            },
            textures: vec![PathBuf::from("/a/b c.png"), PathBuf::from("/é\n.png")],
            full: true,
        };
        let mut buf = Vec::new();
        req.write(&mut buf).unwrap();
        let mut r = buf.as_slice();
        assert_eq!(Request::read(&mut r).unwrap(), Some(req));
        assert_eq!(Request::read(&mut r).unwrap(), None, "end of stream");

        let p = Preview {
            image: Image {
                width: 2,
                height: 1,
                pixels: vec![[0.25, 0.5, 1.0, 1.0], [f32::MAX, 0.0, -0.0, 1.0]],
            },
            full: (8, 4),
            lit_by_default: true,
            compile: [
                Duration::from_micros(1),
                Duration::from_millis(2),
                Duration::from_millis(60),
            ],
            render: Duration::from_micros(900),
            hits_reused: true,
        };
        let whole = Answer::Image(Preview {
            full: (2, 1),
            ..p.clone()
        });
        for a in [Answer::Image(p), whole, Answer::Nothing, Answer::Hung] {
            let mut buf = Vec::new();
            a.write(9, &mut buf).unwrap();
            assert_eq!(Answer::read(&mut buf.as_slice()).unwrap(), (9, a));
        }
    }

    #[test]
    fn a_broken_answer_is_an_error_not_an_allocation() {
        // An image of 2^32 - 1 × 2^32 - 1 pixels.
        let mut buf = Vec::new();
        put_u64(&mut buf, 1).unwrap();
        buf.extend([2, 0, 0]);
        for v in [u32::MAX, u32::MAX, u32::MAX, u32::MAX] {
            put_u32(&mut buf, v).unwrap();
        }
        assert!(Answer::read(&mut buf.as_slice()).is_err());
        // A preview larger than its full image.
        let mut buf = Vec::new();
        put_u64(&mut buf, 1).unwrap();
        buf.extend([2, 0, 0]);
        for v in [16, 16, 8, 8] {
            put_u32(&mut buf, v).unwrap();
        }
        assert!(Answer::read(&mut buf.as_slice()).is_err());
        // An unknown kind, and a truncated request.
        let mut buf = Vec::new();
        put_u64(&mut buf, 1).unwrap();
        buf.push(9);
        assert!(Answer::read(&mut buf.as_slice()).is_err());
        let mut buf = Vec::new();
        put_u64(&mut buf, 1).unwrap();
        buf.push(1);
        put_u32(&mut buf, u32::MAX).unwrap();
        assert!(Request::read(&mut buf.as_slice()).is_err());
    }
}
