//! Section 5's runs: lavapipe's environment knobs (thread count, vector
//! width), each setting in its own child process because Mesa reads them
//! when the driver loads.

use common::Stat;

use crate::child::child;
use crate::schema::{Knob, PartInfo, ThroughputPart};
use crate::Args;

/// The AVX2 knob: Mesa's cap on the instruction sets lavapipe targets, below
/// AVX-512 (tools/measure/jit_profile.sh shows that the code it then generates has
/// no EVEX-encoded instruction). Run only on a CPU with AVX-512, where it
/// gives AVX2 code on the same machine as the default's AVX-512 code.
pub const AVX2_CAP: (&str, &str) = ("GALLIUM_OVERRIDE_CPU_CAPS", "avx");

/// lavapipe's knobs: every setting in its own child process, in `rounds`
/// rounds that each run every setting once (interleaved, so a period of
/// contention hits all settings alike).
pub fn run(args: &Args, parts: &mut Vec<PartInfo>, rounds: usize) -> Vec<Knob> {
    let mut settings: Vec<&[(&str, &str)]> = vec![
        &[],
        &[("LP_NUM_THREADS", "1")],
        &[("LP_NUM_THREADS", "2")],
        &[("LP_NUM_THREADS", "4")],
        &[("LP_NATIVE_VECTOR_WIDTH", "128")],
        &[("LP_NATIVE_VECTOR_WIDTH", "256")],
        &[("LP_NATIVE_VECTOR_WIDTH", "512")],
    ];
    if common::machine::CpuInfo::read().avx512_in_use() {
        settings.push(&[AVX2_CAP]);
    }
    // runs[setting][round] = (device name, driver compile, frame times)
    type Run = (String, f64, Vec<f64>);
    let mut runs: Vec<Vec<Run>> = vec![Vec::new(); settings.len()];
    for _ in 0..rounds {
        for (i, env) in settings.iter().enumerate() {
            match child::<ThroughputPart>(args, parts, "knob", env) {
                Ok(p) => runs[i].push((
                    p.device.name.clone(),
                    p.scenes[0].driver_compile_ms,
                    p.scenes[0].render_ms.samples.clone(),
                )),
                Err(e) => eprintln!("bench: knob {env:?} failed: {e:#}"),
            }
        }
    }
    let medians: Vec<Vec<f64>> = runs
        .iter()
        .map(|r| r.iter().map(|x| Stat::of(&x.2).median).collect())
        .collect();
    settings
        .iter()
        .zip(&runs)
        .enumerate()
        .filter(|(_, (_, r))| !r.is_empty())
        .map(|(i, (env, r))| {
            let speedups: Vec<f64> = medians[0]
                .iter()
                .zip(&medians[i])
                .map(|(d, k)| d / k)
                .collect();
            Knob {
                env: env
                    .iter()
                    .map(|(k, v)| (k.to_string(), v.to_string()))
                    .collect(),
                device_name: r[0].0.clone(),
                driver_compile_ms: r.iter().map(|x| x.1).collect(),
                render_ms: Stat::of(&r.iter().flat_map(|x| x.2.clone()).collect::<Vec<_>>()),
                speedup_vs_default: Stat::of(&speedups),
            }
        })
        .collect()
}
