//! lavapipe's knobs chosen by measurement on this machine, and remembered
//! (as FFTW keeps its wisdom).
//!
//! No fixed rule picks lavapipe's settings well on every CPU: 512-bit vectors
//! ran the staged kernel 0.91× as fast on a Zen 4, 1.14× on a Zen 5 and 1.20×
//! on a Xeon with AVX-512, and AVX2 code at 256 bits was faster than AVX-512
//! code at 256 bits on that Xeon and slower on the Zen 5 (issue 40). So on a
//! CPU with AVX-512 the [`Candidate`]s are timed on this machine
//! ([`probe`], each in a child process, since Mesa reads its variables when
//! the driver loads), the times are kept per CPU, kernel and driver in the
//! user's cache directory ([`wisdom`]), and [`decide`] chooses from them: a
//! pure function of the measured times and the job, tested with made-up
//! times. docs/drivers.md ("Calibration") states the rule and its cost.

pub mod probe;
pub mod wisdom;

use serde::{Deserialize, Serialize};

use crate::vector_width::{CpuVectors, Job};

/// A candidate must run the kernel at least this many times as fast as the
/// default to be chosen: below it, the difference is within the noise of a
/// few frames on a shared machine (interleaved medians of the same setting
/// differ by up to 2 % on the 2-core machines of docs/bench.md).
pub const MARGIN: f64 = 1.03;

/// One setting of lavapipe's knobs that the calibration times.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Candidate {
    /// 256-bit vectors, every instruction set the CPU has: lavapipe's own
    /// choice on a CPU with AVX, and the default the others must beat.
    #[serde(rename = "256")]
    Wide256,
    /// 512-bit vectors (AVX-512F only: elsewhere they are emulated).
    #[serde(rename = "512")]
    Wide512,
    /// 256-bit vectors in AVX2 code: `GALLIUM_OVERRIDE_CPU_CAPS=avx`.
    #[serde(rename = "256-avx2")]
    Avx2At256,
}

/// The value of `GALLIUM_OVERRIDE_CPU_CAPS` that caps Mesa's code below
/// AVX-512. Mesa 25's `src/util/u_cpu_detect.c` (`check_cpu_caps_override`)
/// accepts exactly `nosse`, `sse`, `sse2`, `sse3`, `ssse3`, `sse4.1` and
/// `avx`, each clearing the next set up; `avx` clears AVX-512F (and so every
/// AVX-512 extension) and keeps AVX2 and FMA. Any other value, `avx2`
/// included, is silently ignored.
pub const AVX2_CAPS: &str = "avx";

/// The environment variable of Mesa's cap on the instruction sets.
pub const CAPS_VARIABLE: &str = "GALLIUM_OVERRIDE_CPU_CAPS";

impl Candidate {
    /// Every candidate, the default first.
    pub const ALL: [Candidate; 3] = [Candidate::Wide256, Candidate::Wide512, Candidate::Avx2At256];

    /// Its name on the command line and in the cache file.
    pub fn name(self) -> &'static str {
        match self {
            Candidate::Wide256 => "256",
            Candidate::Wide512 => "512",
            Candidate::Avx2At256 => "256-avx2",
        }
    }

    /// The candidate of this name.
    pub fn from_name(name: &str) -> Option<Candidate> {
        Candidate::ALL.into_iter().find(|c| c.name() == name)
    }

    /// `LP_NATIVE_VECTOR_WIDTH`.
    pub fn bits(self) -> u32 {
        match self {
            Candidate::Wide512 => 512,
            Candidate::Wide256 | Candidate::Avx2At256 => 256,
        }
    }

    /// `GALLIUM_OVERRIDE_CPU_CAPS`, where the candidate sets it.
    pub fn caps(self) -> Option<&'static str> {
        match self {
            Candidate::Avx2At256 => Some(AVX2_CAPS),
            Candidate::Wide256 | Candidate::Wide512 => None,
        }
    }

    /// The summary line's words for it, e.g. `256 bits, AVX2 code`.
    pub fn describe(self) -> &'static str {
        match self {
            Candidate::Wide256 => "256 bits",
            Candidate::Wide512 => "512 bits",
            Candidate::Avx2At256 => "256 bits, AVX2 code",
        }
    }
}

/// The default: what penumbra runs with when nothing was measured.
pub const DEFAULT: Candidate = Candidate::Wide256;

/// The candidates worth timing on a CPU: all of them with AVX-512, none
/// otherwise (without AVX-512, 512-bit vectors are emulated with two AVX2
/// registers and AVX2 code is the only code: the default is all there is).
pub fn candidates(cpu: CpuVectors) -> Vec<Candidate> {
    if cpu.avx && cpu.avx512f {
        Candidate::ALL.to_vec()
    } else {
        Vec::new()
    }
}

/// One candidate's measured frame times.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Measured {
    /// The setting.
    pub candidate: Candidate,
    /// Median frame time, milliseconds.
    pub median_ms: f64,
    /// Fastest frame.
    pub min_ms: f64,
    /// Slowest frame.
    pub max_ms: f64,
    /// How many frames.
    pub frames: usize,
}

impl Measured {
    /// The median and range of `frames_ms` (`None` when empty or not finite).
    pub fn of(candidate: Candidate, frames_ms: &[f64]) -> Option<Measured> {
        if frames_ms.is_empty() || frames_ms.iter().any(|t| !t.is_finite() || *t <= 0.0) {
            return None;
        }
        let mut v = frames_ms.to_vec();
        v.sort_by(f64::total_cmp);
        let n = v.len();
        let median = if n % 2 == 1 {
            v[n / 2]
        } else {
            (v[n / 2 - 1] + v[n / 2]) / 2.0
        };
        Some(Measured {
            candidate,
            median_ms: median,
            min_ms: v[0],
            max_ms: v[n - 1],
            frames: n,
        })
    }
}

/// What [`decide`] chose and how much faster it is than the default.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Decision {
    /// The setting to run with.
    pub candidate: Candidate,
    /// The default's median frame time over the chosen one's (1 when the
    /// default is kept).
    pub speedup: f64,
}

/// Chooses from measured times for `job`: the fastest candidate whose median
/// frame beats the default's by at least [`MARGIN`], else the default.
/// 512-bit vectors are eligible for a long render only ([`Job::is_long`]):
/// lavapipe's compile of the kernel takes about twice as long at 512 bits
/// (docs/drivers.md), which a short render or a `watch` edit pays on every
/// cold compile. `None` when the default was not measured.
pub fn decide(measured: &[Measured], job: Job) -> Option<Decision> {
    let default = measured.iter().find(|m| m.candidate == DEFAULT)?;
    let best = measured
        .iter()
        .filter(|m| m.candidate != Candidate::Wide512 || job.is_long())
        .min_by(|a, b| a.median_ms.total_cmp(&b.median_ms))?;
    let speedup = default.median_ms / best.median_ms;
    Some(if best.candidate != DEFAULT && speedup >= MARGIN {
        Decision {
            candidate: best.candidate,
            speedup,
        }
    } else {
        Decision {
            candidate: DEFAULT,
            speedup: 1.0,
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn m(candidate: Candidate, median_ms: f64) -> Measured {
        Measured {
            candidate,
            median_ms,
            min_ms: median_ms,
            max_ms: median_ms,
            frames: 5,
        }
    }

    const LONG: Job = Job::Render {
        pixels: None,
        passes: 1000,
        time_budget: None,
    };
    const SHORT: Job = Job::Render {
        pixels: None,
        passes: 1,
        time_budget: None,
    };

    use Candidate::*;

    #[test]
    fn a_faster_512_is_chosen_for_a_long_render() {
        let d = decide(
            &[m(Wide256, 100.0), m(Wide512, 80.0), m(Avx2At256, 101.0)],
            LONG,
        )
        .unwrap();
        assert_eq!(d.candidate, Wide512);
        assert!((d.speedup - 100.0 / 80.0).abs() < 1e-12);
    }

    #[test]
    fn a_slower_512_keeps_256() {
        let d = decide(
            &[m(Wide256, 100.0), m(Wide512, 110.0), m(Avx2At256, 120.0)],
            LONG,
        )
        .unwrap();
        assert_eq!((d.candidate, d.speedup), (Wide256, 1.0));
    }

    #[test]
    fn within_the_margin_the_default_is_kept() {
        // 2.9 % faster is noise; 3.1 % is not.
        let d = decide(&[m(Wide256, 100.0), m(Wide512, 100.0 / 1.029)], LONG).unwrap();
        assert_eq!(d.candidate, Wide256);
        let d = decide(&[m(Wide256, 100.0), m(Wide512, 100.0 / 1.031)], LONG).unwrap();
        assert_eq!(d.candidate, Wide512);
    }

    #[test]
    fn faster_avx2_code_gives_the_cap() {
        let d = decide(
            &[m(Wide256, 100.0), m(Wide512, 99.0), m(Avx2At256, 85.0)],
            LONG,
        )
        .unwrap();
        assert_eq!(d.candidate, Avx2At256);
        assert_eq!(d.candidate.caps(), Some("avx"));
        assert_eq!(d.candidate.bits(), 256);
    }

    #[test]
    fn short_renders_and_watch_never_get_512() {
        let times = [m(Wide256, 100.0), m(Wide512, 70.0), m(Avx2At256, 90.0)];
        for job in [SHORT, Job::Watch] {
            assert_eq!(decide(&times, job).unwrap().candidate, Avx2At256, "{job:?}");
        }
        let times = [m(Wide256, 100.0), m(Wide512, 70.0)];
        assert_eq!(decide(&times, Job::Watch).unwrap().candidate, Wide256);
        assert_eq!(decide(&times, LONG).unwrap().candidate, Wide512);
    }

    #[test]
    fn without_the_default_nothing_is_decided() {
        assert_eq!(decide(&[m(Wide512, 70.0)], LONG), None);
        assert_eq!(decide(&[], LONG), None);
    }

    #[test]
    fn only_avx512_cpus_have_candidates() {
        let zen3 = CpuVectors {
            avx: true,
            avx512f: false,
        };
        let zen4 = CpuVectors {
            avx: true,
            avx512f: true,
        };
        assert!(candidates(zen3).is_empty());
        assert!(candidates(CpuVectors::default()).is_empty());
        assert_eq!(candidates(zen4), vec![Wide256, Wide512, Avx2At256]);
    }

    #[test]
    fn measured_is_median_and_range() {
        let s = Measured::of(Wide256, &[5.0, 1.0, 3.0, 2.0]).unwrap();
        assert_eq!(
            (s.median_ms, s.min_ms, s.max_ms, s.frames),
            (2.5, 1.0, 5.0, 4)
        );
        assert_eq!(
            Measured::of(Wide256, &[3.0, 9.0, 1.0]).unwrap().median_ms,
            3.0
        );
        assert_eq!(Measured::of(Wide256, &[]), None);
        assert_eq!(Measured::of(Wide256, &[1.0, f64::NAN]), None);
    }

    #[test]
    fn names_round_trip() {
        for c in Candidate::ALL {
            assert_eq!(Candidate::from_name(c.name()), Some(c));
        }
        assert_eq!(Candidate::from_name("avx2"), None);
    }
}
