//! How the report writes numbers: `median [min–max]` of times and ratios,
//! integers with thousands separators, sizes in MiB, lists of compile times,
//! and the table of an interleaved pair.

use std::fmt::Write as _;

use crate::schema::{Pair, Stat, Throughput};

/// One decimal.
pub fn f1(x: f64) -> String {
    format!("{x:.1}")
}

/// `median [min–max]` in ms.
pub fn st(s: &Stat) -> String {
    format!("{:.1} [{:.1}–{:.1}]", s.median, s.min, s.max)
}

/// A ratio's `median [min–max]`.
pub fn ratio(s: &Stat) -> String {
    format!("{:.2} [{:.2}–{:.2}]", s.median, s.min, s.max)
}

/// `n` with thousands separators (`858,452`).
pub fn int(n: u64) -> String {
    let s = n.to_string();
    let mut out = String::new();
    for (i, c) in s.chars().enumerate() {
        if i > 0 && (s.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}

/// Bytes in MiB, two decimals.
pub fn mib(bytes: usize) -> String {
    format!("{:.2} MiB", bytes as f64 / 1048576.0)
}

/// The table of an interleaved pair: both variants and their ratio.
pub fn pair_table(out: &mut String, p: &Pair) {
    let _ = writeln!(
        out,
        "| {} at {}×{} | ms/frame, median [min–max] |\n|---|---|\n| {} | {} |\n| {} | {} |\n| ratio {}/{} (per interleaved pair) | **{}** |\n",
        p.what,
        p.width,
        p.height,
        p.a,
        st(&p.a_ms),
        p.b,
        st(&p.b_ms),
        p.a,
        p.b,
        ratio(&p.ratio)
    );
}

/// Mrays/s at the median [slowest–fastest frame].
pub fn mrays(t: &Throughput) -> String {
    format!(
        "{:.1} [{:.1}–{:.1}]",
        t.mrays_median, t.mrays_min, t.mrays_max
    )
}

/// Values without decimals, comma-separated.
pub fn list0(v: &[f64]) -> String {
    v.iter()
        .map(|x| format!("{x:.0}"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The smallest value (infinity when empty).
pub fn min(v: &[f64]) -> f64 {
    v.iter().copied().fold(f64::INFINITY, f64::min)
}

/// Values with one decimal, comma-separated.
pub fn list(v: &[f64]) -> String {
    v.iter()
        .map(|x| format!("{x:.1}"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// B/A of a ratio A/B.
pub fn inv_ratio(s: &Stat) -> String {
    format!(
        "{:.2} [{:.2}–{:.2}]",
        1.0 / s.median,
        1.0 / s.max,
        1.0 / s.min
    )
}
