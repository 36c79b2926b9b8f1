//! Section 2 of the report: the seminar's claim, u,v-first against t-first.

use std::fmt::Write as _;

use super::fmt::*;
use crate::schema::*;

/// Section 2: the triangle-test comparisons as tables of interleaved pairs.
pub fn section(o: &mut String, r: &Results) {
    let sem = &r.seminar;
    let _ = writeln!(o, "## 2. The seminar's claim: u,v-first vs t-first\n");
    let _ = writeln!(
        o,
        "The same scene and kernel, only the order of the ray/triangle test changed (`--triangle-test`). Variants are interleaved A B A B … in one process after a warm-up frame of each, and compared as the median of per-pair ratios (robust to the machine's second core coming and going). The seminar measured 0.68 s against 1 s (ratio 0.68). Brute force tests every triangle for every ray — tens of seconds per 1024² frame on lavapipe — so it runs at {}×{}; each comparison keeps both variants at the same resolution. Brute-force pairs: {}; BVH pairs: {}.\n",
        sem.uv_vs_t_brute.width,
        sem.uv_vs_t_brute.height,
        sem.uv_vs_t_brute.ratio.samples.len(),
        sem.uv_vs_t_bvh.ratio.samples.len()
    );
    pair_table(o, &sem.uv_vs_t_brute);
    pair_table(o, &sem.uv_vs_t_bvh);
    pair_table(o, &sem.bvh_vs_brute);
    let _ = writeln!(
        o,
        "The renderer's default test is now the watertight one (Woop, Benthin and Wald 2013; no ray slips between triangles sharing an edge); against the seminar's u,v-first Möller–Trumbore on the same BVH:\n"
    );
    pair_table(o, &sem.watertight_vs_uv_bvh);
}
