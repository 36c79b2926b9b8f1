//! Section 5 of the report: lavapipe's knobs.

use std::fmt::Write as _;

use super::fmt::*;
use crate::schema::*;

/// Section 5: one row per lavapipe setting.
pub fn section(o: &mut String, r: &Results) {
    let bunny = &r.throughput.scenes[0];
    let _ = writeln!(o, "## 5. Lavapipe's knobs\n");
    let _ = writeln!(
        o,
        "Mesa reads these when the driver loads, so every setting runs in its own process (this program re-invoked: the bunny at 1024×1024, a warm-up frame, then {} frames). The settings are interleaved: {} rounds, each running every setting once, so a period when another process takes a core hits all settings alike; the speed-up is the median over rounds of (default's median / setting's median) within the round.\n",
        bunny.render_ms.samples.len().min(5),
        r.knob_rounds
    );
    let _ = writeln!(
        o,
        "| Environment | Device name | Driver compile (cold), per round | Render ms/frame, median [min–max] of all frames | Speed-up vs default, median [min–max] over rounds |\n|---|---|---|---|---|"
    );
    for k in &r.knobs {
        let env = if k.env.is_empty() {
            "(default)".to_string()
        } else {
            k.env
                .iter()
                .map(|(n, v)| format!("`{n}={v}`"))
                .collect::<Vec<_>>()
                .join(" ")
        };
        let _ = writeln!(
            o,
            "| {} | {} | {} ms | {} | {} |",
            env,
            k.device_name,
            list0(&k.driver_compile_ms),
            st(&k.render_ms),
            ratio(&k.speedup_vs_default)
        );
    }
    let _ = writeln!(o);
    calibration_paragraph(o, r);
}

/// What `penumbra calibrate` would choose from this run's knob times
/// (`penumbra::calibration::decide`, the rule the CLI applies to its own
/// probe's times), so the report states the choice beside the candidates'
/// speeds it comes from.
fn calibration_paragraph(o: &mut String, r: &Results) {
    use penumbra::calibration::{candidates, decide, Candidate, Measured, MARGIN};
    use penumbra::vector_width::{CpuVectors, Job};
    let cpu = CpuVectors {
        avx: r.cpu_info.isa.iter().any(|f| f == "avx"),
        avx512f: r.cpu_info.avx512_in_use(),
    };
    if candidates(cpu).is_empty() {
        let _ = writeln!(
            o,
            "**Calibration** (`penumbra calibrate`, docs/drivers.md): this CPU has no AVX-512 in use, so there is nothing to choose: 512-bit vectors would be emulated with two 256-bit registers and AVX2 code is the only code. Every render runs at lavapipe's default, 256 bits.\n"
        );
        return;
    }
    let env_of = |c: Candidate| -> Vec<(String, String)> {
        match c {
            Candidate::Wide256 => vec![("LP_NATIVE_VECTOR_WIDTH".into(), "256".into())],
            Candidate::Wide512 => vec![("LP_NATIVE_VECTOR_WIDTH".into(), "512".into())],
            Candidate::Avx2At256 => vec![(
                crate::parts::knobs::AVX2_CAP.0.into(),
                crate::parts::knobs::AVX2_CAP.1.into(),
            )],
        }
    };
    let measured: Vec<Measured> = Candidate::ALL
        .iter()
        .filter_map(|&c| {
            let k = r.knobs.iter().find(|k| k.env == env_of(c))?;
            Measured::of(c, &k.render_ms.samples)
        })
        .collect();
    let long = Job::Render {
        pixels: None,
        passes: u32::MAX,
        time_budget: None,
    };
    let name = |c: Candidate| format!("`{}` ({})", c.name(), c.describe());
    match (decide(&measured, long), decide(&measured, Job::Watch)) {
        (Some(l), Some(w)) => {
            let _ = writeln!(
                o,
                "**Calibration** (`penumbra calibrate`, docs/drivers.md), applied to the rows above (`calibration::decide`: the fastest candidate whose median frame beats 256 bits by at least {:.0} %, 512 bits for long renders only): long renders would run with **{}**, {:.2}× as fast as the default; short renders and `watch` with **{}**. `penumbra calibrate` measures its own scene in its own processes and may differ by a few per cent.\n",
                (MARGIN - 1.0) * 100.0,
                name(l.candidate),
                l.speedup,
                name(w.candidate),
            );
        }
        _ => {
            let _ = writeln!(
                o,
                "**Calibration**: no choice: the 256-bit row is missing from this run.\n"
            );
        }
    }
}

/// Issue 16's target for every lavapipe a user is likely to have, Mesa 22.3
/// included: this many Mrays/s on the bunny at 1024×1024.
pub const DRIVER_TARGET_MRAYS: f64 = 20.0;

/// The driver matrix, after the knobs: the bunny and the showcase on every
/// lavapipe at hand.
pub fn drivers_section(o: &mut String, r: &Results) {
    let Some(d) = &r.drivers else {
        return;
    };
    let _ = writeln!(o, "### Drivers\n");
    let _ = writeln!(
        o,
        "Every lavapipe at hand: the installed one and each driver tree that `tools/mesa_tree.sh` unpacked into `target/` (`tools/setup.sh --tests` unpacks Debian's main-suite one; nothing is installed into the system), each in its own child processes pointed at it by `VK_DRIVER_FILES` and `VK_ICD_FILENAMES`. {} rounds, each running every driver once (a cold compile, a warm-up frame, then the frames of the bunny and of the showcase); the speed is the median over rounds of (the installed driver's median frame / this driver's) within the round.\n",
        d.rounds
    );
    if let Some(n) = &d.note {
        let _ = writeln!(o, "{n}.\n");
    }
    let _ = writeln!(
        o,
        "| Driver | Scene | Driver compile (cold), per round | Render ms/frame, median [min–max] of all frames | Mrays/s | Speed vs the installed driver, median [min–max] over rounds |\n|---|---|---|---|---|---|"
    );
    for run in &d.drivers {
        if let Some(e) = &run.error {
            let _ = writeln!(o, "| `{}` | — | failed: {e} | | | |", run.icd);
        }
        for s in &run.scenes {
            let _ = writeln!(
                o,
                "| {} (`{}`) | {} {}×{} | {} ms | {} | {:.1} | {} |",
                run.device.driver_info,
                run.icd,
                s.scene,
                s.width,
                s.height,
                list0(&s.driver_compile_ms),
                st(&s.render_ms),
                s.mrays(),
                ratio(&s.speed_vs_installed)
            );
        }
    }
    let _ = writeln!(o);
    for run in &d.drivers {
        if let Some(s) = run.scenes.iter().find(|s| s.scene == "bunny_scene.glb") {
            let mrays = s.mrays();
            let _ = writeln!(
                o,
                "- {}: {mrays:.1} Mrays/s on the bunny, ≥ {DRIVER_TARGET_MRAYS:.0} Mrays/s: {}.",
                run.device.driver_info,
                super::verdict::met(mrays >= DRIVER_TARGET_MRAYS)
            );
        }
    }
    let _ = writeln!(o);
}
