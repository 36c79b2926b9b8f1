//! The peers measured in the benchmark's own run: Mitsuba 3 (`llvm_ad_rgb`,
//! `scalar_rgb`) and Embree 4 (one ray at a time, 16-ray packets) on the
//! bunny scene, each a `tools/peers/peers.py serve PEER` process that builds
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
//! The report's sections on the peers and on where penumbra stands on this
//! machine are here too, one function per section.

use std::fmt::Write as _;
use std::io::{BufRead, BufReader, Write as _};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, ChildStdout, Command, Stdio};

use serde::{Deserialize, Serialize};

use crate::report::{int, ratio, st};
use crate::{Args, Results, Stat};
use penumbra::render::KernelOptions;
use penumbra::scene::{Phong, Scene, Shader};

/// The peers in the order they run.
pub const PEERS: &[&str] = &[
    "mitsuba-llvm",
    "mitsuba-scalar",
    "embree-single",
    "embree-packets",
];

/// Blocked shadow-ray counts of two renderers agree when they differ by at
/// most this fraction: their shadow-ray offsets differ (penumbra's robust
/// offset, Embree's and Mitsuba's own), which moves a few hundred of the
/// grazing rays near shadow boundaries; a wrong light or camera moves tens of
/// thousands.
pub const BLOCKED_TOLERANCE: f64 = 0.01;

/// Primary hits, shadow rays cast and shadow rays blocked in one frame.
#[derive(Serialize, Deserialize, Clone, Debug, Default)]
pub struct Counts {
    pub hits: u64,
    pub shadow_rays: u64,
    /// None where the renderer cannot tell.
    pub blocked: Option<u64>,
}

/// One peer: what it is, its counts and its frames.
#[derive(Serialize, Deserialize, Clone, Debug, Default)]
pub struct PeerRun {
    pub peer: String,
    /// Package versions as the peer reports them.
    pub version: String,
    /// What the peer calls (integrator, packet width, libLLVM).
    #[serde(default)]
    pub notes: String,
    /// Why the peer could not run, when it could not.
    pub error: Option<String>,
    pub threads: usize,
    pub setup_ms: f64,
    pub first_frame_ms: f64,
    pub counts: Counts,
    /// The peer's measured frames.
    pub frame_ms: Stat,
    /// The penumbra frame just before each of the peer's frames.
    pub penumbra_ms: Stat,
    /// penumbra / peer of each interleaved pair.
    pub ratio: Stat,
}

/// The peers part of a run.
#[derive(Serialize, Deserialize, Clone, Debug, Default)]
pub struct PeersPart {
    /// Why no peer was measured (no venv, `--no-peers`), if none was.
    pub not_measured: Option<String>,
    /// The Python interpreter that ran the peers.
    pub python: String,
    pub threads: usize,
    pub width: u32,
    pub height: u32,
    pub rounds: usize,
    /// penumbra's counts on the same scene.
    pub penumbra: Counts,
    /// Every penumbra frame of the part.
    pub penumbra_ms: Stat,
    pub peers: Vec<PeerRun>,
}

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
    let up = crate::upload(r, scene, k)?;
    let (w, h) = up.size();
    let plain = crate::frame(r, &up, k, w, h)?;
    let mut tagged = scene.clone();
    for l in &mut tagged.lights {
        l.ambient = glam::Vec3::splat(0.1);
    }
    tagged.shaders = vec![Shader::Phong(Phong {
        ambient: glam::Vec3::ONE,
        diffuse: glam::Vec3::splat(0.8),
        specular: glam::Vec3::ZERO,
        shininess: 1.0,
    })];
    for o in &mut tagged.objects {
        o.shader = 0;
    }
    let up = crate::upload(r, &tagged, k)?;
    let f = crate::frame(r, &up, k, w, h)?;
    let hits = crate::hits(&f) as u64;
    let dark = f
        .image
        .pixels
        .iter()
        .filter(|p| p[3] == 1.0 && p[0] == 0.1)
        .count() as u64;
    let facing_away = hits.saturating_sub(f.stats.shadow_rays);
    Ok(Counts {
        hits: crate::hits(&plain) as u64,
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
    fn start(python: &Path, root: &Path, peer: &str, threads: usize) -> anyhow::Result<Server> {
        let mut child = Command::new(python)
            .arg(root.join("tools/peers/peers.py"))
            .args(["serve", peer, "--threads", &threads.to_string(), "--scene"])
            .arg(root.join("scenes/bunny_scene.glb"))
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
fn start_peer(python: &Path, root: &Path, peer: &str, threads: usize) -> (PeerRun, Option<Server>) {
    let mut run = PeerRun {
        peer: peer.into(),
        threads,
        ..Default::default()
    };
    let ready = Server::start(python, root, peer, threads).and_then(|mut s| {
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
pub fn part(args: &Args) -> anyhow::Result<PeersPart> {
    let root = crate::root();
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
    let mut r = crate::renderer(args)?;
    let bunny = crate::meshes::bunny_scene(&root)?;
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
    let up = crate::upload(&mut r, &bunny, k)?;
    let (w, h) = up.size();
    (out.width, out.height) = (w, h);
    // Start every peer first (each then waits, idle, for its frames).
    let mut servers = Vec::new();
    for peer in PEERS {
        eprintln!("  peers: starting {peer}");
        let (run, server) = start_peer(&python, &root, peer, threads);
        if let Some(e) = &run.error {
            eprintln!("  peers: {peer} failed: {e}");
        }
        out.peers.push(run);
        servers.push(server);
    }
    crate::frame(&mut r, &up, k, w, h)?;
    crate::frame(&mut r, &up, k, w, h)?;
    let n = PEERS.len();
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
            let p = crate::ms(crate::frame(&mut r, &up, k, w, h)?.stats.timings.render);
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

// ---------------------------------------------------------------- report

/// The figures of the previous report, from the AVX-512 machine (AMD Zen 4,
/// 2 cores): docs/bench.md at commit 0e1b0cd, 2026-11-22, and the peers'
/// figures given in issue 19 for that machine. Only ever printed as that
/// machine's.
pub struct Zen4 {
    pub bunny_ms: f64,
    pub cpu_port_ratio: f64,
    pub build_ratio: f64,
    pub width_512: f64,
    pub width_128: f64,
    pub mitsuba_llvm_ms: f64,
    pub mitsuba_scalar_ms: f64,
    pub embree_single_ms: f64,
    pub embree_packets_ms: f64,
}

pub const ZEN4: Zen4 = Zen4 {
    bunny_ms: 74.9,
    cpu_port_ratio: 0.78,
    build_ratio: 0.45,
    width_512: 1.18,
    width_128: 0.66,
    mitsuba_llvm_ms: 38.7,
    mitsuba_scalar_ms: 173.5,
    embree_single_ms: 61.2,
    embree_packets_ms: 24.7,
};

const ZEN4_SOURCE: &str = "the AVX-512 machine (AMD EPYC, Zen 4, 2 cores; docs/bench.md at commit 0e1b0cd, the peers as given in issue 19 — not this machine)";

/// Header rows: the CPU and the peers' versions.
pub fn header_rows(o: &mut String, r: &Results) {
    let _ = writeln!(o, "| CPU | {} |", r.cpu_info.describe());
    let p = &r.peers;
    let peers = match p.why_not() {
        Some(why) => format!("not measured in this run: {why}"),
        None => {
            let mut v: Vec<String> = Vec::new();
            for run in p.peers.iter().filter(|x| x.error.is_none()) {
                if !v.contains(&run.version) {
                    v.push(run.version.clone());
                }
            }
            format!(
                "{} ({} threads each, as penumbra; Python `{}`)",
                v.join("; "),
                p.threads,
                p.python
            )
        }
    };
    let _ = writeln!(o, "| Peers | {peers} |");
}

/// Headline rows: penumbra against each peer from this run.
pub fn headline_rows(o: &mut String, r: &Results) {
    let p = &r.peers;
    if let Some(why) = p.why_not() {
        let _ = writeln!(
            o,
            "| penumbra / Mitsuba 3 and Embree | **not measured in this run**: {why} |"
        );
        return;
    }
    for run in &p.peers {
        let cell = match (&run.error, run.agreement(&p.penumbra)) {
            (Some(e), _) => format!("not measured: {e}"),
            (None, Err(e)) => format!("**void**: {e}"),
            (None, Ok(())) => format!(
                "**{}×** its time ({} pairs; {:.1} vs {:.1} ms)",
                ratio(&run.ratio),
                run.ratio.samples.len(),
                run.penumbra_ms.median,
                run.frame_ms.median
            ),
        };
        let _ = writeln!(o, "| penumbra / {}, same run | {cell} |", label(&run.peer));
    }
}

/// Section 6's table rows for the peers.
pub fn target_rows(o: &mut String, r: &Results, rays: f64) {
    let p = &r.peers;
    if let Some(why) = p.why_not() {
        let _ = writeln!(
            o,
            "| Mitsuba 3, Embree 4 | not measured in this run ({why}) | | |"
        );
        return;
    }
    for run in &p.peers {
        let cells = match (&run.error, run.agreement(&p.penumbra)) {
            (Some(_), _) => "not measured (section 7) | | ".to_string(),
            (None, Err(_)) => format!(
                "{} | {:.1} | void: counts disagree (section 7)",
                st(&run.frame_ms),
                rays / run.frame_ms.median / 1e3
            ),
            (None, Ok(())) => format!(
                "{} | {:.1} | {}×",
                st(&run.frame_ms),
                rays / run.frame_ms.median / 1e3,
                ratio(&run.ratio)
            ),
        };
        let _ = writeln!(o, "| {}, this run | {cells} |", label(&run.peer));
    }
}

/// Section 6's verdict on the aim, Mitsuba's LLVM variant.
pub fn target_bullet(o: &mut String, r: &Results) {
    let p = &r.peers;
    let line = match p.valid("mitsuba-llvm") {
        Some(m) => format!(
            "{:.1} ms in this run: penumbra needs {:.1} ms in the same rounds, **{:.2}×** as long (median of {} interleaved pairs, range {:.2}–{:.2}) — {}",
            m.frame_ms.median,
            m.penumbra_ms.median,
            m.ratio.median,
            m.ratio.samples.len(),
            m.ratio.min,
            m.ratio.max,
            if m.ratio.median <= 1.0 {
                "met".to_string()
            } else {
                format!(
                    "not met ({:.1} ms to go)",
                    m.penumbra_ms.median - m.frame_ms.median
                )
            }
        ),
        None => format!(
            "no verdict: not measured in this run ({}). On {ZEN4_SOURCE} it took {} ms against penumbra's {} ms there ({:.1}×)",
            p.why_not()
                .or_else(|| p
                    .peers
                    .iter()
                    .find(|x| x.peer == "mitsuba-llvm")
                    .and_then(|x| x.error.clone().or_else(|| x.agreement(&p.penumbra).err())))
                .unwrap_or_default(),
            ZEN4.mitsuba_llvm_ms,
            ZEN4.bunny_ms,
            ZEN4.bunny_ms / ZEN4.mitsuba_llvm_ms
        ),
    };
    let _ = writeln!(o, "- **Mitsuba's LLVM back end (the aim)**: {line}.\n");
}

/// The analysis's paragraph on the peers' advantage, with this run's figures.
pub fn advantage(r: &Results) -> String {
    let p = &r.peers;
    let t = |peer: &str| p.valid(peer).map(|x| x.frame_ms.median);
    let figures = match (
        t("embree-packets"),
        t("mitsuba-llvm"),
        t("embree-single"),
    ) {
        (Some(a), Some(b), Some(c)) => format!(
            "Embree's 16-ray packets ({a:.1} ms in this run, ray queries only) and Mitsuba's LLVM variant ({b:.1} ms, a whole frame) trace coherent bundles with hand-tuned SIMD box tests and keep one traversal stack per packet, not per lane; Embree's single-ray mode ({c:.1} ms) is still a well-tuned scalar kernel with a wide BVH. penumbra is {:.1}× Mitsuba's LLVM time in the same rounds",
            p.valid("mitsuba-llvm").map_or(f64::NAN, |m| m.ratio.median)
        ),
        _ => format!(
            "Embree's packets and Mitsuba's LLVM variant trace coherent bundles with hand-tuned SIMD box tests and keep one traversal stack per packet, not per lane (not measured in this run; on {ZEN4_SOURCE}: {} ms and {} ms against penumbra's {} ms)",
            ZEN4.embree_packets_ms, ZEN4.mitsuba_llvm_ms, ZEN4.bunny_ms
        ),
    };
    format!("4. **The peers' advantage.** {figures}.")
}

/// Section 7: the peers, how they were run, their counts and frames.
pub fn section(o: &mut String, r: &Results) {
    let p = &r.peers;
    let _ = writeln!(o, "## 7. Peers, measured in this run\n");
    if let Some(why) = p.why_not() {
        let _ = writeln!(
            o,
            "**The peers were not measured in this run**: {why}. No peer figure in this report comes from this machine; where one from another machine appears, it says so.\n"
        );
        return;
    }
    let _ = writeln!(
        o,
        "Each peer is a `tools/peers/peers.py serve PEER` process (`{}`, packages pinned in `tools/peers/requirements.txt`, installed by `tools/setup.sh --bench`) that builds its scene from `scenes/bunny_scene.glb` itself: the meshes in world space, the camera node (eye, orientation, vertical field of view), the directional light, {}×{}, {} threads (penumbra's lavapipe runs as many). Mitsuba renders whole frames with its `direct` integrator (one emitter sample, no BSDF sample; a non-jittered stratified sampler puts the one sample per pixel at its centre; a box filter; a two-sided diffuse BSDF): camera rays, shading, one shadow ray per hit and the film, as penumbra's render phase does. Embree runs `tools/peers/embree_frame.c` against the libembree4 that embreex ships: primary rays through the pixel centres with penumbra's camera model, then a shadow ray for each hit whose normal faces the light; ray queries and the ray set-up only, no shading. Each peer's scene set-up, first frame and a warm-up frame come before the measured frames. The frames are interleaved: in each of {} rounds, for every peer (a different one first each round), one penumbra frame (render phase, `RenderStats`) and then one of the peer's; each ratio below is the median over those pairs of penumbra's frame / the peer's frame, with the range over pairs.\n",
        p.python,
        p.width,
        p.height,
        p.threads,
        p.rounds
    );
    if let Some(part) = r.parts.iter().find(|x| x.part == "peers") {
        let _ = writeln!(
            o,
            "This part took {:.0} s while other processes used {:.2} cores on average (the last table); interleaving keeps that from deciding a ratio, not from slowing both sides.\n",
            part.wall_s, part.other_cores
        );
    }
    let _ = writeln!(
        o,
        "**Same scene?** A peer's comparison is void unless its primary hit count equals penumbra's and its blocked shadow rays are within {:.0}% of penumbra's. Shadow-ray totals differ by definition: Mitsuba's direct integrator samples the light at every hit, penumbra and the Embree peers only where the normal faces the light.\n",
        BLOCKED_TOLERANCE * 100.0
    );
    let _ = writeln!(
        o,
        "| Renderer | Version | How | Primary hits | Shadow rays | Blocked | Same scene? |\n|---|---|---|---|---|---|---|"
    );
    let pc = &p.penumbra;
    let blocked = |c: &Counts| c.blocked.map_or("—".into(), int);
    let _ = writeln!(
        o,
        "| penumbra | this commit | lavapipe, render phase | {} | {} | {} | — |",
        int(pc.hits),
        int(pc.shadow_rays),
        blocked(pc)
    );
    for run in &p.peers {
        match &run.error {
            Some(e) => {
                let _ = writeln!(
                    o,
                    "| {} | — | — | — | — | — | did not run: {} |",
                    label(&run.peer),
                    e.replace('|', "\\|").replace('\n', " ")
                );
            }
            None => {
                let _ = writeln!(
                    o,
                    "| {} | {} | {} | {} | {} | {} | {} |",
                    label(&run.peer),
                    run.version,
                    run.notes,
                    int(run.counts.hits),
                    int(run.counts.shadow_rays),
                    blocked(&run.counts),
                    match run.agreement(pc) {
                        Ok(()) => "yes".to_string(),
                        Err(e) => format!("**no: void** ({e})"),
                    }
                );
            }
        }
    }
    let _ = writeln!(
        o,
        "\n| Peer | Scene set-up | First frame | Peer ms/frame, median [min–max] | penumbra ms/frame in the same pairs | penumbra / peer, median [min–max] of pairs |\n|---|---|---|---|---|---|"
    );
    for run in p.peers.iter().filter(|x| x.error.is_none()) {
        let _ = writeln!(
            o,
            "| {} | {:.0} ms | {:.0} ms | {} | {} | {} |",
            label(&run.peer),
            run.setup_ms,
            run.first_frame_ms,
            st(&run.frame_ms),
            st(&run.penumbra_ms),
            match run.agreement(pc) {
                Ok(()) => format!("**{}**", ratio(&run.ratio)),
                Err(_) => format!("void ({})", ratio(&run.ratio)),
            }
        );
    }
    let _ = writeln!(
        o,
        "\nRegenerate the peers' figures alone (no penumbra frames): `target/bench-venv/bin/python tools/peers/peers.py run` prints one JSON line per peer and frame.\n"
    );
}

/// A caution for an absolute figure of `part` when other processes took
/// more than half a core during it (ratios of interleaved pairs are robust to
/// that; absolute times are not).
fn load_caution(r: &Results, part: &str) -> String {
    let worst = r
        .parts
        .iter()
        .filter(|p| p.part == part)
        .map(|p| p.other_cores)
        .fold(f64::NAN, f64::min);
    if worst > 0.5 {
        format!(" (measured while other processes used {worst:.1} cores: an absolute time, slowed by them)")
    } else {
        String::new()
    }
}

/// Section 8: where penumbra stands on this machine — each target's verdict
/// from this run, and what differs from the AVX-512 machine.
pub fn standing_section(o: &mut String, r: &Results) {
    let _ = writeln!(o, "## 8. Where penumbra stands on this machine\n");
    let bunny = &r.throughput.scenes[0];
    let cpu = &r.cpu;
    let million = r.scaling.triangles.last();
    let knob = |name: &str, value: &str| {
        r.knobs
            .iter()
            .find(|k| k.env.iter().any(|(n, v)| n == name && v == value))
    };
    let _ = writeln!(
        o,
        "Every figure and verdict below is from this run ({}); the AVX-512 column is {ZEN4_SOURCE}.\n",
        r.cpu_info.describe()
    );
    let _ = writeln!(
        o,
        "| | This run | Verdict | AVX-512 machine |\n|---|---|---|---|"
    );
    let p = &r.peers;
    // The AVX-512 machine's peers: Mitsuba 3.9.1 and Embree 3 (its packets
    // 16 rays wide), as issue 19 gives them.
    for (peer, zen4, there) in [
        ("mitsuba-llvm", ZEN4.mitsuba_llvm_ms, "Mitsuba 3.9.1"),
        ("mitsuba-scalar", ZEN4.mitsuba_scalar_ms, "Mitsuba 3.9.1"),
        ("embree-single", ZEN4.embree_single_ms, "Embree 3"),
        (
            "embree-packets",
            ZEN4.embree_packets_ms,
            "Embree 3, 16-ray packets",
        ),
    ] {
        let (now, verdict) = match p.valid(peer) {
            Some(m) => (
                format!(
                    "{}× ({:.1} vs {:.1} ms)",
                    ratio(&m.ratio),
                    m.penumbra_ms.median,
                    m.frame_ms.median
                ),
                if peer == "mitsuba-llvm" {
                    if m.ratio.median <= 1.0 {
                        "the aim: met"
                    } else {
                        "the aim: not met"
                    }
                } else {
                    "—"
                }
                .to_string(),
            ),
            None => ("not measured".into(), "no verdict".into()),
        };
        let _ = writeln!(
            o,
            "| penumbra / {} | {now} | {verdict} | {:.2}× ({} vs {} ms; {there}) |",
            label(peer),
            ZEN4.bunny_ms / zen4,
            ZEN4.bunny_ms,
            zen4
        );
    }
    let _ = writeln!(
        o,
        "| lavapipe / plain Rust CPU port at its best | {} ({:.1} vs {:.1} ms) | no slower than the port: {} | {:.2} |",
        ratio(&cpu.ratio),
        cpu.gpu_ms.median,
        cpu.cpu_ms.median,
        if cpu.ratio.median <= 1.0 { "met" } else { "not met" },
        ZEN4.cpu_port_ratio
    );
    if let Some(m) = million {
        let b = m.build_ms() / m.render_ms.median;
        let _ = writeln!(
            o,
            "| {}-triangle BVH build / one 1024×1024 frame of it | {:.2}× ({:.0} vs {:.1} ms) | well under (below half): {}{} | {:.2}× |",
            int(m.triangles as u64),
            b,
            m.build_ms(),
            m.render_ms.median,
            if b < 0.5 { "met" } else { "not met" },
            load_caution(r, "scaling"),
            ZEN4.build_ratio
        );
    }
    let _ = writeln!(
        o,
        "| Mrays/s, bunny | {:.1} | ≥ 10: {}{} | {:.1} |",
        bunny.mrays_median,
        if bunny.mrays_median >= 10.0 {
            "met"
        } else {
            "not met"
        },
        load_caution(r, "throughput"),
        (bunny.primary_rays + bunny.shadow_rays) as f64 / ZEN4.bunny_ms / 1e3
    );
    let w512 = knob("LP_NATIVE_VECTOR_WIDTH", "512");
    let w128 = knob("LP_NATIVE_VECTOR_WIDTH", "128");
    for (name, k, zen4) in [("512", w512, ZEN4.width_512), ("128", w128, ZEN4.width_128)] {
        let _ = writeln!(
            o,
            "| `LP_NATIVE_VECTOR_WIDTH={name}`: speed vs the default (256) | {} | {} | {:.2}× |",
            k.map_or("not run (`--no-knobs`)".into(), |k| format!(
                "{}×",
                ratio(&k.speedup_vs_default)
            )),
            match k {
                Some(k) if k.speedup_vs_default.median > 1.02 => "faster than the default",
                Some(k) if k.speedup_vs_default.median < 0.98 => "slower than the default",
                Some(_) => "as fast as the default",
                None => "—",
            },
            zen4
        );
    }
    let _ = writeln!(
        o,
        "\nThe knob is the environment variable lavapipe reads when it loads (section 5); `penumbra render --vector-width auto` (`src/vector_width.rs`) sets it to 512 only for long renders on a CPU with AVX-512, and this CPU {}.\n",
        if r.cpu_info.avx512() {
            "has AVX-512"
        } else {
            "has none, so auto keeps 256 here"
        }
    );
    let _ = writeln!(o, "{}\n", machines_paragraph(r));
}

/// What differs between the AVX2 and the AVX-512 machines, from this run's
/// figures and the AVX-512 machine's.
fn machines_paragraph(r: &Results) -> String {
    let c = &r.cpu_info;
    let bunny = r.throughput.scenes[0].render_ms.median;
    let w512 = r
        .knobs
        .iter()
        .find(|k| {
            k.env
                .iter()
                .any(|(n, v)| n == "LP_NATIVE_VECTOR_WIDTH" && v == "512")
        })
        .map(|k| k.speedup_vs_default.median);
    let mut s = format!(
        "**AVX2 and AVX-512.** This machine {} AVX-512 ({}). ",
        if c.avx512() { "has" } else { "has no" },
        c.isa.join(" ")
    );
    if let Some(e) = r.peers.valid("embree-packets") {
        let _ = write!(
            s,
            "Embree's packets here: {}; on the AVX-512 machine the peers' figures were 16-ray packets. ",
            e.notes
        );
    }
    if let Some(w) = w512 {
        let _ = write!(
            s,
            "lavapipe's 512-bit vectors (16 lanes) run at {w:.2}× the default 256-bit speed here, against {:.2}× on the AVX-512 machine: {} ",
            ZEN4.width_512,
            match (c.avx512(), w > 1.02, w < 0.98) {
                (true, true, _) => "with AVX-512, LLVM emits 16-lane instructions, and the wider SIMD groups pay for their extra divergence.",
                (true, false, _) => "even with AVX-512 the wider SIMD groups do not pay for their extra divergence here.",
                (false, _, true) => "without AVX-512, LLVM splits every 16-lane operation into two 256-bit halves, so the wider groups add divergence and register pressure without wider arithmetic; the default (256) is the right width here.",
                (false, _, false) => "without AVX-512, LLVM splits every 16-lane operation into two 256-bit halves, yet the wider groups are not slower here.",
            }
        );
    }
    let _ = write!(
        s,
        "penumbra's bunny frame takes {bunny:.1} ms here{} against {:.1} ms there ({:.2}×). ",
        load_caution(r, "throughput"),
        ZEN4.bunny_ms,
        bunny / ZEN4.bunny_ms
    );
    if let Some(m) = r.peers.valid("mitsuba-llvm") {
        let _ = write!(
            s,
            "Mitsuba's LLVM variant takes {:.1} ms here{} against {:.1} ms there ({:.2}×), so penumbra's ratio to it is {:.2}× here against {:.2}× there: {}",
            m.frame_ms.median,
            load_caution(r, "peers"),
            ZEN4.mitsuba_llvm_ms,
            m.frame_ms.median / ZEN4.mitsuba_llvm_ms,
            m.ratio.median,
            ZEN4.bunny_ms / ZEN4.mitsuba_llvm_ms,
            if (m.ratio.median - ZEN4.bunny_ms / ZEN4.mitsuba_llvm_ms).abs() > 0.2 {
                "the gap depends on the machine, which is why the ratio has to come from the same run."
            } else {
                "about the same gap on both machines."
            }
        );
    }
    s
}
