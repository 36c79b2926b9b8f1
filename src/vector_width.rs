//! The SIMD width lavapipe compiles the kernel for, chosen for the job.
//!
//! lavapipe (llvmpipe) runs a compute shader's invocations in SIMD lanes of
//! `LP_NATIVE_VECTOR_WIDTH` bits (128, 256 or 512), read once when the driver
//! loads. Wider vectors can trace more rays per instruction but make the
//! driver's compile of the kernel slower, so the right width depends on the
//! kernel, the CPU and the job: on a CPU with AVX-512 the kernel ran 0.91× as
//! fast at 512 bits on a Zen 4 and 1.20× on a Xeon, so no fixed rule fits, and
//! auto takes what the calibration measured on this machine
//! ([`crate::calibration`]; 512 bits for long renders only, since they double
//! the driver's compile), 256 bits where nothing was measured. The figures are
//! in docs/drivers.md ("Vector width", "Calibration").
//!
//! [`choose`] is the decision as a pure function (CPU features, environment,
//! job and measured times in, settings out) so that every branch is testable on
//! any machine; [`apply`] puts it into the process environment, which must
//! happen before the Vulkan instance is created. The variables have no effect
//! on GPU drivers.
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

use crate::calibration::Measured;

/// The environment variable lavapipe reads its vector width from.
pub const VARIABLE: &str = "LP_NATIVE_VECTOR_WIDTH";

/// The environment variable that names the directory of Mesa's shader cache.
pub const CACHE_VARIABLE: &str = "MESA_SHADER_CACHE_DIR";

/// The name of a width's own cache directory starts with this; the width follows.
pub const CACHE_PREFIX: &str = "penumbra-lp";

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
    /// Auto: the calibration measured this setting faster than the default
    /// by the speed-up, in thousandths (1250: 1.25×).
    Calibrated {
        /// The default's median frame time over this setting's, × 1000.
        speedup_milli: u32,
    },
    /// Auto: the calibration measured nothing faster than the default by
    /// more than its margin ([`crate::calibration::MARGIN`]).
    CalibratedDefault,
    /// Auto: AVX-512, but this machine has no calibration (or the user's
    /// `GALLIUM_OVERRIDE_CPU_CAPS` rules it out): the default, 256.
    NotCalibrated,
    /// Auto: no AVX-512 on this CPU.
    NoAvx512,
    /// Auto: no AVX either; the driver's default (128) is left alone.
    NoAvx,
}

/// The chosen settings and why.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Choice {
    /// The width in bits that the process will run lavapipe with; `None` when
    /// the variable is left unset and the driver picks its default.
    pub bits: Option<u32>,
    /// `GALLIUM_OVERRIDE_CPU_CAPS` to set (the calibration's AVX2 code).
    pub caps: Option<&'static str>,
    /// The user's own value of `LP_NATIVE_VECTOR_WIDTH`, verbatim, when it was set.
    pub user_value: Option<String>,
    /// Why.
    pub reason: Reason,
}

impl fmt::Display for Choice {
    /// The summary line's phrase, e.g. `vector width 512 (calibrated on this
    /// machine: 1.14× the default's speed)`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match (&self.user_value, self.bits) {
            (Some(v), _) => write!(f, "vector width {v}")?,
            (None, Some(b)) => write!(f, "vector width {b}")?,
            (None, None) => write!(f, "vector width driver default")?,
        }
        if self.caps.is_some() {
            write!(f, ", AVX2 code")?;
        }
        match &self.reason {
            Reason::Environment => write!(f, " (LP_NATIVE_VECTOR_WIDTH set)"),
            Reason::Flag => write!(f, " (--vector-width)"),
            Reason::Calibrated { speedup_milli } => write!(
                f,
                " (calibrated on this machine: {:.2}x the default's speed)",
                *speedup_milli as f64 / 1000.0
            ),
            Reason::CalibratedDefault => write!(
                f,
                " (calibrated on this machine: nothing {:.0} % faster than the default)",
                (crate::calibration::MARGIN - 1.0) * 100.0
            ),
            Reason::NotCalibrated => write!(
                f,
                " (auto: AVX-512, not calibrated; `penumbra calibrate` measures)"
            ),
            Reason::NoAvx512 => write!(f, " (auto: no AVX-512)"),
            Reason::NoAvx => write!(f, " (auto: no AVX)"),
        }
    }
}

/// Chooses the settings: the user's `LP_NATIVE_VECTOR_WIDTH` (`env`) first,
/// then `--vector-width`, else by CPU, job and this machine's calibration
/// (`measured`, [`crate::calibration::decide`]): the driver's default
/// without AVX, 256 without AVX-512, and with AVX-512 the calibration's
/// choice, or 256 where there is none.
pub fn choose(
    request: Request,
    env: Option<&str>,
    cpu: CpuVectors,
    job: Job,
    measured: Option<&[Measured]>,
) -> Choice {
    if let Some(v) = env {
        return Choice {
            bits: v.trim().parse().ok(),
            caps: None,
            user_value: Some(v.to_owned()),
            reason: Reason::Environment,
        };
    }
    let decision = measured.and_then(|m| crate::calibration::decide(m, job));
    let (bits, caps, reason) = match (request, decision) {
        (Request::Bits(b), _) => (Some(b), None, Reason::Flag),
        (Request::Auto, _) if !cpu.avx => (None, None, Reason::NoAvx),
        (Request::Auto, _) if !cpu.avx512f => (Some(256), None, Reason::NoAvx512),
        (Request::Auto, None) => (Some(256), None, Reason::NotCalibrated),
        (Request::Auto, Some(d)) if d.candidate == crate::calibration::DEFAULT => {
            (Some(d.candidate.bits()), None, Reason::CalibratedDefault)
        }
        (Request::Auto, Some(d)) => (
            Some(d.candidate.bits()),
            d.candidate.caps(),
            Reason::Calibrated {
                speedup_milli: (d.speedup * 1000.0).round() as u32,
            },
        ),
    };
    Choice {
        bits,
        caps,
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
    let base = var(CACHE_VARIABLE)
        .filter(|v| !v.is_empty())
        .map(PathBuf::from)
        .or_else(|| crate::user_cache::user_cache_dir(&var))?;
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

/// Chooses for this process ([`choose`] with this CPU, environment and
/// calibration) and sets `LP_NATIVE_VECTOR_WIDTH` (and
/// `GALLIUM_OVERRIDE_CPU_CAPS` for the calibration's AVX2 code) accordingly,
/// with `MESA_SHADER_CACHE_DIR` set to
/// the width's own [`cache_dir`] (made if missing; if it cannot be made, Mesa
/// runs without a disk cache, as it does for any unwritable directory). Call it
/// before the Vulkan instance is created (lavapipe reads both when it loads)
/// and while no other thread reads the environment: early in `main`.
///
/// A `GALLIUM_OVERRIDE_CPU_CAPS` of the user's is never changed: with it the
/// calibration is not used.
pub fn apply(request: Request, job: Job, measured: Option<&[Measured]>) -> Choice {
    apply_for(CpuVectors::detect(), request, job, measured)
}

/// [`apply`] as on a CPU with these instruction sets (a test's fake
/// calibration names a CPU with AVX-512 on any machine).
pub fn apply_for(
    cpu: CpuVectors,
    request: Request,
    job: Job,
    measured: Option<&[Measured]>,
) -> Choice {
    let env = std::env::var(VARIABLE).ok();
    let gallium = std::env::var(crate::calibration::CAPS_VARIABLE).ok();
    let cpu = cpu.capped_by(gallium.as_deref());
    let measured = measured.filter(|_| gallium.is_none());
    let choice = choose(request, env.as_deref(), cpu, job, measured);
    if choice.user_value.is_none() {
        if let Some(b) = choice.bits {
            std::env::set_var(VARIABLE, b.to_string());
        }
        if let Some(c) = choice.caps {
            std::env::set_var(crate::calibration::CAPS_VARIABLE, c);
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
    use crate::calibration::Candidate;

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

    /// Made-up medians of 256 bits, 512 bits and AVX2 code at 256 bits.
    fn times(w256: f64, w512: f64, avx2: f64) -> Vec<Measured> {
        [
            (Candidate::Wide256, w256),
            (Candidate::Wide512, w512),
            (Candidate::Avx2At256, avx2),
        ]
        .iter()
        .map(|&(c, t)| Measured::of(c, &[t]).unwrap())
        .collect()
    }

    #[test]
    fn avx512_without_a_calibration_keeps_256_and_says_so() {
        for job in [
            render(None, 1 << 20, None),
            render(None, 1, None),
            Job::Watch,
        ] {
            let c = choose(Request::Auto, None, ZEN4, job, None);
            assert_eq!(
                (c.bits, c.caps, &c.reason),
                (Some(256), None, &Reason::NotCalibrated)
            );
        }
        let c = choose(Request::Auto, None, ZEN4, Job::Watch, None);
        assert_eq!(
            c.to_string(),
            "vector width 256 (auto: AVX-512, not calibrated; `penumbra calibrate` measures)"
        );
    }

    #[test]
    fn a_calibration_gives_its_choice_and_speed_up() {
        let t = times(100.0, 80.0, 95.0);
        let c = choose(Request::Auto, None, ZEN4, render(None, 64, None), Some(&t));
        assert_eq!((c.bits, c.caps), (Some(512), None));
        assert_eq!(
            c.to_string(),
            "vector width 512 (calibrated on this machine: 1.25x the default's speed)"
        );
        // A short render or watch: the best 256-bit setting, AVX2 code here.
        for job in [render(None, 63, None), Job::Watch] {
            let c = choose(Request::Auto, None, ZEN4, job, Some(&t));
            assert_eq!((c.bits, c.caps), (Some(256), Some("avx")), "{job:?}");
            assert_eq!(
                c.to_string(),
                "vector width 256, AVX2 code (calibrated on this machine: 1.05x the default's speed)"
            );
        }
        let t = times(100.0, 101.0, 99.0);
        let c = choose(Request::Auto, None, ZEN4, render(None, 64, None), Some(&t));
        assert_eq!(
            (c.bits, c.caps, &c.reason),
            (Some(256), None, &Reason::CalibratedDefault)
        );
        assert_eq!(
            c.to_string(),
            "vector width 256 (calibrated on this machine: nothing 3 % faster than the default)"
        );
    }

    #[test]
    fn long_renders_are_2_to_the_26_primary_rays_within_a_budget_of_5_s() {
        let hd = Some(1920 * 1080);
        assert!(render(hd, 33, None).is_long());
        assert!(!render(hd, 32, None).is_long());
        assert!(render(None, 64, None).is_long());
        assert!(!render(None, 63, None).is_long());
        assert!(!render(Some(64 * 64), 1024, None).is_long());
        assert!(render(Some(64 * 64), 1 << 16, None).is_long());
        assert!(!render(None, 1000, Some(4)).is_long());
        assert!(render(None, 1000, Some(5)).is_long());
        assert!(!Job::Watch.is_long());
    }

    #[test]
    fn without_avx512_it_is_256_and_without_avx_the_default() {
        let t = times(100.0, 50.0, 50.0);
        let c = choose(
            Request::Auto,
            None,
            ZEN3,
            render(None, 1000, None),
            Some(&t),
        );
        assert_eq!(c.to_string(), "vector width 256 (auto: no AVX-512)");
        let c = choose(
            Request::Auto,
            None,
            SSE_ONLY,
            render(None, 1000, None),
            None,
        );
        assert_eq!(c.to_string(), "vector width driver default (auto: no AVX)");
        assert_eq!(
            choose(Request::Auto, None, SSE_ONLY, Job::Watch, None).bits,
            None
        );
    }

    #[test]
    fn the_flag_overrides_and_the_environment_wins_over_a_calibration() {
        let t = times(100.0, 50.0, 60.0);
        let long = render(None, 1000, None);
        let c = choose(Request::Bits(128), None, ZEN4, long, Some(&t));
        assert_eq!(c.to_string(), "vector width 128 (--vector-width)");
        assert_eq!(c.caps, None);
        let c = choose(Request::Bits(512), None, ZEN3, Job::Watch, None);
        assert_eq!(c.bits, Some(512));
        let c = choose(Request::Bits(128), Some("512"), ZEN3, Job::Watch, Some(&t));
        assert_eq!(
            c.to_string(),
            "vector width 512 (LP_NATIVE_VECTOR_WIDTH set)"
        );
        let c = choose(Request::Auto, Some("256"), ZEN4, long, Some(&t));
        assert_eq!((c.bits, c.caps), (Some(256), None));
        let c = choose(Request::Auto, Some("weird"), ZEN4, long, None);
        assert_eq!((c.bits, c.user_value.as_deref()), (None, Some("weird")));
    }

    #[test]
    fn gallium_override_caps_avx512() {
        assert_eq!(ZEN4.capped_by(Some("avx")), ZEN3);
        assert_eq!(ZEN4.capped_by(Some("avx512")), ZEN4);
        assert_eq!(ZEN4.capped_by(Some("sse4.1")), SSE_ONLY);
        assert_eq!(ZEN4.capped_by(None), ZEN4);
        let cpu = ZEN4.capped_by(Some("avx"));
        let t = times(100.0, 50.0, 60.0);
        assert_eq!(
            choose(Request::Auto, None, cpu, render(None, 64, None), Some(&t)).bits,
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
