//! The report's verdicts, each decided from the figures in one place: the
//! targets and their thresholds, how a lavapipe setting compares with the
//! default, what the CPU's vector width means for lavapipe. The sections
//! phrase their sentences around these words.

/// The throughput target: primary + shadow rays per second, in millions.
pub const MRAYS_TARGET: f64 = 10.0;

/// The BVH build target: "well under" one frame means below this fraction.
pub const BUILD_FRACTION: f64 = 0.5;

/// Speed-ups within this distance of 1 count as "as fast as the default".
pub const SAME_SPEED: f64 = 0.02;

/// Two machines' ratios to a peer that differ by more than this show a
/// machine-dependent gap.
pub const GAP_TOLERANCE: f64 = 0.2;

/// "met" or "not met".
pub fn met(ok: bool) -> &'static str {
    if ok {
        "met"
    } else {
        "not met"
    }
}

/// Whether the bunny's throughput reaches [`MRAYS_TARGET`].
pub fn mrays_met(mrays: f64) -> bool {
    mrays >= MRAYS_TARGET
}

/// Whether a time ratio penumbra / other (the CPU port, Mitsuba) is at most
/// 1: penumbra no slower.
pub fn no_slower(ratio: f64) -> bool {
    ratio <= 1.0
}

/// Whether a BVH build of `build_ms` is well under a frame of `frame_ms`.
pub fn build_met(build_ms: f64, frame_ms: f64) -> bool {
    build_ms < BUILD_FRACTION * frame_ms
}

/// The scaling section's clause on the build target.
pub fn build_clause(ok: bool) -> &'static str {
    if ok {
        "well under the render time (below half): the issue's build target is met"
    } else {
        "not well under the render time (half or more): the issue's build target is not met on this machine"
    }
}

/// How a setting's speed-up over the default reads.
pub fn speed_vs_default(speedup: f64) -> &'static str {
    if speedup > 1.0 + SAME_SPEED {
        "faster than the default"
    } else if speedup < 1.0 - SAME_SPEED {
        "slower than the default"
    } else {
        "as fast as the default"
    }
}

/// Why 512-bit vectors run as they do, given whether the CPU has AVX-512
/// and their speed-up over the default 256 bits.
pub fn wide_vectors(avx512: bool, speedup: f64) -> &'static str {
    let faster = speedup > 1.0 + SAME_SPEED;
    let slower = speedup < 1.0 - SAME_SPEED;
    match (avx512, faster, slower) {
        (true, true, _) => "with AVX-512, LLVM emits 16-lane instructions, and the wider SIMD groups pay for their extra divergence.",
        (true, false, _) => "even with AVX-512 the wider SIMD groups do not pay for their extra divergence here.",
        (false, _, true) => "without AVX-512, LLVM splits every 16-lane operation into two 256-bit halves, so the wider groups add divergence and register pressure without wider arithmetic; the default (256) is the right width here.",
        (false, _, false) => "without AVX-512, LLVM splits every 16-lane operation into two 256-bit halves, yet the wider groups are not slower here.",
    }
}

/// What `--vector-width auto` does: the calibration's choice (src/calibration).
pub fn auto_rule() -> &'static str {
    "takes the setting that `penumbra calibrate` measured fastest on the machine, the first long render calibrating after itself (512 bits for long renders only, AVX2 or AVX-512 code at 256 bits; docs/drivers.md, \"Calibration\", gives each candidate's speed on a machine), and 256 bits where nothing was measured"
}

/// Whether this CPU has what auto would use 512 bits on.
pub fn auto_width(avx512: bool) -> &'static str {
    if avx512 {
        "has AVX-512"
    } else {
        "has none, so auto keeps 256 here"
    }
}

/// Whether penumbra's ratio to a peer depends on the machine.
pub fn gap(here: f64, there: f64) -> &'static str {
    if (here - there).abs() > GAP_TOLERANCE {
        "the gap depends on the machine, which is why the ratio has to come from the same run."
    } else {
        "about the same gap on both machines."
    }
}

/// Whether a nice value made other processes disturb the benchmark less or
/// more than their CPU time suggests.
pub fn nice_effect(nice: i64) -> &'static str {
    if nice < 0 {
        "less"
    } else {
        "more"
    }
}
