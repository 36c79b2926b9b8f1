//! Section 6 of the report: the targets, where the time goes and what
//! stands in the way.

use std::fmt::Write as _;

use super::fmt::*;
use super::verdict::*;
use super::{analysis, peers};
use crate::schema::*;

/// Section 6: the peers, the CPU port and penumbra in one table, then
/// each target's verdict.
pub fn section(o: &mut String, r: &Results) {
    let bunny = &r.throughput.scenes[0];
    let cpu = &r.cpu;
    let _ = writeln!(o, "## 6. Targets\n");
    let _ = writeln!(
        o,
        "The peers, measured in this run (section 7: the same scene and thread count, frames interleaved with penumbra's; penumbra / it is the median of the per-pair ratios, with their range), against penumbra's render phase on lavapipe from section 1, and against a plain multi-threaded Rust CPU implementation of penumbra's own algorithm measured in this run (`tools/measure/bench/cpu.rs`: the same camera-relative `f32` data and the same BVH tree — over its exact `f32` node boxes, not the kernel's quantised records, and with shadow rays taking the left child first, not the nearer: the kernel's choices would make the port 1.5× and 1.2× slower (module doc of `tools/measure/bench/cpu.rs`), and the target is the port at its best — the same primary rays, nearest-first closest-hit traversal with the same slab test, u,v-first Möller–Trumbore (and the GPU kernel set to `--triangle-test uv-first` for this comparison), Phong shading, the same shadow rays with the same self-skip and Wächter–Binder offset; rows in parallel with rayon on {} threads).\n",
        cpu.threads
    );
    let rays = (bunny.primary_rays + bunny.shadow_rays) as f64;
    let _ = writeln!(
        o,
        "| Renderer | ms/frame | Mrays/s (effective) | penumbra / it |\n|---|---|---|---|"
    );
    peers::target_rows(o, r, rays);
    let _ = writeln!(
        o,
        "| Rust CPU port, rayon, this run | {} | {:.1} | {:.2}× |",
        st(&cpu.cpu_ms),
        rays / cpu.cpu_ms.median / 1e3,
        cpu.gpu_ms.median / cpu.cpu_ms.median
    );
    let _ = writeln!(
        o,
        "| **penumbra on lavapipe** (section 1) | **{}** | **{:.1}** | 1 |\n",
        st(&bunny.render_ms),
        bunny.mrays_median
    );
    let _ = writeln!(
        o,
        "Mrays/s (effective) for the peers = this scene's {} primary + shadow rays / their frame time.\n",
        int(rays as u64)
    );
    let _ = writeln!(
        o,
        "- **≥ 10 Mrays/s**: {} ({:.1} Mrays/s).",
        met(mrays_met(bunny.mrays_median)),
        bunny.mrays_median
    );
    let _ = writeln!(
        o,
        "- **No slower than the Rust CPU port in the same run**: GPU/CPU time ratio {} over {} interleaved pairs (GPU {} ms, CPU {} ms) — {}. The two agree: {} vs {} hits (the scene's 858,452), {} vs {} shadow rays, largest absolute difference of any pixel channel {:.2e} ({} pixels differ by more than 10⁻³).",
        ratio(&cpu.ratio),
        cpu.ratio.samples.len(),
        st(&cpu.gpu_ms),
        st(&cpu.cpu_ms),
        met(no_slower(cpu.ratio.median)),
        int(cpu.gpu_hits as u64),
        int(cpu.cpu_hits as u64),
        int(cpu.gpu_shadow_rays),
        int(cpu.cpu_shadow_rays),
        cpu.max_abs_diff,
        cpu.pixels_over_1e3
    );
    peers::target_bullet(o, r);
}

/// "Where the time goes": the `perf` profile by shared object and symbol.
pub fn profile(o: &mut String, r: &Results) {
    let bunny = &r.throughput.scenes[0];
    let _ = writeln!(o, "### Where the time goes\n");
    let p = &r.profile;
    match &p.skipped {
        Some(why) => {
            let _ = writeln!(o, "No profile: {why}.\n");
        }
        None => {
            let _ = writeln!(
                o,
                "`perf record -e cpu-clock` (software clock sampling; this virtual machine has no hardware counters) of one default bunny process — cold compile plus {} frames — about {} samples:\n",
                bunny.render_ms.samples.len().min(5) + 2,
                int(p.samples)
            );
            let _ = writeln!(o, "| Shared object | Samples |\n|---|---|");
            for (name, pct) in &p.dsos {
                let _ = writeln!(o, "| {name} | {pct:.1}% |");
            }
            let _ = writeln!(
                o,
                "\n| Hottest symbols outside the kernel | Samples |\n|---|---|"
            );
            for (name, pct) in &p.symbols {
                let _ = writeln!(o, "| `{}` | {pct:.1}% |", name.replace('|', "\\|"));
            }
            let _ = writeln!(o);
        }
    }
}

/// "What stands in the way": the analysis of this run's figures.
pub fn obstacles(o: &mut String, r: &Results) {
    let _ = writeln!(o, "### What stands in the way\n");
    o.push_str(&analysis::markdown(r));
    let _ = writeln!(o);
}
