//! The peers measured in the benchmark's own run: Mitsuba 3 (`llvm_ad_rgb`,
//! `scalar_rgb`) and Embree 4 (one ray at a time, 16-ray packets) on the
//! bunny scene, each a `tools/measure/peers/peers.py serve PEER` process that builds
//! its scene from the same glTF file, with frames interleaved with
//! penumbra's (one penumbra frame, then one of the peer's) so that another
//! process taking a core slows both sides of a ratio alike.
//!
//! The peers need the Python environment that `tools/setup.sh --bench`
//! installs into `target/bench-venv`; without it the part records why the
//! peers were not measured and the report says so (it never puts another
//! machine's figures in their place). A peer whose primary hit count differs
//! from penumbra's, or whose blocked shadow rays differ by more than
//! [`BLOCKED_TOLERANCE`], renders a different scene: its ratio is reported as
//! void.
//!
//! The report's sections on the peers are in `crate::report::peers`.

use std::io::{BufRead, BufReader, Write as _};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, ChildStdout, Command, Stdio};

use common::Stat;
use penumbra::render::KernelOptions;
use penumbra::scene::{Phong, Scene, Shader};

use crate::report::fmt::int;
use crate::schema::{Counts, PeerRun, PeersPart};
use crate::Args;

/// The peers in the order they run.
pub const PEERS: &[&str] = &[
    "mitsuba-llvm",
    "mitsuba-scalar",
    "embree-single",
    "embree-packets",
];

/// The environment variable that asks tools/measure/peers/peers.py for AVX2 code,
/// with its value: the benchmark's second peers run on an AVX-512 CPU.
pub const AVX2_PEERS: (&str, &str) = ("PENUMBRA_PEERS_ISA", "avx2");

/// Blocked shadow-ray counts of two renderers agree when they differ by at
/// most this fraction: their shadow-ray offsets differ (penumbra's robust
/// offset, Embree's and Mitsuba's own), which moves a few hundred of the
/// grazing rays near shadow boundaries; a wrong light or camera moves tens of
/// thousands.
pub const BLOCKED_TOLERANCE: f64 = 0.01;
impl PeersPart {
    /// Why the report has no peer figures from this run, if it has none.
    pub fn why_not(&self) -> Option<String> {
        if let Some(why) = &self.not_measured {
            return Some(why.clone());
        }
        if self.peers.iter().all(|p| p.error.is_some()) {
            return Some(if self.peers.is_empty() {
                "this bench.json was written before the benchmark measured its peers".into()
            } else {
                "every peer failed to start (see section 7)".into()
            });
        }
        None
    }

    /// The peer's run, when it ran and its counts agree with penumbra's.
    pub fn valid(&self, peer: &str) -> Option<&PeerRun> {
        self.peers
            .iter()
            .find(|p| p.peer == peer && p.error.is_none())
            .filter(|p| p.agreement(&self.penumbra).is_ok())
    }
}

impl PeerRun {
    /// Whether the peer rendered the same scene: the same primary hits, and
    /// blocked shadow rays within [`BLOCKED_TOLERANCE`] where both count them.
    pub fn agreement(&self, penumbra: &Counts) -> Result<(), String> {
        if self.counts.hits != penumbra.hits {
            return Err(format!(
                "{} primary hits against penumbra's {}",
                int(self.counts.hits),
                int(penumbra.hits)
            ));
        }
        if let (Some(a), Some(b)) = (self.counts.blocked, penumbra.blocked) {
            if (a as f64 - b as f64).abs() > BLOCKED_TOLERANCE * b as f64 {
                return Err(format!(
                    "{} blocked shadow rays against penumbra's {} (more than {:.0}% apart)",
                    int(a),
                    int(b),
                    BLOCKED_TOLERANCE * 100.0
                ));
            }
        }
        Ok(())
    }
}

/// What each peer times, for the report.
pub fn label(peer: &str) -> &'static str {
    match peer {
        "mitsuba-llvm" => "Mitsuba 3 `llvm_ad_rgb`, whole frame",
        "mitsuba-scalar" => "Mitsuba 3 `scalar_rgb`, whole frame",
        "embree-single" => "Embree 4, one ray at a time, ray queries only",
        "embree-packets" => "Embree 4, ray packets, ray queries only",
        _ => "unknown peer",
    }
}

/// The venv's Python, if `tools/setup.sh --bench` made it.
pub fn venv_python(root: &Path) -> Option<PathBuf> {
    let p = root.join("target/bench-venv/bin/python");
    p.exists().then_some(p)
}

// ---------------------------------------------------------------- measuring

/// penumbra's counts on `scene`: hits and shadow rays from a frame's
/// statistics, and blocked shadow rays from a render in which every surface
/// has ambient 1 under the light's ambient 0.1 and no specular term, so an
/// unlit hit is exactly 0.1: unlit hits are the blocked ones plus those that
/// face away from the light, which cast no shadow ray.
fn penumbra_counts(r: &mut penumbra::render::Renderer, scene: &Scene) -> anyhow::Result<Counts> {
    let k = KernelOptions::default();
    let up = crate::measure::upload(r, scene, k)?;
    let (w, h) = up.size();
    let plain = crate::measure::frame(r, &up, k, w, h)?;
    let mut tagged = scene.clone();
    for l in &mut tagged.lights {
        l.ambient = glam::Vec3::splat(0.1);
    }
    tagged.shaders = vec![Shader::Phong(Phong {
        textures: Default::default(),
        ambient: glam::Vec3::ONE,
        diffuse: glam::Vec3::splat(0.8),
        specular: glam::Vec3::ZERO,
        shininess: 1.0,
    })];
    for o in &mut tagged.objects {
        o.shader = 0;
    }
    let up = crate::measure::upload(r, &tagged, k)?;
    let f = crate::measure::frame(r, &up, k, w, h)?;
    let hits = crate::measure::hits(&f) as u64;
    let dark = f
        .image
        .pixels
        .iter()
        .filter(|p| p[3] == 1.0 && p[0] == 0.1)
        .count() as u64;
    let facing_away = hits.saturating_sub(f.stats.shadow_rays);
    Ok(Counts {
        hits: crate::measure::hits(&plain) as u64,
        shadow_rays: plain.stats.shadow_rays,
        blocked: (tagged.lights.len() == 1).then(|| dark.saturating_sub(facing_away)),
    })
}

/// A running `peers.py serve PEER`.
struct Server {
    child: Child,
    stdin: ChildStdin,
    stdout: BufReader<ChildStdout>,
}

impl Server {
    fn start(
        python: &Path,
        root: &Path,
        scene: &Path,
        peer: &str,
        threads: usize,
    ) -> anyhow::Result<Server> {
        let mut child = Command::new(python)
            .arg(root.join("tools/measure/peers/peers.py"))
            .args(["serve", peer, "--threads", &threads.to_string(), "--scene"])
            .arg(scene)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .spawn()?;
        let stdin = child.stdin.take().expect("piped");
        let stdout = BufReader::new(child.stdout.take().expect("piped"));
        Ok(Server {
            child,
            stdin,
            stdout,
        })
    }

    fn line(&mut self) -> anyhow::Result<serde_json::Value> {
        let mut s = String::new();
        if self.stdout.read_line(&mut s)? == 0 {
            anyhow::bail!("the peer process ended");
        }
        Ok(serde_json::from_str(&s)?)
    }

    fn frame(&mut self) -> anyhow::Result<f64> {
        writeln!(self.stdin, "frame")?;
        self.stdin.flush()?;
        self.line()?["frame_ms"]
            .as_f64()
            .ok_or_else(|| anyhow::anyhow!("no frame_ms in the peer's answer"))
    }

    fn stop(mut self) {
        let _ = writeln!(self.stdin, "quit");
        drop(self.stdin);
        let _ = self.child.wait();
    }
}

/// Starts a peer and reads its ready line: facts and counts, or the error.
fn start_peer(
    python: &Path,
    root: &Path,
    scene: &Path,
    peer: &str,
    threads: usize,
) -> (PeerRun, Option<Server>) {
    let mut run = PeerRun {
        peer: peer.into(),
        threads,
        ..Default::default()
    };
    let ready = Server::start(python, root, scene, peer, threads).and_then(|mut s| {
        let v = s.line()?;
        Ok((s, v))
    });
    match ready {
        Err(e) => {
            run.error = Some(format!("{e:#}"));
            (run, None)
        }
        Ok((s, v)) => {
            if let Some(e) = v["error"].as_str() {
                run.error = Some(e.into());
                s.stop();
                return (run, None);
            }
            let u = |k: &str| v[k].as_u64().unwrap_or(0);
            run.version = v["version"].as_str().unwrap_or("").into();
            run.notes = v["notes"].as_str().unwrap_or("").into();
            run.setup_ms = v["setup_ms"].as_f64().unwrap_or(f64::NAN);
            run.first_frame_ms = v["first_frame_ms"].as_f64().unwrap_or(f64::NAN);
            run.counts = Counts {
                hits: u("hits"),
                shadow_rays: u("shadow_rays"),
                blocked: v["blocked"].as_u64(),
            };
            (run, Some(s))
        }
    }
}

/// The peers part (a child process of the benchmark): penumbra's bunny frames
/// interleaved with each peer's, `rounds` pairs per peer.
pub fn run(args: &Args) -> anyhow::Result<PeersPart> {
    let root = common::repo_root();
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let mut out = PeersPart {
        threads,
        rounds: if args.quick { 2 } else { 9 },
        ..Default::default()
    };
    let python = match venv_python(&root) {
        None => {
            out.not_measured = Some(
                "no `target/bench-venv` (the peers' Python environment): run `tools/setup.sh --bench`, then the benchmark again".into(),
            );
            None
        }
        Some(p) => Some(p),
    };
    let mut r = crate::measure::renderer(args)?;
    out.device = Some(crate::measure::device(&r));
    let mut bunny = common::meshes::bunny_scene(&root)?;
    // The peers read the scene from a .glb file: with `--subdivide`, one
    // holding the subdivided bunny's triangles.
    let glb_dir = tempfile::tempdir()?;
    let mut glb = root.join("scenes/bunny_scene.glb");
    if args.subdivide > 0 {
        bunny = common::meshes::subdivided_bunny(&bunny, args.subdivide);
        // The peers shade with the triangles' own normals, as penumbra does
        // the file's bunny, which has none: so does the subdivided one here
        // (with the subdivision's vertex normals, 6% of the shadow rays that
        // were blocked differed: the comparison was void).
        common::meshes::bunny_mesh(&mut bunny).normals = None;
        let sub = glb_dir.path().join("bunny_subdivided.glb");
        common::meshes::write_glb_with_bunny(&glb, common::meshes::bunny_mesh(&mut bunny), &sub)?;
        glb = sub;
    }
    out.triangles = bunny
        .objects
        .iter()
        .map(|o| match &o.shape {
            penumbra::scene::Shape::Mesh(m) => m.indices.len() as u64,
            _ => 0,
        })
        .sum();
    out.penumbra = penumbra_counts(&mut r, &bunny)?;
    let Some(python) = python else {
        return Ok(out);
    };
    out.python = python
        .strip_prefix(&root)
        .unwrap_or(&python)
        .display()
        .to_string();
    let k = KernelOptions::default();
    let up = crate::measure::upload(&mut r, &bunny, k)?;
    let (w, h) = up.size();
    (out.width, out.height) = (w, h);
    // Under an instruction-set cap (the AVX2 run), the precompiled scalar
    // Mitsuba is the same code as without it: leave it out.
    let capped = std::env::var(AVX2_PEERS.0).is_ok_and(|v| !v.is_empty());
    let peers: Vec<&str> = PEERS
        .iter()
        .copied()
        .filter(|p| !(capped && *p == "mitsuba-scalar"))
        .collect();
    // Start every peer first (each then waits, idle, for its frames).
    let mut servers = Vec::new();
    for peer in peers.iter().copied() {
        eprintln!("  peers: starting {peer}");
        let (run, server) = start_peer(&python, &root, &glb, peer, threads);
        if let Some(e) = &run.error {
            eprintln!("  peers: {peer} failed: {e}");
        }
        out.peers.push(run);
        servers.push(server);
    }
    crate::measure::frame(&mut r, &up, k, w, h)?;
    crate::measure::frame(&mut r, &up, k, w, h)?;
    let n = peers.len();
    let mut times: Vec<(Vec<f64>, Vec<f64>)> = vec![(Vec::new(), Vec::new()); n];
    let mut all = Vec::new();
    for round in 0..out.rounds {
        eprintln!("  peers: round {}/{}", round + 1, out.rounds);
        // Each round starts with another peer, so no peer always follows the
        // same one.
        for i in (0..n).map(|j| (j + round) % n) {
            let Some(s) = servers[i].as_mut() else {
                continue;
            };
            let p = common::ms(
                crate::measure::frame(&mut r, &up, k, w, h)?
                    .stats
                    .timings
                    .render,
            );
            match s.frame() {
                Ok(q) => {
                    all.push(p);
                    times[i].0.push(p);
                    times[i].1.push(q);
                }
                Err(e) => {
                    out.peers[i].error = Some(format!("failed during the frames: {e:#}"));
                    servers[i] = None;
                }
            }
        }
    }
    for ((run, (p, q)), s) in out.peers.iter_mut().zip(&times).zip(servers) {
        if let Some(s) = s {
            s.stop();
        }
        run.penumbra_ms = Stat::of(p);
        run.frame_ms = Stat::of(q);
        let ratio: Vec<f64> = p.iter().zip(q).map(|(a, b)| a / b).collect();
        run.ratio = Stat::of(&ratio);
    }
    out.penumbra_ms = Stat::of(&all);
    Ok(out)
}
