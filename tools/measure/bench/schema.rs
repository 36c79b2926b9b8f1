//! The benchmark's results: everything one run measured, as serialised to
//! `docs/bench.json` and read back by `--from-json`. One struct per part
//! (each part runs in its own child process and hands its struct back as
//! JSON), gathered in [`Results`]. Fields added after a report was written
//! carry `#[serde(default)]` so that older `bench.json` files still load.

use serde::{Deserialize, Serialize};

pub use common::machine::CpuInfo;
pub use common::Stat;

/// The device as the renderer reports it.
#[derive(Serialize, Deserialize, Clone, Debug, Default)]
pub struct Device {
    pub name: String,
    pub device_type: String,
    pub driver_name: String,
    pub driver_info: String,
    pub api_version: String,
}

/// Times in milliseconds with their median, minimum and maximum.
/// One scene's phases and frames.
#[derive(Serialize, Deserialize, Clone, Debug, Default)]
pub struct Throughput {
    pub scene: String,
    pub triangles: usize,
    pub width: u32,
    pub height: u32,
    pub scene_build_ms: f64,
    pub naga_ms: f64,
    pub pipeline_ms: f64,
    pub driver_compile_ms: f64,
    pub bvh_build_ms: f64,
    pub upload_ms: f64,
    pub first_frame_ms: f64,
    pub bvh_nodes: usize,
    pub bvh_depth: usize,
    pub bvh_bytes: usize,
    pub primary_rays: u64,
    pub shadow_rays: u64,
    pub hits: usize,
    pub render_ms: Stat,
    pub readback_ms: Stat,
    /// Mrays/s at the median, slowest and fastest frame.
    pub mrays_median: f64,
    pub mrays_min: f64,
    pub mrays_max: f64,
}

/// One child run of the throughput part.
#[derive(Serialize, Deserialize, Clone, Debug, Default)]
pub struct ThroughputPart {
    pub device: Device,
    pub env: Vec<(String, String)>,
    pub scenes: Vec<Throughput>,
}

/// Two variants measured interleaved (A B A B ...).
#[derive(Serialize, Deserialize, Clone, Debug, Default)]
pub struct Pair {
    pub what: String,
    pub a: String,
    pub b: String,
    pub width: u32,
    pub height: u32,
    pub a_ms: Stat,
    pub b_ms: Stat,
    /// A/B of each interleaved pair of frames.
    pub ratio: Stat,
}

/// Section 4b: the packet traversal (`Traversal::Packet`) against the
/// default per-lane one, interleaved.
#[derive(Serialize, Deserialize, Clone, Debug, Default)]
pub struct PacketPart {
    /// A = packet, B = per-lane, on the bunny.
    pub bunny: Pair,
}

/// Section 2: the seminar's triangle-test claim and the BVH, as interleaved pairs.
#[derive(Serialize, Deserialize, Clone, Debug, Default)]
pub struct SeminarPart {
    pub uv_vs_t_brute: Pair,
    pub uv_vs_t_bvh: Pair,
    pub bvh_vs_brute: Pair,
    /// The default (watertight) test against the seminar's, with the BVH.
    pub watertight_vs_uv_bvh: Pair,
}

/// One mesh size of the triangle scaling (section 3).
#[derive(Serialize, Deserialize, Clone, Debug, Default)]
pub struct TrianglePoint {
    pub triangles: usize,
    pub scene_build_ms: f64,
    pub bvh_build_ms: f64,
    pub upload_ms: f64,
    pub bvh_nodes: usize,
    pub bvh_depth: usize,
    pub bvh_bytes: usize,
    pub rays: u64,
    pub render_ms: Stat,
    /// The largest mesh only: its BVH builds, the one before its frames and
    /// more after them (`GpuScene::build_bvh` on fresh layouts): one build
    /// is too noisy to compare with a frame.
    #[serde(default)]
    pub bvh_rebuild_ms: Option<Stat>,
}

impl TrianglePoint {
    /// The BVH build time to compare with a frame: the median of the
    /// repeated builds where there are some.
    pub fn build_ms(&self) -> f64 {
        self.bvh_rebuild_ms
            .as_ref()
            .map_or(self.bvh_build_ms, |b| b.median)
    }
}

/// One image size of the pixel scaling (section 3).
#[derive(Serialize, Deserialize, Clone, Debug, Default)]
pub struct SizePoint {
    pub width: u32,
    pub height: u32,
    pub rays: u64,
    pub render_ms: Stat,
}

/// One light count of the light scaling (section 3).
#[derive(Serialize, Deserialize, Clone, Debug, Default)]
pub struct LightPoint {
    pub lights: usize,
    pub rays: u64,
    pub render_ms: Stat,
}

/// Section 3: frame time against triangles, pixels and lights.
#[derive(Serialize, Deserialize, Clone, Debug, Default)]
pub struct ScalingPart {
    pub triangles: Vec<TrianglePoint>,
    pub pixels: Vec<SizePoint>,
    pub lights: Vec<LightPoint>,
}

/// Compile phases and SPIR-V size of one kernel.
#[derive(Serialize, Deserialize, Clone, Debug, Default)]
pub struct KernelCompile {
    pub spirv_bytes: usize,
    /// Per cold compile (two rounds, the order swapped in the second).
    pub naga_ms: Vec<f64>,
    pub pipeline_ms: Vec<f64>,
    pub driver_compile_ms: Vec<f64>,
}

/// The textures section: interleaved frames of the textured, masked and
/// untextured bunny scene.
#[derive(Serialize, Deserialize, Clone, Debug, Default)]
pub struct TexturesPart {
    /// A = the bunny scene textured, B = untextured.
    pub texturing: Pair,
    /// A = the textured scene with the bunny's material a cut-out, B = the
    /// textured scene.
    pub mask: Pair,
    /// Bytes of the textured scene's textures with their mip chains.
    pub texture_bytes: u64,
    /// The device the part ran on.
    #[serde(default)]
    pub device: Device,
}

/// Section 4: the specialised kernel against the general one, compiles and frames.
#[derive(Serialize, Deserialize, Clone, Debug, Default)]
pub struct SpecialisePart {
    pub specialised: KernelCompile,
    pub general: KernelCompile,
    /// A = general, B = specialised.
    pub frames: Pair,
    /// The showcase (no area light, 1 spp): A = area-light sampling code
    /// compiled in, B = left out (the default).
    #[serde(default)]
    pub sampling: Pair,
    /// Specialised by constants written into the WGSL text.
    #[serde(default)]
    pub text: KernelCompile,
    /// A = specialised by WGSL text, B = by overrides.
    #[serde(default)]
    pub text_frames: Pair,
}

/// The plain Rust CPU port against lavapipe, interleaved (section 6).
#[derive(Serialize, Deserialize, Clone, Debug, Default)]
pub struct CpuPart {
    pub threads: usize,
    pub width: u32,
    pub height: u32,
    pub cpu_ms: Stat,
    pub gpu_ms: Stat,
    /// GPU/CPU of each interleaved pair.
    pub ratio: Stat,
    pub cpu_hits: usize,
    pub gpu_hits: usize,
    pub cpu_shadow_rays: u64,
    pub gpu_shadow_rays: u64,
    pub max_abs_diff: f32,
    pub pixels_over_1e3: usize,
    /// Modelled SIMD-8 utilisation of the traversal loops (see report).
    pub simd8_utilisation: f64,
    /// Mean loop iterations per pixel (box/leaf visits + triangle tests).
    pub mean_steps: f64,
}

/// How long a child process ran and how busy the rest of the machine was.
#[derive(Serialize, Deserialize, Clone, Debug, Default)]
pub struct PartInfo {
    pub part: String,
    pub env: Vec<(String, String)>,
    pub wall_s: f64,
    /// CPU time of the benchmark's child process over its wall time (cores).
    pub own_cores: f64,
    /// CPU time of everything else on the machine over the same wall time
    /// (cores): other processes competing for the 2 cores.
    pub other_cores: f64,
    /// CPU time of niced processes (nice > 0), which yield to the benchmark,
    /// over the same wall time (cores); not in `other_cores`.
    #[serde(default)]
    pub niced_cores: f64,
}

/// One lavapipe setting, measured in several child processes interleaved
/// with the other settings.
#[derive(Serialize, Deserialize, Clone, Debug, Default)]
pub struct Knob {
    pub env: Vec<(String, String)>,
    pub device_name: String,
    pub driver_compile_ms: Vec<f64>,
    /// Every measured frame of every round.
    pub render_ms: Stat,
    /// Per round: the default setting's median / this setting's median.
    pub speedup_vs_default: Stat,
}

/// Where the time of a bunny run goes, from `perf record -e cpu-clock`.
#[derive(Serialize, Deserialize, Clone, Debug, Default)]
pub struct Profile {
    /// Why there is none, when there is none.
    pub skipped: Option<String>,
    pub samples: u64,
    /// (shared object, percent of samples), largest first.
    pub dsos: Vec<(String, f64)>,
    /// (symbol, percent), largest first: the top of the non-JIT code.
    pub symbols: Vec<(String, f64)>,
}

/// Everything one run measured.
#[derive(Serialize, Deserialize, Clone, Debug, Default)]
pub struct Results {
    pub machine: String,
    pub cores: usize,
    pub date: String,
    pub commit: String,
    pub command: String,
    /// The renderer's default triangle test (throughput, scaling, knobs).
    pub default_triangle_test: String,
    pub quick: bool,
    pub wall_s: f64,
    /// The benchmark's scheduling priority (nice value; the children and the
    /// peers inherit it): below 0 it ran ahead of other processes.
    #[serde(default)]
    pub nice: i64,
    /// The nice value of the benchmark's autogroup (its session), where the
    /// kernel groups processes by session: then the cores are shared between
    /// sessions by this value, and a process's own nice ranks it only within
    /// its session.
    #[serde(default)]
    pub autogroup_nice: Option<i64>,
    pub parts: Vec<PartInfo>,
    pub throughput: ThroughputPart,
    pub knob_rounds: usize,
    pub knobs: Vec<Knob>,
    pub profile: Profile,
    pub seminar: SeminarPart,
    pub scaling: ScalingPart,
    pub specialise: SpecialisePart,
    /// The cost of textures and of a cut-out; absent from reports written
    /// before the benchmark measured it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub textures: Option<TexturesPart>,
    pub cpu: CpuPart,
    /// The CPU, from /proc/cpuinfo.
    #[serde(default)]
    pub cpu_info: CpuInfo,
    /// Mitsuba 3 and Embree 4, interleaved with penumbra in this run.
    #[serde(default)]
    pub peers: PeersPart,
    /// The peers part again with AVX2 code on both sides, on a CPU with
    /// AVX-512: lavapipe under [`crate::parts::knobs::AVX2_CAP`], the peers
    /// under `PENUMBRA_PEERS_ISA=avx2` (tools/measure/peers/peers.py). Absent on a
    /// CPU without AVX-512, where [`Results::peers`] is AVX2 code already.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub peers_avx2: Option<PeersPart>,
    /// The driver matrix; absent from reports written before the benchmark
    /// measured it, and with `--no-knobs` (on a GPU it does not apply).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub drivers: Option<DriversPart>,
    /// The packet traversal against the per-lane one; absent from reports
    /// written before the benchmark measured it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub packet: Option<PacketPart>,
    /// The one-shot CLI render, timed end to end; absent from reports
    /// written before the benchmark timed it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cli: Option<CliPart>,
}

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
    /// The device penumbra ran on (absent from runs before it was kept).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub device: Option<Device>,
    /// The triangles of the scene (absent from runs before it was kept).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub triangles: u64,
}

/// The driver matrix (`crate::parts::drivers`): the bunny and the showcase
/// on every lavapipe at hand.
#[derive(Serialize, Deserialize, Clone, Debug, Default)]
pub struct DriversPart {
    /// Why only the installed driver ran, when no other tree was found.
    pub note: Option<String>,
    pub rounds: usize,
    /// The installed driver first.
    pub drivers: Vec<DriverRun>,
}

/// One driver of the matrix.
#[derive(Serialize, Deserialize, Clone, Debug, Default)]
pub struct DriverRun {
    /// `installed`, or the ICD file of the tree, relative to the repository.
    pub icd: String,
    /// The device as the driver names it (its first round).
    pub device: Device,
    /// Why a round failed, when one did.
    pub error: Option<String>,
    pub scenes: Vec<DriverScene>,
}

/// One scene on one driver.
#[derive(Serialize, Deserialize, Clone, Debug, Default)]
pub struct DriverScene {
    pub scene: String,
    pub width: u32,
    pub height: u32,
    /// Primary + shadow rays of a frame.
    pub rays: u64,
    /// The driver's cold compile, per round.
    pub driver_compile_ms: Vec<f64>,
    /// Every frame of every round.
    pub render_ms: Stat,
    /// Per round: the installed driver's median frame / this driver's.
    pub speed_vs_installed: Stat,
}

impl DriverScene {
    /// Primary + shadow rays per second at the median frame, in millions.
    pub fn mrays(&self) -> f64 {
        self.rays as f64 / self.render_ms.median / 1e3
    }
}

/// The one-shot CLI render: `penumbra render` of the bunny scene as a user
/// runs it, the whole process timed from spawn to exit (loading, device
/// start-up, compile, BVH, frame, PNG), with Mesa's shader cache cold (a
/// fresh cache directory per run) and warm (one directory, filled by a run
/// before the measured ones).
#[derive(Serialize, Deserialize, Clone, Debug, Default)]
pub struct CliPart {
    /// Why the CLI was not timed, when it was not.
    pub not_measured: Option<String>,
    /// The command timed, as a user would type it.
    pub command: String,
    /// Wall time of each process with a cold shader cache, ms.
    pub cold_ms: Stat,
    /// Wall time of each process with a warm shader cache, ms.
    pub warm_ms: Stat,
}

/// For `skip_serializing_if`: a count absent from older results.
fn is_zero(n: &u64) -> bool {
    *n == 0
}
