//! The SIMD width lavapipe compiles the kernel for, chosen for the job.
//!
//! lavapipe (llvmpipe) runs a compute shader's invocations in SIMD lanes of
//! `LP_NATIVE_VECTOR_WIDTH` bits (128, 256 or 512), read once when the driver
//! loads. Wider vectors can trace more rays per instruction but make the
//! driver's compile of the kernel slower, so the right width depends on the
//! kernel and the job: where a kernel runs faster at 512 bits on a CPU with
//! AVX-512, a batch render long enough to repay the longer compile wants them,
//! while `watch`, where every shader edit waits for the compile, keeps 256. The
//! current kernel runs slower at 512 bits ([`WIDE_SPEEDUP`]), so auto keeps
//! 256 for every job. The figures behind the rule are in docs/drivers.md
//! ("Vector width").
//!
//! [`choose`] is the decision as a pure function (CPU features, environment and
//! job in, width out) so that every branch is testable on any machine; [`apply`]
//! puts it into the process environment, which must happen before the Vulkan
//! instance is created. The variable has no effect on GPU drivers.
//!
//! Mesa's shader cache does not key its entries by the vector width: lavapipe
//! of Mesa 25.0 loads the machine code that a 256-bit run cached into a 512-bit
//! run, and the reverse (docs/drivers.md, "The shader cache and the width").
//! So [`apply`] also gives each width a cache directory of its own
//! ([`cache_dir`]), and a width once chosen is the width the kernel runs at.

use std::ffi::OsString;
use std::fmt;
use std::path::{Path, PathBuf};
use std::str::FromStr;
use std::time::Duration;

/// The environment variable lavapipe reads its vector width from.
pub const VARIABLE: &str = "LP_NATIVE_VECTOR_WIDTH";

/// The environment variable that names the directory of Mesa's shader cache.
pub const CACHE_VARIABLE: &str = "MESA_SHADER_CACHE_DIR";

/// The name of a width's own cache directory starts with this; the width follows.
pub const CACHE_PREFIX: &str = "penumbra-lp";

/// 512-bit vectors' speed-up over 256-bit ones for the current kernel on a CPU
/// with AVX-512 (frame time at 256 / at 512; docs/drivers.md, "Vector width",
/// gives the measurements). At or below 1 the wider vectors never pay, however
/// long the render, and auto keeps 256: so it is for the staged renderer, whose
/// frames run slower at 512 bits; the megakernel before it ran faster.
pub const WIDE_SPEEDUP: f64 = 0.91;

/// A render is "long" (worth 512-bit vectors, where they are faster) from this many primary rays
/// (width × height × passes) on: 64 passes at 1024×1024.
pub const LONG_RENDER_PRIMARY_RAYS: u64 = 1 << 26;

/// A render stopped by a time budget shorter than this is never "long": the
/// longer compile would take too large a share of it.
pub const LONG_RENDER_MIN_BUDGET: Duration = Duration::from_secs(5);

/// The pixel count assumed when the command line does not give the size
/// (`--width` and `--height`): the benchmark's 1024×1024. The scene's own size
/// is not known yet when the width must be chosen (before the device is made).
pub const ASSUMED_PIXELS: u64 = 1 << 20;

/// What `--vector-width` asked for.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Request {
    /// Choose by CPU and job ([`choose`]).
    #[default]
    Auto,
    /// This many bits: 128, 256 or 512.
    Bits(u32),
}

impl FromStr for Request {
    type Err = String;
    fn from_str(s: &str) -> Result<Request, String> {
        match s {
            "auto" => Ok(Request::Auto),
            "128" => Ok(Request::Bits(128)),
            "256" => Ok(Request::Bits(256)),
            "512" => Ok(Request::Bits(512)),
            _ => Err(format!("expected auto, 128, 256 or 512, got `{s}`")),
        }
    }
}

/// The vector instruction sets of the CPU that decide the width.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CpuVectors {
    /// 256-bit AVX (AVX2 or plain AVX): lavapipe's default width is 256 with it.
    pub avx: bool,
    /// AVX-512 Foundation: 512-bit vectors run natively.
    pub avx512f: bool,
}

impl CpuVectors {
    /// This CPU's, as the operating system lets programs use them.
    pub fn detect() -> CpuVectors {
        #[cfg(any(target_arch = "x86", target_arch = "x86_64"))]
        {
            CpuVectors {
                avx: std::arch::is_x86_feature_detected!("avx"),
                avx512f: std::arch::is_x86_feature_detected!("avx512f"),
            }
        }
        #[cfg(not(any(target_arch = "x86", target_arch = "x86_64")))]
        {
            CpuVectors::default()
        }
    }

    /// The instruction sets Mesa will target: `GALLIUM_OVERRIDE_CPU_CAPS`
    /// (e.g. `avx`) caps them, so AVX-512 counts only if the override names it.
    pub fn capped_by(self, gallium_override: Option<&str>) -> CpuVectors {
        match gallium_override {
            Some(caps) if !caps.contains("avx512") => CpuVectors {
                avx: self.avx && caps.contains("avx"),
                avx512f: false,
            },
            _ => self,
        }
    }
}

/// The kind of work the driver will compile for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Job {
    /// A one-off batch render (`penumbra render`).
    Render {
        /// Width × height, if the command line gives both; else [`ASSUMED_PIXELS`].
        pixels: Option<u64>,
        /// Passes (`--spp`).
        passes: u32,
        /// `--time-budget`, which may stop the render early.
        time_budget: Option<Duration>,
    },
    /// Hot reload (`penumbra watch`): compile latency matters most.
    Watch,
}

impl Job {
    /// Whether a render is long enough to repay 512-bit vectors' longer compile.
    pub fn is_long(&self) -> bool {
        match *self {
            Job::Render {
                pixels,
                passes,
                time_budget,
            } => {
                let rays = pixels
                    .unwrap_or(ASSUMED_PIXELS)
                    .saturating_mul(passes as u64);
                rays >= LONG_RENDER_PRIMARY_RAYS
                    && time_budget.is_none_or(|b| b >= LONG_RENDER_MIN_BUDGET)
            }
            Job::Watch => false,
        }
    }
}

/// Why the width is what it is.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Reason {
    /// `LP_NATIVE_VECTOR_WIDTH` was already set by the user: always respected.
    Environment,
    /// `--vector-width N`.
    Flag,
    /// Auto: AVX-512 and a long render.
    LongRenderWithAvx512,
    /// Auto: AVX-512, but the render is too short to repay the compile.
    ShortRender,
    /// Auto: AVX-512, but the kernel runs slower at 512 bits ([`WIDE_SPEEDUP`]).
    WideSlower,
    /// Auto: `watch` keeps 256 for compile latency.
    Watch,
    /// Auto: no AVX-512 on this CPU.
    NoAvx512,
    /// Auto: no AVX either; the driver's default (128) is left alone.
    NoAvx,
}

/// The chosen width and why.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Choice {
    /// The width in bits that the process will run lavapipe with; `None` when
    /// the variable is left unset and the driver picks its default.
    pub bits: Option<u32>,
    /// The user's own value of `LP_NATIVE_VECTOR_WIDTH`, verbatim, when it was set.
    pub user_value: Option<String>,
    /// Why.
    pub reason: Reason,
}

impl fmt::Display for Choice {
    /// The summary line's phrase, e.g. `vector width 512 (auto: AVX-512, long render)`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match (&self.user_value, self.bits) {
            (Some(v), _) => write!(f, "vector width {v}")?,
            (None, Some(b)) => write!(f, "vector width {b}")?,
            (None, None) => write!(f, "vector width driver default")?,
        }
        let why = match self.reason {
            Reason::Environment => "LP_NATIVE_VECTOR_WIDTH set",
            Reason::Flag => "--vector-width",
            Reason::LongRenderWithAvx512 => "auto: AVX-512, long render",
            Reason::ShortRender => "auto: AVX-512, short render",
            Reason::WideSlower => "auto: AVX-512, but 512 bits run this kernel slower",
            Reason::Watch => "auto: watch",
            Reason::NoAvx512 => "auto: no AVX-512",
            Reason::NoAvx => "auto: no AVX",
        };
        write!(f, " ({why})")
    }
}

/// Chooses the width for the current kernel: [`choose_for_kernel`] with its
/// measured [`WIDE_SPEEDUP`].
pub fn choose(request: Request, env: Option<&str>, cpu: CpuVectors, job: Job) -> Choice {
    choose_for_kernel(request, env, cpu, job, WIDE_SPEEDUP)
}

/// Chooses the width for a kernel whose 512-bit frames run `wide_speedup`
/// times as fast as its 256-bit ones: the user's `LP_NATIVE_VECTOR_WIDTH`
/// (`env`) first, then `--vector-width`, else by CPU and job — 512 for a long
/// render ([`Job::is_long`]) on a CPU with AVX-512 if the wider vectors are
/// faster, 256 on any CPU with AVX otherwise (`watch` included), and the
/// driver's default without AVX.
pub fn choose_for_kernel(
    request: Request,
    env: Option<&str>,
    cpu: CpuVectors,
    job: Job,
    wide_speedup: f64,
) -> Choice {
    if let Some(v) = env {
        return Choice {
            bits: v.trim().parse().ok(),
            user_value: Some(v.to_owned()),
            reason: Reason::Environment,
        };
    }
    let (bits, reason) = match request {
        Request::Bits(b) => (Some(b), Reason::Flag),
        Request::Auto if !cpu.avx => (None, Reason::NoAvx),
        Request::Auto if job == Job::Watch => (Some(256), Reason::Watch),
        Request::Auto if !cpu.avx512f => (Some(256), Reason::NoAvx512),
        Request::Auto if wide_speedup <= 1.0 => (Some(256), Reason::WideSlower),
        Request::Auto if job.is_long() => (Some(512), Reason::LongRenderWithAvx512),
        Request::Auto => (Some(256), Reason::ShortRender),
    };
    Choice {
        bits,
        user_value: None,
        reason,
    }
}

/// The shader cache directory for `bits`-wide code: `penumbra-lp{bits}` under
/// the directory Mesa would use otherwise (`MESA_SHADER_CACHE_DIR`, else
/// `$XDG_CACHE_HOME`, else `$HOME/.cache`), or in place of a `penumbra-lp…`
/// directory that a parent penumbra process chose, so that widths never nest.
/// `None` where Mesa's cache is disabled (`MESA_SHADER_CACHE_DISABLE` true) or
/// no base directory is known. `var` reads the environment.
pub fn cache_dir(bits: u32, var: impl Fn(&str) -> Option<OsString>) -> Option<PathBuf> {
    let disabled = var("MESA_SHADER_CACHE_DISABLE").is_some_and(|v| {
        matches!(
            v.to_string_lossy().to_ascii_lowercase().as_str(),
            "1" | "true" | "yes" | "y"
        )
    });
    if disabled {
        return None;
    }
    let nonempty = |k: &str| var(k).filter(|v| !v.is_empty()).map(PathBuf::from);
    let base = nonempty(CACHE_VARIABLE)
        .or_else(|| nonempty("XDG_CACHE_HOME"))
        .or_else(|| nonempty("HOME").map(|h| h.join(".cache")))?;
    let ours = |p: &Path| {
        p.file_name()
            .is_some_and(|n| n.to_string_lossy().starts_with(CACHE_PREFIX))
    };
    let base = match base.parent() {
        Some(parent) if ours(&base) => parent.to_path_buf(),
        _ => base,
    };
    Some(base.join(format!("{CACHE_PREFIX}{bits}")))
}

/// Chooses for this process ([`choose`] with this CPU and environment) and sets
/// `LP_NATIVE_VECTOR_WIDTH` accordingly, with `MESA_SHADER_CACHE_DIR` set to
/// the width's own [`cache_dir`] (made if missing; if it cannot be made, Mesa
/// runs without a disk cache, as it does for any unwritable directory). Call it
/// before the Vulkan instance is created (lavapipe reads both when it loads)
/// and while no other thread reads the environment: early in `main`.
pub fn apply(request: Request, job: Job) -> Choice {
    let env = std::env::var(VARIABLE).ok();
    let gallium = std::env::var("GALLIUM_OVERRIDE_CPU_CAPS").ok();
    let cpu = CpuVectors::detect().capped_by(gallium.as_deref());
    let choice = choose(request, env.as_deref(), cpu, job);
    if choice.user_value.is_none() {
        if let Some(b) = choice.bits {
            std::env::set_var(VARIABLE, b.to_string());
        }
    }
    if let Some(dir) = choice
        .bits
        .and_then(|b| cache_dir(b, |k| std::env::var_os(k)))
    {
        let _ = std::fs::create_dir_all(&dir);
        std::env::set_var(CACHE_VARIABLE, dir);
    }
    choice
}

#[cfg(test)]
mod tests {
    use super::*;

    const ZEN3: CpuVectors = CpuVectors {
        avx: true,
        avx512f: false,
    };
    const ZEN4: CpuVectors = CpuVectors {
        avx: true,
        avx512f: true,
    };
    const SSE_ONLY: CpuVectors = CpuVectors {
        avx: false,
        avx512f: false,
    };

    fn render(pixels: Option<u64>, passes: u32, budget: Option<u64>) -> Job {
        Job::Render {
            pixels,
            passes,
            time_budget: budget.map(Duration::from_secs),
        }
    }

    /// A kernel whose 512-bit frames are faster: the megakernel's 1.13.
    fn choose(request: Request, env: Option<&str>, cpu: CpuVectors, job: Job) -> Choice {
        choose_for_kernel(request, env, cpu, job, 1.13)
    }

    #[test]
    fn this_kernel_keeps_256_on_avx512_since_512_bits_run_it_slower() {
        for job in [
            render(None, 1 << 20, None),
            render(None, 1, None),
            Job::Watch,
        ] {
            let c = super::choose(Request::Auto, None, ZEN4, job);
            assert_eq!(c.bits, Some(256), "{job:?}");
        }
        let c = super::choose(Request::Auto, None, ZEN4, render(None, 1000, None));
        assert_eq!(
            c.to_string(),
            "vector width 256 (auto: AVX-512, but 512 bits run this kernel slower)"
        );
        // The flag and the environment still give 512.
        let c = super::choose(Request::Bits(512), None, ZEN4, render(None, 1, None));
        assert_eq!((c.bits, c.reason), (Some(512), Reason::Flag));
        let c = super::choose(Request::Auto, Some("512"), ZEN4, Job::Watch);
        assert_eq!(c.bits, Some(512));
    }

    #[test]
    fn long_renders_on_avx512_get_512_where_it_is_faster() {
        let c = choose(Request::Auto, None, ZEN4, render(None, 64, None));
        assert_eq!(c.bits, Some(512));
        assert_eq!(
            c.to_string(),
            "vector width 512 (auto: AVX-512, long render)"
        );
        // 1920x1080 at 33 passes is past 2^26 primary rays; at 32 it is not.
        let hd = Some(1920 * 1080);
        assert_eq!(
            choose(Request::Auto, None, ZEN4, render(hd, 33, None)).bits,
            Some(512)
        );
        assert_eq!(
            choose(Request::Auto, None, ZEN4, render(hd, 32, None)).reason,
            Reason::ShortRender
        );
    }

    #[test]
    fn short_renders_and_watch_keep_256() {
        let c = choose(Request::Auto, None, ZEN4, render(None, 63, None));
        assert_eq!((c.bits, c.reason), (Some(256), Reason::ShortRender));
        let c = choose(Request::Auto, None, ZEN4, render(Some(64 * 64), 1024, None));
        assert_eq!(
            c.bits,
            Some(256),
            "64x64 at 1024 passes is 2^22 rays: short"
        );
        let c = choose(
            Request::Auto,
            None,
            ZEN4,
            render(Some(64 * 64), 1 << 16, None),
        );
        assert_eq!(
            c.bits,
            Some(512),
            "64x64 at 65536 passes is 2^28 rays: long"
        );
        let c = choose(Request::Auto, None, ZEN4, Job::Watch);
        assert_eq!(c.to_string(), "vector width 256 (auto: watch)");
        // A time budget under 5 s caps the render's length.
        let c = choose(Request::Auto, None, ZEN4, render(None, 1000, Some(4)));
        assert_eq!(c.reason, Reason::ShortRender);
        let c = choose(Request::Auto, None, ZEN4, render(None, 1000, Some(5)));
        assert_eq!(c.bits, Some(512));
    }

    #[test]
    fn without_avx512_it_is_256_and_without_avx_the_default() {
        let c = choose(Request::Auto, None, ZEN3, render(None, 1000, None));
        assert_eq!(c.to_string(), "vector width 256 (auto: no AVX-512)");
        let c = choose(Request::Auto, None, SSE_ONLY, render(None, 1000, None));
        assert_eq!(c.to_string(), "vector width driver default (auto: no AVX)");
        assert_eq!(choose(Request::Auto, None, SSE_ONLY, Job::Watch).bits, None);
    }

    #[test]
    fn the_flag_overrides_and_the_environment_wins() {
        let c = choose(Request::Bits(128), None, ZEN4, render(None, 1000, None));
        assert_eq!(c.to_string(), "vector width 128 (--vector-width)");
        let c = choose(Request::Bits(512), None, ZEN3, Job::Watch);
        assert_eq!(c.bits, Some(512));
        let c = choose(Request::Bits(128), Some("512"), ZEN3, Job::Watch);
        assert_eq!(
            c.to_string(),
            "vector width 512 (LP_NATIVE_VECTOR_WIDTH set)"
        );
        assert_eq!(c.bits, Some(512));
        let c = choose(Request::Auto, Some("weird"), ZEN4, render(None, 1000, None));
        assert_eq!((c.bits, c.user_value.as_deref()), (None, Some("weird")));
    }

    #[test]
    fn gallium_override_caps_avx512() {
        assert_eq!(ZEN4.capped_by(Some("avx")), ZEN3);
        assert_eq!(ZEN4.capped_by(Some("avx512")), ZEN4);
        assert_eq!(ZEN4.capped_by(Some("sse4.1")), SSE_ONLY);
        assert_eq!(ZEN4.capped_by(None), ZEN4);
        let cpu = ZEN4.capped_by(Some("avx"));
        assert_eq!(
            choose(Request::Auto, None, cpu, render(None, 64, None)).bits,
            Some(256)
        );
    }

    /// An environment of these variables only.
    fn vars(pairs: &[(&str, &str)]) -> impl Fn(&str) -> Option<OsString> {
        let owned: Vec<(String, OsString)> = pairs
            .iter()
            .map(|(k, v)| (k.to_string(), OsString::from(v)))
            .collect();
        move |k| owned.iter().find(|(n, _)| n == k).map(|(_, v)| v.clone())
    }

    #[test]
    fn each_width_has_its_own_cache_directory() {
        let home = vars(&[("HOME", "/home/u")]);
        assert_eq!(
            cache_dir(512, &home),
            Some(PathBuf::from("/home/u/.cache/penumbra-lp512"))
        );
        assert_ne!(cache_dir(256, &home), cache_dir(512, &home));
        let xdg = vars(&[("HOME", "/home/u"), ("XDG_CACHE_HOME", "/x")]);
        assert_eq!(
            cache_dir(256, xdg),
            Some(PathBuf::from("/x/penumbra-lp256"))
        );
        // The user's own directory is the base: a farm's shared cache stays shared.
        let user = vars(&[("HOME", "/home/u"), (CACHE_VARIABLE, "/shared/mesa")]);
        assert_eq!(
            cache_dir(512, user),
            Some(PathBuf::from("/shared/mesa/penumbra-lp512"))
        );
        // A parent penumbra's choice is replaced, not nested.
        let parent = vars(&[(CACHE_VARIABLE, "/shared/mesa/penumbra-lp256")]);
        assert_eq!(
            cache_dir(512, parent),
            Some(PathBuf::from("/shared/mesa/penumbra-lp512"))
        );
    }

    #[test]
    fn a_disabled_cache_or_no_base_gets_no_directory() {
        for v in ["true", "1", "TRUE", "yes"] {
            let off = vars(&[("HOME", "/home/u"), ("MESA_SHADER_CACHE_DISABLE", v)]);
            assert_eq!(cache_dir(512, off), None, "{v}");
        }
        let on = vars(&[("HOME", "/home/u"), ("MESA_SHADER_CACHE_DISABLE", "false")]);
        assert!(cache_dir(512, on).is_some());
        assert_eq!(cache_dir(512, vars(&[])), None);
        assert_eq!(cache_dir(512, vars(&[("HOME", "")])), None);
    }

    #[test]
    fn requests_parse_and_bad_ones_are_refused() {
        assert_eq!("auto".parse(), Ok(Request::Auto));
        assert_eq!("512".parse(), Ok(Request::Bits(512)));
        assert!("300".parse::<Request>().unwrap_err().contains("300"));
        assert!("".parse::<Request>().is_err());
    }
}
