//! The report's rows and section on the peers: the header's versions, the
//! headline ratios, section 6's rows and verdict on the aim, the analysis's
//! paragraph on their advantage, and section 7.

use std::fmt::Write as _;

use super::fmt::{int, ratio, st};
use super::standing::{ZEN4, ZEN4_SOURCE};
use super::verdict::{met, no_slower};
use crate::parts::peers::{label, BLOCKED_TOLERANCE};
use crate::schema::{Counts, Results};

/// Header rows: the CPU and the peers' versions.
pub fn header_rows(o: &mut String, r: &Results) {
    let _ = writeln!(o, "| CPU | {} |", r.cpu_info.describe());
    let p = &r.peers;
    let peers = match p.why_not() {
        Some(why) => format!("not measured in this run: {why}"),
        None => {
            let mut v: Vec<String> = Vec::new();
            for run in p.peers.iter().filter(|x| x.error.is_none()) {
                if !v.contains(&run.version) {
                    v.push(run.version.clone());
                }
            }
            format!(
                "{} ({} threads each, as penumbra; Python `{}`)",
                v.join("; "),
                p.threads,
                p.python
            )
        }
    };
    let _ = writeln!(o, "| Peers | {peers} |");
}

/// Headline rows: penumbra against each peer from this run.
pub fn headline_rows(o: &mut String, r: &Results) {
    let p = &r.peers;
    if let Some(why) = p.why_not() {
        let _ = writeln!(
            o,
            "| penumbra / Mitsuba 3 and Embree | **not measured in this run**: {why} |"
        );
        return;
    }
    for run in &p.peers {
        let cell = match (&run.error, run.agreement(&p.penumbra)) {
            (Some(e), _) => format!("not measured: {e}"),
            (None, Err(e)) => format!("**void**: {e}"),
            (None, Ok(())) => format!(
                "**{}×** its time ({} pairs; {:.1} vs {:.1} ms)",
                ratio(&run.ratio),
                run.ratio.samples.len(),
                run.penumbra_ms.median,
                run.frame_ms.median
            ),
        };
        let _ = writeln!(o, "| penumbra / {}, same run | {cell} |", label(&run.peer));
    }
}

/// Section 6's table rows for the peers.
pub fn target_rows(o: &mut String, r: &Results, rays: f64) {
    let p = &r.peers;
    if let Some(why) = p.why_not() {
        let _ = writeln!(
            o,
            "| Mitsuba 3, Embree 4 | not measured in this run ({why}) | | |"
        );
        return;
    }
    for run in &p.peers {
        let cells = match (&run.error, run.agreement(&p.penumbra)) {
            (Some(_), _) => "not measured (section 7) | | ".to_string(),
            (None, Err(_)) => format!(
                "{} | {:.1} | void: counts disagree (section 7)",
                st(&run.frame_ms),
                rays / run.frame_ms.median / 1e3
            ),
            (None, Ok(())) => format!(
                "{} | {:.1} | {}×",
                st(&run.frame_ms),
                rays / run.frame_ms.median / 1e3,
                ratio(&run.ratio)
            ),
        };
        let _ = writeln!(o, "| {}, this run | {cells} |", label(&run.peer));
    }
}

/// Section 6's verdict on the aim, Mitsuba's LLVM variant.
pub fn target_bullet(o: &mut String, r: &Results) {
    let p = &r.peers;
    let line = match p.valid("mitsuba-llvm") {
        Some(m) => format!(
            "{:.1} ms in this run: penumbra needs {:.1} ms in the same rounds, **{:.2}×** as long (median of {} interleaved pairs, range {:.2}–{:.2}) — {}",
            m.frame_ms.median,
            m.penumbra_ms.median,
            m.ratio.median,
            m.ratio.samples.len(),
            m.ratio.min,
            m.ratio.max,
            if no_slower(m.ratio.median) {
                met(true).to_string()
            } else {
                format!(
                    "{} ({:.1} ms to go)",
                    met(false),
                    m.penumbra_ms.median - m.frame_ms.median
                )
            }
        ),
        None => format!(
            "no verdict: not measured in this run ({}). On {ZEN4_SOURCE} it took {} ms against penumbra's {} ms there ({:.1}×)",
            p.why_not()
                .or_else(|| p
                    .peers
                    .iter()
                    .find(|x| x.peer == "mitsuba-llvm")
                    .and_then(|x| x.error.clone().or_else(|| x.agreement(&p.penumbra).err())))
                .unwrap_or_default(),
            ZEN4.mitsuba_llvm_ms,
            ZEN4.bunny_ms,
            ZEN4.bunny_ms / ZEN4.mitsuba_llvm_ms
        ),
    };
    let _ = writeln!(o, "- **Mitsuba's LLVM back end (the aim)**: {line}.\n");
}

/// The analysis's paragraph on the peers' advantage, with this run's figures.
pub fn advantage(r: &Results) -> String {
    let p = &r.peers;
    let t = |peer: &str| p.valid(peer).map(|x| x.frame_ms.median);
    let figures = match (
        t("embree-packets"),
        t("mitsuba-llvm"),
        t("embree-single"),
    ) {
        (Some(a), Some(b), Some(c)) => format!(
            "Embree's 16-ray packets ({a:.1} ms in this run, ray queries only) and Mitsuba's LLVM variant ({b:.1} ms, a whole frame) trace coherent bundles with hand-tuned SIMD box tests and keep one traversal stack per packet, not per lane; Embree's single-ray mode ({c:.1} ms) is still a well-tuned scalar kernel with a wide BVH. penumbra is {:.1}× Mitsuba's LLVM time in the same rounds",
            p.valid("mitsuba-llvm").map_or(f64::NAN, |m| m.ratio.median)
        ),
        _ => format!(
            "Embree's packets and Mitsuba's LLVM variant trace coherent bundles with hand-tuned SIMD box tests and keep one traversal stack per packet, not per lane (not measured in this run; on {ZEN4_SOURCE}: {} ms and {} ms against penumbra's {} ms)",
            ZEN4.embree_packets_ms, ZEN4.mitsuba_llvm_ms, ZEN4.bunny_ms
        ),
    };
    format!("4. **The peers' advantage.** {figures}.")
}

/// Section 7: the peers, how they were run, their counts and frames.
pub fn section(o: &mut String, r: &Results) {
    let p = &r.peers;
    let _ = writeln!(o, "## 7. Peers, measured in this run\n");
    if let Some(why) = p.why_not() {
        let _ = writeln!(
            o,
            "**The peers were not measured in this run**: {why}. No peer figure in this report comes from this machine; where one from another machine appears, it says so.\n"
        );
        return;
    }
    let _ = writeln!(
        o,
        "Each peer is a `tools/measure/peers/peers.py serve PEER` process (`{}`, packages pinned in `tools/measure/peers/requirements.txt`, installed by `tools/setup.sh --bench`) that builds its scene from `scenes/bunny_scene.glb` itself: the meshes in world space, the camera node (eye, orientation, vertical field of view), the directional light, {}×{}, {} threads (penumbra's lavapipe runs as many). Mitsuba renders whole frames with its `direct` integrator (one emitter sample, no BSDF sample; a non-jittered stratified sampler puts the one sample per pixel at its centre; a box filter; a two-sided diffuse BSDF): camera rays, shading, one shadow ray per hit and the film, as penumbra's render phase does. Embree runs `tools/measure/peers/embree_frame.c` against the libembree4 that embreex ships: primary rays through the pixel centres with penumbra's camera model, then a shadow ray for each hit whose normal faces the light; ray queries and the ray set-up only, no shading. Each peer's scene set-up, first frame and a warm-up frame come before the measured frames. The frames are interleaved: in each of {} rounds, for every peer (a different one first each round), one penumbra frame (render phase, `RenderStats`) and then one of the peer's; each ratio below is the median over those pairs of penumbra's frame / the peer's frame, with the range over pairs.\n",
        p.python,
        p.width,
        p.height,
        p.threads,
        p.rounds
    );
    if let Some(part) = r.parts.iter().find(|x| x.part == "peers") {
        let _ = writeln!(
            o,
            "This part took {:.0} s while other processes used {:.2} cores on average (the last table); interleaving keeps that from deciding a ratio, not from slowing both sides.\n",
            part.wall_s, part.other_cores
        );
    }
    let _ = writeln!(
        o,
        "**Same scene?** A peer's comparison is void unless its primary hit count equals penumbra's and its blocked shadow rays are within {:.0}% of penumbra's. Shadow-ray totals differ by definition: Mitsuba's direct integrator samples the light at every hit, penumbra and the Embree peers only where the normal faces the light.\n",
        BLOCKED_TOLERANCE * 100.0
    );
    let _ = writeln!(
        o,
        "| Renderer | Version | How | Primary hits | Shadow rays | Blocked | Same scene? |\n|---|---|---|---|---|---|---|"
    );
    let pc = &p.penumbra;
    let blocked = |c: &Counts| c.blocked.map_or("—".into(), int);
    let _ = writeln!(
        o,
        "| penumbra | this commit | lavapipe, render phase | {} | {} | {} | — |",
        int(pc.hits),
        int(pc.shadow_rays),
        blocked(pc)
    );
    for run in &p.peers {
        match &run.error {
            Some(e) => {
                let _ = writeln!(
                    o,
                    "| {} | — | — | — | — | — | did not run: {} |",
                    label(&run.peer),
                    e.replace('|', "\\|").replace('\n', " ")
                );
            }
            None => {
                let _ = writeln!(
                    o,
                    "| {} | {} | {} | {} | {} | {} | {} |",
                    label(&run.peer),
                    run.version,
                    run.notes,
                    int(run.counts.hits),
                    int(run.counts.shadow_rays),
                    blocked(&run.counts),
                    match run.agreement(pc) {
                        Ok(()) => "yes".to_string(),
                        Err(e) => format!("**no: void** ({e})"),
                    }
                );
            }
        }
    }
    let _ = writeln!(
        o,
        "\n| Peer | Scene set-up | First frame | Peer ms/frame, median [min–max] | penumbra ms/frame in the same pairs | penumbra / peer, median [min–max] of pairs |\n|---|---|---|---|---|---|"
    );
    for run in p.peers.iter().filter(|x| x.error.is_none()) {
        let _ = writeln!(
            o,
            "| {} | {:.0} ms | {:.0} ms | {} | {} | {} |",
            label(&run.peer),
            run.setup_ms,
            run.first_frame_ms,
            st(&run.frame_ms),
            st(&run.penumbra_ms),
            match run.agreement(pc) {
                Ok(()) => format!("**{}**", ratio(&run.ratio)),
                Err(_) => format!("void ({})", ratio(&run.ratio)),
            }
        );
    }
    let _ = writeln!(
        o,
        "\nRegenerate the peers' figures alone (no penumbra frames): `target/bench-venv/bin/python tools/measure/peers/peers.py run` prints one JSON line per peer and frame.\n"
    );
}
