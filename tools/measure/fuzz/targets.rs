//! What a case runs: the scene loaders on a file in the worker's folder, the
//! WGSL compiler on the kernel with one shading file replaced, or a user's
//! shader file through reflection, assembly, pruning and SPIR-V.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use penumbra::loaders::{load_scene, LoadOptions};
use penumbra::render::compile::{Assembled, ShaderSource};
use penumbra::render::shade::ProgramFile;
use penumbra::render::{KernelOptions, StageKernel};
use penumbra::scene::Features;

use super::judge::{self, Verdict};

/// The loaders and the compiler that the harness feeds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Target {
    /// A JSON scene (`load_scene` on `.json`).
    Json,
    /// A `.gltf` file.
    Gltf,
    /// A `.glb` file.
    Glb,
    /// A shading WGSL file in the full kernel (naga parse, validation, SPIR-V).
    Wgsl,
    /// A part file of a split render (`.exr`), merged with a valid second
    /// part by `penumbra merge`'s `plan` and `write`.
    Part,
    /// A request head to the live page's parser (`watch --serve`).
    Request,
    /// An image (PNG, JPEG or OpenEXR bytes) through the texture loader
    /// under a small memory budget (module `texture`).
    Texture,
    /// A user's shader file (`"type": "wgsl"`): reflection and the checks
    /// before naga (`scene::shading`), the shade program's assembly, naga,
    /// pruning and SPIR-V (`render::shade`, `render::compile`).
    Shader,
}

impl Target {
    /// All targets.
    pub const ALL: [Target; 8] = [
        Target::Json,
        Target::Gltf,
        Target::Glb,
        Target::Wgsl,
        Target::Part,
        Target::Request,
        Target::Texture,
        Target::Shader,
    ];

    /// Whether a case compiles WGSL (about a hundred loader cases' time).
    pub fn compiles(self) -> bool {
        matches!(self, Target::Wgsl | Target::Shader)
    }

    /// The file extension (also the name on the command line).
    pub fn ext(self) -> &'static str {
        match self {
            Target::Json => "json",
            Target::Gltf => "gltf",
            Target::Glb => "glb",
            Target::Wgsl => "wgsl",
            Target::Part => "exr",
            Target::Request => "request",
            Target::Texture => "texture",
            Target::Shader => "shader",
        }
    }

    /// Parses [`Target::ext`].
    pub fn from_ext(s: &str) -> Option<Target> {
        Target::ALL.into_iter().find(|t| t.ext() == s)
    }
}

/// The outcome of one case.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// The verdict.
    pub verdict: Verdict,
    /// The error or panic message (empty for `Ok`).
    pub message: String,
    /// Wall time of the case.
    pub time: Duration,
    /// Peak bytes allocated by the case.
    pub peak: usize,
}

/// Writes a case file; a failure is an outcome of its own (not the loader's).
fn write_case(path: &Path, data: &[u8]) -> Result<(), Outcome> {
    std::fs::write(path, data).map_err(|e| Outcome {
        verdict: Verdict::Err,
        message: format!("cannot write the case: {e}"),
        time: Duration::ZERO,
        peak: 0,
    })
}

/// A worker's folder: the case file, the files seeds reference, and the
/// traps that mutated URIs point at (a FIFO, a file outside the folder).
pub struct Workspace {
    /// The scene folder, where case files are written.
    pub dir: PathBuf,
    _keep: tempfile::TempDir,
    kernel: Assembled,
    features: Features,
}

impl Workspace {
    /// Sets up a workspace in a new temporary folder.
    pub fn new(root: &Path) -> std::io::Result<Workspace> {
        let keep = tempfile::tempdir()?;
        let dir = keep.path().join("scene");
        std::fs::create_dir(&dir)?;
        std::fs::copy(root.join("scenes/bunny.glb"), dir.join("bunny.glb"))?;
        // The user shader of the generated scenes (seeds.rs).
        std::fs::create_dir(dir.join("shaders"))?;
        std::fs::copy(
            root.join("scenes/shaders/toon.wgsl"),
            dir.join("shaders/toon.wgsl"),
        )?;
        std::fs::write(keep.path().join("outside.bin"), [0u8; 256])?;
        let fifo = std::ffi::CString::new(dir.join("fifo.bin").as_os_str().as_encoded_bytes())
            .map_err(std::io::Error::other)?;
        // SAFETY: a valid NUL-terminated path.
        if unsafe { libc::mkfifo(fifo.as_ptr(), 0o600) } != 0 {
            return Err(std::io::Error::last_os_error());
        }
        // The valid part that each mutated one is merged with.
        std::fs::write(dir.join("other.exr"), super::seeds::part(1).1)?;
        let kernel = ShaderSource::Embedded
            .assemble()
            .map_err(std::io::Error::other)?;
        let features = load_scene(&root.join("scenes/showcase.json"), &LoadOptions::default())
            .map_err(std::io::Error::other)?
            .scene
            .features();
        Ok(Workspace {
            dir,
            _keep: keep,
            kernel,
            features,
        })
    }

    /// The path a case of `target` is written to.
    pub fn case_path(&self, target: Target) -> PathBuf {
        self.dir.join(format!("case.{}", target.ext()))
    }

    /// The kernel text with shading file `name` (e.g. `phong.wgsl`) replaced by `text`.
    fn kernel_with(&self, name: &str, text: &str) -> Assembled {
        let mut out = String::new();
        let mut files = Vec::new();
        let mut line = 1u32;
        let lines: Vec<&str> = self.kernel.text.lines().collect();
        for (label, start, count) in &self.kernel.files {
            let body = if label.ends_with(&format!("shading/{name}")) {
                text.to_string()
            } else {
                let (a, b) = (*start as usize - 1, (*start + *count) as usize - 1);
                lines[a..b.min(lines.len())].join("\n")
            };
            out.push_str(&body);
            out.push('\n');
            let n = body.lines().count() as u32;
            files.push((label.clone(), line, n));
            line += n;
        }
        Assembled {
            text: out,
            files,
            subject: None,
        }
    }

    /// Runs one case and judges it. `name` is the seed's file name (for WGSL:
    /// which shading file the text replaces).
    pub fn run(&self, target: Target, data: &[u8], name: &str, restrict: bool) -> Outcome {
        let (len, result): (usize, Result<Result<(), String>, String>);
        let start = judge::current();
        let t0 = Instant::now();
        match target {
            Target::Wgsl => {
                let text = String::from_utf8_lossy(data);
                // The staged renderer (issue 13): Phong and Blinn-Phong are
                // shade programs of their own; the other shading files are
                // part of the engine stages.
                let shade = matches!(name, "phong.wgsl" | "blinn_phong.wgsl");
                let kernel = self.kernel_with(name, &text);
                len = if shade { text.len() } else { kernel.text.len() };
                judge::start_case();
                result = penumbra::panics::catch(|| {
                    if shade {
                        let file = ProgramFile::User(format!("shading/{name}").into());
                        let source = penumbra::render::shade::assemble(
                            &ShaderSource::Embedded,
                            &file,
                            &text,
                        )
                        .map_err(|e| e.to_string())?;
                        return source
                            .assembled
                            .compile_entry(
                                &Default::default(),
                                penumbra::render::shade::SHADE_ENTRY_POINT,
                            )
                            .map(|_| ())
                            .map_err(|e| e.to_string());
                    }
                    kernel
                        .compile_frame(&self.features, &KernelOptions::default())
                        .map(|_| ())
                        .map_err(|e| e.to_string())
                });
            }
            Target::Shader => {
                let text = String::from_utf8_lossy(data);
                len = text.len();
                let file = ProgramFile::User(self.case_path(target));
                // Every feature the shade stage sees, textures included, so
                // that pruning keeps the most code.
                let key = StageKernel {
                    features: penumbra::render::shade::variant(&Features {
                        textures: true,
                        ..self.features
                    }),
                    ..Default::default()
                };
                judge::start_case();
                result = penumbra::panics::catch(|| {
                    penumbra::render::shade::assemble(&ShaderSource::Embedded, &file, &text)
                        .and_then(|source| {
                            source
                                .assembled
                                .compile_entry(&key, penumbra::render::shade::SHADE_ENTRY_POINT)
                        })
                        .map(|_| ())
                        .map_err(|e| e.to_string())
                });
            }
            Target::Part => {
                let path = self.case_path(target);
                let other = self.dir.join("other.exr");
                len = data.len() + std::fs::metadata(&other).map_or(0, |m| m.len() as usize);
                if let Err(o) = write_case(&path, data) {
                    return o;
                }
                let out = self
                    .dir
                    .join(if restrict { "merged.png" } else { "merged.exr" });
                judge::start_case();
                result = penumbra::panics::catch(|| {
                    let plan = penumbra::farm::merge::plan(&[path.clone(), other.clone()])
                        .map_err(|e| format!("{e:#}"))?;
                    penumbra::farm::merge::write(&plan, &out, Default::default())
                        .map_err(|e| format!("{e:#}"))
                });
            }
            Target::Request => {
                len = data.len();
                if let Err(o) = write_case(&self.case_path(target), data) {
                    return o;
                }
                judge::start_case();
                result = penumbra::panics::catch(|| super::request::run(data));
            }
            Target::Texture => {
                len = data.len();
                // Well inside the judge's limit, as for the scenes.
                let budget = (judge::allowed(len) / 2) as u64;
                judge::start_case();
                result = penumbra::panics::catch(|| super::texture::run(data, budget));
            }
            _ => {
                let path = self.case_path(target);
                len = data.len() + 67 * 1024; // the case and the bunny.glb it may reference
                if let Err(o) = write_case(&path, data) {
                    return o;
                }
                let opts = LoadOptions {
                    restrict_paths: restrict,
                    // Well inside the judge's limit: the loaders' own budget
                    // must refuse amplification before the judge sees it.
                    max_scene_bytes: (judge::allowed(len) / 2) as u64,
                    ..Default::default()
                };
                judge::start_case();
                result = penumbra::panics::catch(|| {
                    load_scene(&path, &opts)
                        .map(|_| ())
                        .map_err(|e| e.to_string())
                });
            }
        }
        let time = t0.elapsed();
        let peak = match target.compiles() {
            true => judge::case_peak(start).max(judge::case_peak_all()),
            false => judge::case_peak(start),
        };
        // Messages name the case file; without its temporary folder they
        // are the same from run to run.
        let folder = format!("{}/", self.dir.display());
        let result = result.map(|r| r.map_err(|e| e.replace(&folder, "")));
        let (verdict, message) = match result {
            Err(panic) => (Verdict::Panic, panic),
            // A panic caught at a dependency boundary is still a bug to fix.
            Ok(Err(e)) if e.contains("internal error") => (Verdict::Panic, e),
            _ if time > judge::HANG && len < 1 << 20 => (Verdict::Hang, format!("{time:?}")),
            _ if peak > judge::allowed(len) => (
                Verdict::Huge,
                format!("{peak} bytes for {len} bytes of input"),
            ),
            Ok(Ok(())) => (Verdict::Ok, String::new()),
            Ok(Err(e)) => (Verdict::Err, e),
        };
        Outcome {
            verdict,
            message,
            time,
            peak,
        }
    }
}
