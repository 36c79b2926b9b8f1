//! `penumbra calibrate`: times lavapipe's candidate settings on this machine
//! (each in a child process: `penumbra calibrate --probe CANDIDATE`, since
//! Mesa reads its variables when the driver loads) and remembers them in the
//! user's cache directory (src/calibration). A long `render` with no
//! calibration runs it by itself once the render is done; short renders and
//! `watch` use the one remembered, if any, and never measure.

use std::io::Read as _;
use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use anyhow::{bail, Context as _};
use serde::{Deserialize, Serialize};

use penumbra::calibration::wisdom::{self, Entry, Key, Wisdom};
use penumbra::calibration::{self, probe, Candidate, Measured, CAPS_VARIABLE};
use penumbra::render::{Renderer, RendererOptions};
use penumbra::terminal;
use penumbra::vector_width::{self, Choice, CpuVectors, Job, Request};
use penumbra::vulkan::{DeviceInfo, DeviceSelector};

/// Rounds of the interleaved measurement: each runs every candidate once.
pub const ROUNDS: usize = 3;
/// Frames each probe times after its first (which pays the compile).
pub const FRAMES: usize = 8;
/// The most a whole calibration may take; past it the probe in flight is
/// ended and nothing is remembered.
pub const CAP: Duration = Duration::from_secs(60);

/// For tests: `cpu=NAME;driver=NAME;256=MS,MS;512=MS;256-avx2=MS[;log=FILE]`
/// makes the probes report these frame times and this driver without
/// loading Vulkan, and the calibration's key use this CPU; with `log`, each
/// probe appends its candidate's name to FILE. So every branch runs on any
/// machine, whatever its CPU.
pub const FAKE_VARIABLE: &str = "PENUMBRA_CALIBRATION_FAKE";

#[derive(clap::Args)]
pub struct CalibrateArgs {
    /// Vulkan device to calibrate: an index from `penumbra devices`, or part
    /// of its name (the knobs are lavapipe's; a GPU has none).
    #[arg(long)]
    device: Option<DeviceSelector>,
    /// Time one candidate (256, 512 or 256-avx2) in this process and print
    /// its frame times as JSON: what `calibrate` runs in each child process,
    /// with the candidate's variables set.
    #[arg(long, value_name = "CANDIDATE")]
    probe: Option<String>,
}

pub fn run(args: CalibrateArgs) -> anyhow::Result<()> {
    if let Some(name) = &args.probe {
        return run_probe(name, args.device);
    }
    let fake = Fake::from_env()?;
    let cpu = CpuVectors::detect();
    let candidates = match &fake {
        Some(f) => f.times.iter().map(|(c, _)| *c).collect(),
        None => calibration::candidates(cpu),
    };
    let path = wisdom_path()?;
    if candidates.is_empty() {
        println!("calibrate: this CPU has no AVX-512: lavapipe's default (256 bits on AVX, else 128) is all there is to run; nothing measured");
        return Ok(());
    }
    let (entry, walls) = measure(&candidates, args.device.as_ref(), fake.as_ref())?;
    for (m, w) in entry.measured.iter().zip(&walls) {
        println!(
            "{:<20} median {:.2} ms [{:.2}–{:.2}] of CPU time a frame, {} frames (wall {:.2} ms [{:.2}–{:.2}])",
            m.candidate.describe(),
            m.median_ms,
            m.min_ms,
            m.max_ms,
            m.frames,
            w.median_ms,
            w.min_ms,
            w.max_ms
        );
    }
    for (what, job) in [
        ("long renders", LONG),
        ("short renders and watch", Job::Watch),
    ] {
        let c = vector_width::choose(
            Request::Auto,
            None,
            cpu_for(&fake, cpu),
            job,
            Some(&entry.measured),
        );
        println!("{what}: {c}");
    }
    remember(&path, entry)?;
    println!(
        "remembered in {}",
        terminal::escape(&path.display().to_string())
    );
    if std::env::var_os(vector_width::VARIABLE).is_some()
        || std::env::var_os(CAPS_VARIABLE).is_some()
    {
        println!(
            "note: {} or {CAPS_VARIABLE} in this environment still wins over the calibration",
            vector_width::VARIABLE
        );
    }
    Ok(())
}

/// A long render, to print its choice.
const LONG: Job = Job::Render {
    pixels: None,
    passes: u32::MAX,
    time_budget: None,
};

/// The CPU the choice is for: with a fake, one with AVX-512 (the fake's
/// candidates say what there is to choose from).
fn cpu_for(fake: &Option<Fake>, cpu: CpuVectors) -> CpuVectors {
    match fake {
        Some(_) => CpuVectors {
            avx: true,
            avx512f: true,
        },
        None => cpu,
    }
}

/// The settings of a render or `watch`, chosen before the driver loads, the
/// calibration they came from (to check its driver against the device's),
/// and the calibration still to run after the render, if any.
pub struct Settings {
    /// What was chosen and why.
    pub choice: Choice,
    /// The calibration used, and its file.
    used: Option<(Entry, PathBuf)>,
    fake_driver: Option<String>,
    /// A long render with no calibration: what [`Settings::calibrate_if_due`] measures.
    due: Option<Due>,
}

/// A calibration to run after the render.
struct Due {
    candidates: Vec<Candidate>,
    device: Option<DeviceSelector>,
    path: PathBuf,
    fake: Option<Fake>,
}

/// Chooses lavapipe's settings for `job` and puts them in the environment
/// (call it before the Vulkan driver loads). The user's flag and variables
/// win; else this machine's calibration; where there is none, the default,
/// and if `may_calibrate` and the job is long, the calibration is due after
/// the render ([`Settings::calibrate_if_due`]): a render that fails (bad
/// input) never pays for it, and the render is not held up by it.
pub fn settings(
    request: Request,
    job: Job,
    device: Option<&DeviceSelector>,
    may_calibrate: bool,
) -> anyhow::Result<Settings> {
    let fake = Fake::from_env()?;
    let user_set = request != Request::Auto
        || std::env::var_os(vector_width::VARIABLE).is_some()
        || std::env::var_os(CAPS_VARIABLE).is_some();
    let cpu = cpu_for(&fake, CpuVectors::detect());
    let candidates: Vec<Candidate> = match &fake {
        Some(f) => f.times.iter().map(|(c, _)| *c).collect(),
        None => calibration::candidates(cpu),
    };
    let mut used = None;
    let mut due = None;
    if let (false, false, Ok(path)) = (user_set, candidates.is_empty(), wisdom_path()) {
        let key_cpu = key_cpu(fake.as_ref());
        match read_wisdom(&path).find(&key_cpu, &wisdom::this_kernel()) {
            Some(e) => used = Some((e.clone(), path)),
            None if may_calibrate && job.is_long() => {
                due = Some(Due {
                    candidates,
                    device: device.cloned(),
                    path,
                    fake: fake.clone(),
                })
            }
            None => {}
        }
    }
    let measured = used.as_ref().map(|(e, _)| e.measured.as_slice());
    let choice = vector_width::apply_for(cpu, request, job, measured);
    Ok(Settings {
        choice,
        used,
        fake_driver: fake.map(|f| f.driver),
        due,
    })
}

impl Settings {
    /// After a successful long render with no calibration of this machine:
    /// calibrates now (saying so on stderr) for the renders after it. A
    /// failure is a note: the render itself succeeded.
    pub fn calibrate_if_due(&self) {
        let Some(due) = &self.due else {
            return;
        };
        eprintln!(
            "note: calibrating lavapipe on this machine for the long renders after this one (once, at most {} s; remembered in {})",
            CAP.as_secs(),
            terminal::escape(&due.path.display().to_string())
        );
        let done = measure(&due.candidates, due.device.as_ref(), due.fake.as_ref())
            .and_then(|(e, _)| remember(&due.path, e));
        if let Err(e) = done {
            eprintln!(
                "note: calibration failed: {}",
                terminal::diagnostic(&format!("{e:#}"))
            );
        }
    }

    /// After the device is made: a calibration made with another driver is
    /// stale (the settings it chose stay for this run): it is dropped from
    /// the file with a note, and the next long render or `penumbra
    /// calibrate` measures again.
    pub fn check_driver(&self, device: &DeviceInfo) {
        let Some((entry, path)) = &self.used else {
            return;
        };
        if device.device_type != "CPU" && self.fake_driver.is_none() {
            return;
        }
        let driver = self
            .fake_driver
            .clone()
            .unwrap_or_else(|| driver_of(device));
        if entry.key.driver == driver {
            return;
        }
        eprintln!(
            "note: {}: calibrated with driver `{}`, this is `{}`: forgotten; the next long render or `penumbra calibrate` measures again",
            terminal::escape(&path.display().to_string()),
            terminal::escape(&entry.key.driver),
            terminal::escape(&driver)
        );
        let mut w = read_wisdom(path);
        w.remove(&entry.key.cpu, &entry.key.kernel);
        if let Err(e) = w.write(path) {
            eprintln!(
                "note: {}: {e}",
                terminal::escape(&path.display().to_string())
            );
        }
    }
}

/// The calibration file, from the environment.
fn wisdom_path() -> anyhow::Result<PathBuf> {
    wisdom::path(|k| std::env::var_os(k))
        .context("calibrate: no cache directory (neither XDG_CACHE_HOME nor HOME is set)")
}

/// The file's calibrations; a file that cannot be read as one is ignored
/// with a note.
fn read_wisdom(path: &std::path::Path) -> Wisdom {
    match Wisdom::read(path) {
        Ok(w) => w.unwrap_or_default(),
        Err(why) => {
            eprintln!(
                "note: {}: not a calibration of this version ({}): ignored",
                terminal::escape(&path.display().to_string()),
                terminal::diagnostic(&why)
            );
            Wisdom::default()
        }
    }
}

/// Puts `entry` in the file (atomically); a file that cannot be read as a
/// calibration (already noted) is replaced.
fn remember(path: &std::path::Path, entry: Entry) -> anyhow::Result<()> {
    let mut w = Wisdom::read(path).ok().flatten().unwrap_or_default();
    w.insert(entry);
    w.write(path)
        .with_context(|| format!("{}: writing the calibration", path.display()))
}

fn key_cpu(fake: Option<&Fake>) -> String {
    match fake {
        Some(f) => f.cpu.clone(),
        None => wisdom::this_cpu(),
    }
}

/// The driver as the key names it.
fn driver_of(d: &DeviceInfo) -> String {
    format!("{} {}", d.driver_name, d.driver_info)
        .trim()
        .to_owned()
}

/// What a probe prints: one line of JSON.
#[derive(Serialize, Deserialize)]
struct ProbeReport {
    device: String,
    device_type: String,
    driver: String,
    /// The CPU time of each frame (what the choice is made on).
    frames_ms: Vec<f64>,
    /// The wall time of each frame's render phase (shown only).
    wall_ms: Vec<f64>,
}

/// Times every candidate in child processes, interleaved: [`ROUNDS`] rounds
/// that each run every candidate once, [`FRAMES`] frames each, within [`CAP`].
/// The entry holds the frames' CPU time; the wall times are returned beside
/// it, to show.
fn measure(
    candidates: &[Candidate],
    device: Option<&DeviceSelector>,
    fake: Option<&Fake>,
) -> anyhow::Result<(Entry, Vec<Measured>)> {
    let deadline = Instant::now() + CAP;
    let mut frames: Vec<Vec<f64>> = vec![Vec::new(); candidates.len()];
    let mut walls: Vec<Vec<f64>> = vec![Vec::new(); candidates.len()];
    let mut driver = String::new();
    for _ in 0..ROUNDS {
        for (i, c) in candidates.iter().enumerate() {
            let r = probe_child(*c, device, deadline)?;
            if r.device_type != "CPU" && fake.is_none() {
                // A GPU: lavapipe's knobs do not apply. Remembered as such.
                let entry = Entry {
                    key: Key {
                        cpu: key_cpu(fake),
                        kernel: wisdom::this_kernel(),
                        driver: r.driver,
                    },
                    measured: Vec::new(),
                };
                return Ok((entry, Vec::new()));
            }
            driver = r.driver;
            frames[i].extend(r.frames_ms);
            walls[i].extend(r.wall_ms);
        }
    }
    let measured = candidates
        .iter()
        .zip(&frames)
        .map(|(c, f)| {
            Measured::of(*c, f)
                .with_context(|| format!("calibrate: the {} probe gave no frame times", c.name()))
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    let walls = candidates
        .iter()
        .zip(&walls)
        .filter_map(|(c, w)| Measured::of(*c, w))
        .collect();
    let entry = Entry {
        key: Key {
            cpu: key_cpu(fake),
            kernel: wisdom::this_kernel(),
            driver,
        },
        measured,
    };
    Ok((entry, walls))
}

/// Runs `penumbra calibrate --probe C` with C's environment, ending it at
/// `deadline`.
fn probe_child(
    c: Candidate,
    device: Option<&DeviceSelector>,
    deadline: Instant,
) -> anyhow::Result<ProbeReport> {
    let exe = std::env::current_exe().context("calibrate: finding this program")?;
    let mut cmd = Command::new(exe);
    cmd.args(["calibrate", "--probe", c.name()]);
    match device {
        Some(DeviceSelector::Index(i)) => cmd.args(["--device", &i.to_string()]),
        Some(DeviceSelector::Name(n)) => cmd.args(["--device", n]),
        None => &mut cmd,
    };
    cmd.env(vector_width::VARIABLE, c.bits().to_string());
    match c.caps() {
        Some(caps) => cmd.env(CAPS_VARIABLE, caps),
        None => cmd.env_remove(CAPS_VARIABLE),
    };
    // The width's own shader cache, as a render at it would use.
    if let Some(dir) = vector_width::cache_dir(c.bits(), |k| std::env::var_os(k)) {
        let _ = std::fs::create_dir_all(&dir);
        cmd.env(vector_width::CACHE_VARIABLE, dir);
    }
    let mut child = cmd
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .context("calibrate: starting a probe")?;
    let status = loop {
        if let Some(s) = child.try_wait()? {
            break s;
        }
        if Instant::now() >= deadline {
            let _ = child.kill();
            let _ = child.wait();
            bail!(
                "calibrate: the {} probe ran past the cap of {} s",
                c.name(),
                CAP.as_secs()
            );
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let mut out = String::new();
    let mut err = String::new();
    if let Some(mut o) = child.stdout.take() {
        o.read_to_string(&mut out)?;
    }
    if let Some(mut e) = child.stderr.take() {
        e.read_to_string(&mut err)?;
    }
    if !status.success() {
        let why = err
            .lines()
            .find(|l| l.starts_with("error:"))
            .unwrap_or(err.trim());
        bail!(
            "calibrate: the {} probe failed: {}",
            c.name(),
            why.trim_start_matches("error: ")
        );
    }
    serde_json::from_str(out.trim())
        .with_context(|| format!("calibrate: the {} probe's report", c.name()))
}

/// `penumbra calibrate --probe C`: the frame times of this process's settings.
fn run_probe(name: &str, device: Option<DeviceSelector>) -> anyhow::Result<()> {
    let c = Candidate::from_name(name)
        .with_context(|| format!("--probe: unknown candidate `{name}`"))?;
    let report = match Fake::from_env()? {
        Some(f) => {
            if let Some(log) = &f.log {
                use std::io::Write as _;
                let mut file = std::fs::OpenOptions::new()
                    .create(true)
                    .append(true)
                    .open(log)?;
                writeln!(file, "{}", c.name())?;
            }
            let frames_ms = f
                .times
                .iter()
                .find(|(k, _)| *k == c)
                .map(|(_, t)| t.clone())
                .with_context(|| format!("{FAKE_VARIABLE}: no times for {name}"))?;
            ProbeReport {
                device: "fake".into(),
                device_type: "CPU".into(),
                driver: f.driver,
                wall_ms: frames_ms.clone(),
                frames_ms,
            }
        }
        None => {
            let mut renderer = Renderer::new(&RendererOptions {
                device,
                ..Default::default()
            })?;
            let times = probe::frame_times(&mut renderer, FRAMES)?;
            let d = renderer.device();
            ProbeReport {
                device: d.name.clone(),
                device_type: d.device_type.clone(),
                driver: driver_of(d),
                frames_ms: times.iter().map(|t| t.cpu.as_secs_f64() * 1e3).collect(),
                wall_ms: times.iter().map(|t| t.wall.as_secs_f64() * 1e3).collect(),
            }
        }
    };
    println!("{}", serde_json::to_string(&report)?);
    Ok(())
}

/// The fake measurement of [`FAKE_VARIABLE`].
#[derive(Clone)]
struct Fake {
    cpu: String,
    driver: String,
    times: Vec<(Candidate, Vec<f64>)>,
    log: Option<PathBuf>,
}

impl Fake {
    fn from_env() -> anyhow::Result<Option<Fake>> {
        match std::env::var(FAKE_VARIABLE) {
            Ok(v) => Fake::parse(&v)
                .map(Some)
                .map_err(|e| anyhow::anyhow!("{FAKE_VARIABLE}: {e}")),
            Err(_) => Ok(None),
        }
    }

    fn parse(v: &str) -> Result<Fake, String> {
        let mut f = Fake {
            cpu: String::new(),
            driver: String::new(),
            times: Vec::new(),
            log: None,
        };
        for part in v.split(';').filter(|p| !p.is_empty()) {
            let (k, val) = part
                .split_once('=')
                .ok_or(format!("`{part}` is not NAME=VALUE"))?;
            match k {
                "cpu" => f.cpu = val.into(),
                "driver" => f.driver = val.into(),
                "log" => f.log = Some(val.into()),
                _ => {
                    let c = Candidate::from_name(k).ok_or(format!("unknown candidate `{k}`"))?;
                    let t = val
                        .split(',')
                        .map(|x| x.parse::<f64>().map_err(|_| format!("`{x}` is not a time")))
                        .collect::<Result<Vec<_>, _>>()?;
                    f.times.push((c, t));
                }
            }
        }
        if f.cpu.is_empty() || f.driver.is_empty() {
            return Err("needs cpu= and driver=".into());
        }
        Ok(f)
    }
}
