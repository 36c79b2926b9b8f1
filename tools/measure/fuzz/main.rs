//! The fuzzing harness: mutates the project's scenes, glTF files and shading
//! WGSL and feeds them to the loaders and the compiler, judging each case as
//! a clean `Err`, success, or a bug (panic, hang, huge allocation, crash).
//!
//! ```text
//! cargo run --release -p penumbra-tools --bin fuzz -- [--cases N] [--seconds S] [--seed S]
//!     [--jobs J] [--targets json,gltf,glb,wgsl,exr,request,texture,shader] [--out DIR]
//! cargo run --release -p penumbra-tools --bin fuzz -- --replay FILE...
//! cargo run --release -p penumbra-tools --bin fuzz -- --write-seeds DIR
//! ```
//!
//! Runs on stable Rust without cargo-fuzz. Cases run in worker processes
//! (this program with `--worker`), so an abort or a stack overflow is caught
//! as a crash and the worker restarted; the supervisor saves every failing
//! input under `--out` (default `target/fuzz/failures`) and exits non-zero
//! when any case is a bug. docs/fuzz.md has the figures of a million-case run.

mod judge;
mod mutate;
mod request;
mod seeds;
mod targets;
mod texture;

use std::collections::BTreeMap;
use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode, Stdio};
use std::time::{Duration, Instant};

use judge::Verdict;
use mutate::Rng;
use targets::{Target, Workspace};

#[global_allocator]
static ALLOC: judge::Counting = judge::Counting;

/// The command line.
#[derive(Clone, Debug)]
struct Args {
    cases: u64,
    seconds: Option<f64>,
    seed: u64,
    jobs: usize,
    targets: Vec<Target>,
    out: PathBuf,
    worker: Option<usize>,
    replay: Vec<PathBuf>,
    write_seeds: Option<PathBuf>,
}

fn usage(msg: &str) -> ! {
    eprintln!("error: {msg}");
    eprintln!(
        "usage: fuzz [--cases N] [--seconds S] [--seed S] [--jobs J] [--targets json,gltf,glb,wgsl,exr,request,texture,shader] [--out DIR] | --replay FILE..."
    );
    std::process::exit(2)
}

fn parse_args() -> Args {
    let mut a = Args {
        cases: 100_000,
        seconds: None,
        seed: 1,
        jobs: 1,
        targets: Target::ALL.to_vec(),
        out: seeds::root().join("target/fuzz/failures"),
        worker: None,
        replay: Vec::new(),
        write_seeds: None,
    };
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        let mut value = |name: &str| {
            it.next()
                .unwrap_or_else(|| usage(&format!("{name} needs a value")))
        };
        let num = |name: &str, v: String| -> u64 {
            v.parse()
                .unwrap_or_else(|_| usage(&format!("{name}: expected a whole number, got `{v}`")))
        };
        match flag.as_str() {
            "--cases" => a.cases = num("--cases", value("--cases")),
            "--seconds" => {
                let v = value("--seconds");
                let s: f64 = v
                    .parse()
                    .ok()
                    .filter(|s: &f64| *s > 0.0 && s.is_finite())
                    .unwrap_or_else(|| {
                        usage(&format!("--seconds: expected a positive number, got `{v}`"))
                    });
                a.seconds = Some(s);
            }
            "--seed" => a.seed = num("--seed", value("--seed")),
            "--jobs" => a.jobs = num("--jobs", value("--jobs")).clamp(1, 64) as usize,
            "--targets" => {
                let v = value("--targets");
                a.targets = v
                    .split(',')
                    .map(|t| {
                        Target::from_ext(t)
                            .unwrap_or_else(|| usage(&format!("--targets: unknown target `{t}`")))
                    })
                    .collect();
            }
            "--out" => a.out = PathBuf::from(value("--out")),
            "--worker" => a.worker = Some(num("--worker", value("--worker")) as usize),
            "--replay" => a.replay.extend(it.by_ref().map(PathBuf::from)),
            "--write-seeds" => a.write_seeds = Some(PathBuf::from(value("--write-seeds"))),
            other => usage(&format!("unknown argument `{other}`")),
        }
    }
    a
}

fn main() -> ExitCode {
    let args = parse_args();
    // Panics are caught and judged per case; keep their default output quiet.
    std::panic::set_hook(Box::new(|_| {}));
    if !args.replay.is_empty() {
        return replay(&args.replay);
    }
    if let Some(dir) = &args.write_seeds {
        // The seeds as files, to replay or to feed another fuzzer.
        let _ = std::fs::create_dir_all(dir);
        for (i, s) in seeds::all().iter().enumerate() {
            let path = dir.join(format!("{i:02}.{}", s.target.ext()));
            if let Err(e) = std::fs::write(&path, &s.data) {
                eprintln!("error: {}: {e}", path.display());
                return ExitCode::FAILURE;
            }
            println!("{}: {}", path.display(), s.name);
        }
        return ExitCode::SUCCESS;
    }
    match args.worker {
        Some(id) => worker(&args, id),
        None => supervise(&args),
    }
}

/// `--replay`: runs each file through the target its extension names and
/// prints the verdict and message.
fn replay(files: &[PathBuf]) -> ExitCode {
    let ws = match Workspace::new(&seeds::root()) {
        Ok(ws) => ws,
        Err(e) => {
            eprintln!("error: cannot set up the workspace: {e}");
            return ExitCode::FAILURE;
        }
    };
    let mut bugs = 0;
    for f in files {
        let ext = f.extension().and_then(|e| e.to_str()).unwrap_or("");
        let Some(target) = Target::from_ext(ext) else {
            eprintln!("error: {}: unknown extension", f.display());
            return ExitCode::FAILURE;
        };
        let data = std::fs::read(f).unwrap_or_default();
        // A WGSL file replaces the shading file of its name (else phong.wgsl).
        let name = f.file_name().and_then(|n| n.to_str()).unwrap_or("");
        let name = if seeds::shading_files().contains(&name) {
            name
        } else {
            "phong.wgsl"
        };
        let o = ws.run(target, &data, name, false);
        bugs += usize::from(o.verdict.is_bug());
        println!(
            "{}: {} in {:.1} ms, peak {} KiB: {}",
            f.display(),
            o.verdict.name(),
            o.time.as_secs_f64() * 1e3,
            o.peak / 1024,
            o.message
        );
    }
    if bugs > 0 {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    }
}

/// A failure's identity for counting distinct failures: the verdict and the
/// message with numbers and paths removed.
fn failure_key(verdict: Verdict, message: &str) -> String {
    let m: String = message
        .lines()
        .next()
        .unwrap_or("")
        .chars()
        .map(|c| if c.is_ascii_digit() { '#' } else { c })
        .collect();
    format!("{} {}", verdict.name(), m)
}

/// One worker process: runs cases, prints a `bug` line per failing case and
/// a `tally` line now and then (cumulative counts per verdict and target).
fn worker(args: &Args, id: usize) -> ExitCode {
    let root = seeds::root();
    let ws = match Workspace::new(&root) {
        Ok(ws) => ws,
        Err(e) => {
            eprintln!("error: worker {id}: cannot set up the workspace: {e}");
            return ExitCode::FAILURE;
        }
    };
    let seeds: Vec<_> = seeds::all()
        .into_iter()
        .filter(|s| args.targets.contains(&s.target))
        .collect();
    if seeds.is_empty() {
        eprintln!("error: no seeds for the targets asked for");
        return ExitCode::FAILURE;
    }
    let json_donors: Vec<serde_json::Value> = seeds
        .iter()
        .filter(|s| !s.target.compiles())
        .filter_map(|s| serde_json::from_slice(&s.data).ok())
        .collect();
    let byte_donors: Vec<Vec<u8>> = seeds.iter().map(|s| s.data.clone()).collect();
    let deadline = args
        .seconds
        .map(|s| Instant::now() + Duration::from_secs_f64(s));
    let mut rng = Rng::new(args.seed.wrapping_mul(1_000_003).wrapping_add(id as u64));
    let mut tally: BTreeMap<(Target, Verdict), u64> = BTreeMap::new();
    let out = std::io::stdout();
    {
        let mut w = out.lock();
        let _ = writeln!(w, "dir\t{}", ws.dir.display());
        let _ = w.flush();
    }
    let current = ws.dir.join("current");
    let stuck = watchdog(current.clone());
    let mut in_cases = Duration::ZERO;
    let mut last_target = None;
    for n in 0..args.cases {
        if deadline.is_some_and(|d| Instant::now() > d) {
            break;
        }
        let seed = pick_seed(&seeds, &mut rng).clone();
        let data = make_case(&seed, &json_donors, &byte_donors, &mut rng);
        // Written first, so that the supervisor can save the case if this
        // process dies: the target, and for WGSL and textures the bytes (a
        // scene case is the case file itself).
        if last_target != Some(seed.target) {
            let _ = std::fs::write(&current, format!("{}\n", seed.target.ext()));
            last_target = Some(seed.target);
        }
        if seed.target.compiles() || matches!(seed.target, Target::Texture) {
            let _ = std::fs::write(ws.case_path(seed.target), &data);
        }
        stuck.arm();
        let restrict = rng.one_in(4);
        let file_name = Path::new(&seed.name)
            .file_name()
            .map(|f| f.to_string_lossy().to_string())
            .unwrap_or_default();
        let o = ws.run(seed.target, &data, &file_name, restrict);
        stuck.disarm();
        *tally.entry((seed.target, o.verdict)).or_default() += 1;
        in_cases += o.time;
        if o.verdict.is_bug() {
            let saved = save(&args.out, seed.target, &data);
            let mut w = out.lock();
            let _ = writeln!(
                w,
                "bug\t{}\t{}\t{}\t{}",
                o.verdict.name(),
                seed.target.ext(),
                failure_key(o.verdict, &o.message),
                saved.display()
            );
        }
        if n % 500 == 499 {
            print_tally(&tally, in_cases);
        }
    }
    print_tally(&tally, in_cases);
    ExitCode::SUCCESS
}

/// A seed: WGSL (the kernel's or a user's shader file, equally often) for
/// one case in a hundred (a compile costs about a hundred loader cases),
/// else one of the scene seeds, each target equally often.
fn pick_seed<'s>(seeds: &'s [seeds::Seed], rng: &mut Rng) -> &'s seeds::Seed {
    let wgsl = seeds.iter().any(|s| s.target.compiles());
    let scenes = seeds.iter().any(|s| !s.target.compiles());
    let want_wgsl = wgsl && (!scenes || rng.one_in(100));
    let targets: Vec<Target> = Target::ALL
        .into_iter()
        .filter(|&t| t.compiles() == want_wgsl)
        .filter(|t| seeds.iter().any(|s| s.target == *t))
        .collect();
    let target = *rng.pick(&targets);
    let of: Vec<usize> = (0..seeds.len())
        .filter(|&i| seeds[i].target == target)
        .collect();
    &seeds[*rng.pick(&of)]
}

/// Ends the process when a case runs longer than [`judge::STUCK`]: the
/// supervisor then saves the case as a crash and starts a new worker.
struct Watchdog {
    armed: std::sync::Arc<std::sync::Mutex<Option<Instant>>>,
}

impl Watchdog {
    fn arm(&self) {
        *self.armed.lock().unwrap_or_else(|e| e.into_inner()) = Some(Instant::now());
    }
    fn disarm(&self) {
        *self.armed.lock().unwrap_or_else(|e| e.into_inner()) = None;
    }
}

fn watchdog(current: PathBuf) -> Watchdog {
    let armed = std::sync::Arc::new(std::sync::Mutex::new(None::<Instant>));
    let a = armed.clone();
    std::thread::spawn(move || loop {
        std::thread::sleep(Duration::from_millis(200));
        let since = *a.lock().unwrap_or_else(|e| e.into_inner());
        if since.is_some_and(|t| t.elapsed() > judge::STUCK) {
            let _ = std::fs::write(current.with_file_name("stuck"), b"1");
            std::process::exit(3);
        }
    });
    Watchdog { armed }
}

fn print_tally(tally: &BTreeMap<(Target, Verdict), u64>, in_cases: Duration) {
    let fields: Vec<String> = tally
        .iter()
        .map(|((t, v), n)| format!("{}:{}={n}", t.ext(), v.name()))
        .collect();
    let mut w = std::io::stdout().lock();
    let ms = in_cases.as_millis();
    let _ = writeln!(w, "tally\t{}\t{ms}", fields.join(" "));
    let _ = w.flush();
}

/// A mutated copy of a seed.
fn make_case(
    seed: &seeds::Seed,
    json_donors: &[serde_json::Value],
    byte_donors: &[Vec<u8>],
    rng: &mut Rng,
) -> Vec<u8> {
    match seed.target {
        Target::Wgsl => mutate::mutate_wgsl(&String::from_utf8_lossy(&seed.data), rng).into_bytes(),
        Target::Shader => {
            mutate::mutate_shader(&String::from_utf8_lossy(&seed.data), rng).into_bytes()
        }
        Target::Glb if rng.one_in(2) => {
            // Structure-aware on the JSON chunk, keeping the container valid.
            let mut data = seed.data.clone();
            if let Some((json, rest)) = glb_json(&data) {
                if let Ok(mut v) = serde_json::from_slice::<serde_json::Value>(json) {
                    mutate::mutate_json(&mut v, json_donors, rng);
                    data = seeds::glb(serde_json::to_vec(&v).unwrap_or_default(), rest);
                }
            }
            if rng.one_in(4) {
                mutate::mutate_bytes(&mut data, byte_donors, rng);
            }
            data
        }
        Target::Part => {
            let mut data = seed.data.clone();
            if rng.one_in(2) {
                mutate::mutate_exr_windows(&mut data, rng);
            }
            if rng.one_in(2) {
                mutate::mutate_bytes(&mut data, byte_donors, rng);
            }
            data
        }
        Target::Glb => {
            let mut data = seed.data.clone();
            mutate::mutate_bytes(&mut data, byte_donors, rng);
            data
        }
        Target::Request => request::mutate(&seed.data, byte_donors, rng),
        Target::Texture => texture::mutate(&seed.data, byte_donors, rng),
        Target::Json | Target::Gltf => {
            if rng.one_in(4) {
                let mut data = seed.data.clone();
                mutate::mutate_bytes(&mut data, byte_donors, rng);
                return data;
            }
            match serde_json::from_slice::<serde_json::Value>(&seed.data) {
                Ok(mut v) => {
                    mutate::mutate_json(&mut v, json_donors, rng);
                    let mut data = serde_json::to_vec(&v).unwrap_or_default();
                    if rng.one_in(8) {
                        mutate::mutate_bytes(&mut data, byte_donors, rng);
                    }
                    data
                }
                Err(_) => seed.data.clone(),
            }
        }
    }
}

/// The JSON chunk of a well-formed GLB and the bytes after it.
fn glb_json(data: &[u8]) -> Option<(&[u8], &[u8])> {
    let len = u32::from_le_bytes(data.get(12..16)?.try_into().ok()?) as usize;
    let json = data.get(20..20 + len)?;
    Some((json, data.get(20 + len..)?))
}

/// Saves a failing input under `out`, named by its content hash.
fn save(out: &Path, target: Target, data: &[u8]) -> PathBuf {
    use std::hash::{Hash, Hasher};
    let mut h = std::collections::hash_map::DefaultHasher::new();
    data.hash(&mut h);
    let path = out.join(format!("{:016x}.{}", h.finish(), target.ext()));
    let _ = std::fs::create_dir_all(out);
    let _ = std::fs::write(&path, data);
    path
}

/// The supervisor: splits the cases among `--jobs` workers, restarts a
/// worker that dies, and prints the report.
fn supervise(args: &Args) -> ExitCode {
    let t0 = Instant::now();
    let exe = match std::env::current_exe() {
        Ok(e) => e,
        Err(e) => {
            eprintln!("error: cannot find this program: {e}");
            return ExitCode::FAILURE;
        }
    };
    let per_job = args.cases.div_ceil(args.jobs as u64);
    let handles: Vec<_> = (0..args.jobs)
        .map(|id| {
            let (args, exe) = (args.clone(), exe.clone());
            std::thread::spawn(move || run_worker(&exe, &args, id, per_job, t0))
        })
        .collect();
    let mut tally: BTreeMap<(String, String), u64> = BTreeMap::new();
    let mut failures: BTreeMap<String, (u64, String)> = BTreeMap::new();
    let mut in_cases_ms = 0;
    for h in handles {
        let Ok(r) = h.join() else { continue };
        in_cases_ms += r.in_cases_ms;
        for (k, n) in r.tally {
            *tally.entry(k).or_default() += n;
        }
        for (k, (n, example)) in r.failures {
            let e = failures.entry(k).or_insert((0, example));
            e.0 += n;
        }
    }
    let elapsed = t0.elapsed().as_secs_f64();
    let total: u64 = tally.values().sum();
    let by_verdict = |v: Verdict| -> u64 {
        tally
            .iter()
            .filter(|((_, vv), _)| vv == v.name())
            .map(|(_, n)| n)
            .sum()
    };
    println!(
        "fuzz: {total} cases in {elapsed:.1} s ({:.0} cases/s), seed {}, {} jobs",
        total as f64 / elapsed.max(1e-9),
        args.seed,
        args.jobs
    );
    let counts: Vec<String> = Verdict::ALL
        .iter()
        .map(|&v| format!("{} {}", v.name(), by_verdict(v)))
        .collect();
    println!("verdicts: {}", counts.join(", "));
    println!(
        "time in the loaders and the compiler: {:.1} s of the workers' total",
        in_cases_ms as f64 / 1e3
    );
    for t in &args.targets {
        let row: Vec<String> = Verdict::ALL
            .iter()
            .filter_map(|v| {
                let n = tally.get(&(t.ext().to_string(), v.name().to_string()))?;
                Some(format!("{} {n}", v.name()))
            })
            .collect();
        println!("  {}: {}", t.ext(), row.join(", "));
    }
    println!("distinct failures: {}", failures.len());
    for (k, (n, example)) in &failures {
        println!("  {n} x {k}\n      e.g. {example}");
    }
    if failures.is_empty() && total > 0 {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    }
}

/// What one worker thread of the supervisor collected.
struct WorkerResult {
    in_cases_ms: u64,
    tally: BTreeMap<(String, String), u64>,
    failures: BTreeMap<String, (u64, String)>,
}

/// Runs worker `id` until it has done `cases` cases (or the time is up),
/// restarting it after a crash.
fn run_worker(exe: &Path, args: &Args, id: usize, cases: u64, t0: Instant) -> WorkerResult {
    let mut result = WorkerResult {
        in_cases_ms: 0,
        tally: BTreeMap::new(),
        failures: BTreeMap::new(),
    };
    let mut done = 0u64;
    let mut restart = 0u64;
    while done < cases {
        let left = args.seconds.map(|s| s - t0.elapsed().as_secs_f64());
        if left.is_some_and(|l| l <= 0.0) {
            break;
        }
        let targets: Vec<&str> = args.targets.iter().map(|t| t.ext()).collect();
        let mut cmd = Command::new(exe);
        cmd.arg("--worker")
            .arg(id.to_string())
            .arg("--cases")
            .arg((cases - done).to_string())
            .arg("--seed")
            .arg((args.seed + restart * 7919).to_string())
            .arg("--targets")
            .arg(targets.join(","))
            .arg("--out")
            .arg(&args.out)
            .stdin(Stdio::null())
            .stdout(Stdio::piped());
        if let Some(l) = left {
            cmd.arg("--seconds").arg(format!("{l:.3}"));
        }
        let mut child = match cmd.spawn() {
            Ok(c) => c,
            Err(e) => {
                eprintln!("error: cannot start a worker: {e}");
                break;
            }
        };
        let mut last = BTreeMap::new();
        let mut last_ms = 0u64;
        let mut dir = None;
        if let Some(stdout) = child.stdout.take() {
            for line in BufReader::new(stdout).lines().map_while(Result::ok) {
                let parts: Vec<&str> = line.split('\t').collect();
                match parts.as_slice() {
                    ["tally", fields, ms] => {
                        last = parse_tally(fields);
                        last_ms = ms.parse().unwrap_or(0);
                    }
                    ["bug", _verdict, _target, key, saved] => {
                        let e = result
                            .failures
                            .entry(key.to_string())
                            .or_insert((0, saved.to_string()));
                        e.0 += 1;
                    }
                    ["dir", d] => dir = Some(PathBuf::from(d)),
                    _ => {}
                }
            }
        }
        let status = child.wait().ok();
        let n: u64 = last.values().sum();
        for (k, v) in last {
            *result.tally.entry(k).or_default() += v;
        }
        done += n;
        result.in_cases_ms += last_ms;
        if status.is_some_and(|s| s.success()) {
            break;
        }
        // The worker died: its last case is a crash. Save it, and remove
        // the workspace that the dead process could not.
        done += 1;
        let mut saved = String::from("(not saved)");
        if let Some(dir) = dir {
            let ext = std::fs::read_to_string(dir.join("current")).unwrap_or_default();
            if let Some(target) = Target::from_ext(ext.trim()) {
                let data = std::fs::read(dir.join(format!("case.{}", target.ext())));
                saved = save(&args.out, target, &data.unwrap_or_default())
                    .display()
                    .to_string();
            }
            if let Some(parent) = dir.parent() {
                let _ = std::fs::remove_dir_all(parent);
            }
        }
        let code = status.and_then(|s| s.code());
        let key = match code {
            Some(3) => "crash: a case ran longer than the watchdog allows".to_string(),
            Some(c) => format!("crash: worker exited with status {c}"),
            None => "crash: worker killed by a signal (abort, stack overflow)".to_string(),
        };
        *result
            .tally
            .entry(("?".into(), Verdict::Crash.name().into()))
            .or_default() += 1;
        result.failures.entry(key).or_insert((0, saved)).0 += 1;
        restart += 1;
    }
    result
}

fn parse_tally(fields: &str) -> BTreeMap<(String, String), u64> {
    fields
        .split(' ')
        .filter_map(|f| {
            let (k, n) = f.split_once('=')?;
            let (t, v) = k.split_once(':')?;
            Some(((t.to_string(), v.to_string()), n.parse().ok()?))
        })
        .collect()
}
