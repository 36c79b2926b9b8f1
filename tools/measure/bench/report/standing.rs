//! Section 8 of the report: where penumbra stands on this machine, each
//! target's verdict from this run next to the AVX-512 machine's figures.

use std::fmt::Write as _;

use super::fmt::{int, ratio};
use super::verdict::*;
use crate::parts::peers::label;
use crate::schema::Results;

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

/// The AVX-512 machine's figures.
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

/// Where [`ZEN4`]'s figures come from, as the report says it.
pub const ZEN4_SOURCE: &str = "the AVX-512 machine (AMD EPYC, Zen 4, 2 cores; docs/bench.md at commit 0e1b0cd, the peers as given in issue 19 — not this machine)";

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
pub fn section(o: &mut String, r: &Results) {
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
                    format!("the aim: {}", met(no_slower(m.ratio.median)))
                } else {
                    "—".to_string()
                },
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
        met(no_slower(cpu.ratio.median)),
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
            met(build_met(m.build_ms(), m.render_ms.median)),
            load_caution(r, "scaling"),
            ZEN4.build_ratio
        );
    }
    let _ = writeln!(
        o,
        "| Mrays/s, bunny | {:.1} | ≥ 10: {}{} | {:.1} |",
        bunny.mrays_median,
        met(mrays_met(bunny.mrays_median)),
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
            k.map_or("—", |k| speed_vs_default(k.speedup_vs_default.median)),
            zen4
        );
    }
    let cap = crate::parts::knobs::AVX2_CAP;
    if let Some(k) = knob(cap.0, cap.1) {
        let _ = writeln!(
            o,
            "| AVX2 code (`{}={}`): speed vs AVX-512 code (the default) | {}× | {} | — |",
            cap.0,
            cap.1,
            ratio(&k.speedup_vs_default),
            speed_vs_default(k.speedup_vs_default.median)
        );
    }
    let _ = writeln!(
        o,
        "\nThe knob is the environment variable lavapipe reads when it loads (section 5); `penumbra render --vector-width auto` (`src/vector_width.rs`) {}; this CPU {}.\n",
        auto_rule(),
        auto_width(r.cpu_info.avx512())
    );
    let _ = writeln!(o, "{}\n", machines_paragraph(r));
    isa_comparison(o, r);
}

/// On a CPU with AVX-512: the peers part's second run with AVX2 code on both
/// sides next to its first, and the verdict on being no further from
/// Mitsuba's LLVM variant with AVX2 code than with AVX-512 code.
fn isa_comparison(o: &mut String, r: &Results) {
    let Some(avx2) = &r.peers_avx2 else {
        return;
    };
    let _ = writeln!(
        o,
        "### AVX2 code against AVX-512 code, on this machine in this run\n"
    );
    if let Some(why) = avx2.why_not() {
        let _ = writeln!(o, "The peers' AVX2 run did not measure them: {why}.\n");
        return;
    }
    let cap = crate::parts::knobs::AVX2_CAP;
    let _ = writeln!(
        o,
        "The peers part (section 7) ran a second time with AVX2 code on both sides: lavapipe under `{}={}` (Mesa's cap on the instruction sets it targets; `tools/measure/jit_profile.sh` counts no EVEX-encoded instruction in the code it then generates), Dr.Jit's LLVM back end targeting this CPU with its AVX-512 features disabled and 8-wide vectors, Embree's device configured with `isa=avx2` (tools/measure/peers/peers.py, `{}={}`). Each run interleaves penumbra's frames with each peer's ({} and {} rounds); the two runs are consecutive processes.\n",
        cap.0, cap.1, crate::parts::peers::AVX2_PEERS.0, crate::parts::peers::AVX2_PEERS.1, r.peers.rounds, avx2.rounds
    );
    let _ = writeln!(
        o,
        "| Peer | AVX-512 code: penumbra vs peer, ms | penumbra / peer | AVX2 code: penumbra vs peer, ms | penumbra / peer |\n|---|---|---|---|---|"
    );
    for peer in crate::parts::peers::PEERS {
        let (Some(a), Some(b)) = (r.peers.valid(peer), avx2.valid(peer)) else {
            continue;
        };
        let _ = writeln!(
            o,
            "| {} | {:.1} vs {:.1} | {}× | {:.1} vs {:.1} | {}× |",
            label(peer),
            a.penumbra_ms.median,
            a.frame_ms.median,
            ratio(&a.ratio),
            b.penumbra_ms.median,
            b.frame_ms.median,
            ratio(&b.ratio)
        );
    }
    if let (Some(a), Some(b)) = (r.peers.valid("mitsuba-llvm"), avx2.valid("mitsuba-llvm")) {
        let _ = writeln!(
            o,
            "\nAVX2 code takes {:.2}× the time of AVX-512 code for penumbra's frame and {:.2}× for Mitsuba's (medians). **No further from Mitsuba 3 `llvm_ad_rgb` with AVX2 code than with AVX-512 code: {}** ({:.2}× against {:.2}×, medians of the pairs).\n",
            b.penumbra_ms.median / a.penumbra_ms.median,
            b.frame_ms.median / a.frame_ms.median,
            met(b.ratio.median <= a.ratio.median),
            b.ratio.median,
            a.ratio.median
        );
    }
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
            wide_vectors(c.avx512(), w)
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
            if c.avx512() {
                "both machines have AVX-512, so the difference is the kernel's (the AVX-512 column measured the megakernel of 0e1b0cd, this run the staged renderer) and the machine's own speed (Mitsuba's time above), not the instruction sets'; those are compared on this machine in the next subsection."
            } else {
                gap(m.ratio.median, ZEN4.bunny_ms / ZEN4.mitsuba_llvm_ms)
            }
        );
    }
    s
}
