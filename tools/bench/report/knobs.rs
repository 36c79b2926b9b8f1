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
}
