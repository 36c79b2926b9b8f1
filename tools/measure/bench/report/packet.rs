//! Section 4b of the report: the packet traversal against the per-lane one.

use std::fmt::Write as _;

use super::fmt::*;
use crate::schema::*;

/// The packet variant's ratio; nothing for results measured before the
/// benchmark had the part.
pub fn section(o: &mut String, r: &Results) {
    let Some(p) = &r.packet else {
        return;
    };
    let _ = writeln!(o, "## 4b. Packet traversal\n");
    let _ = writeln!(
        o,
        "The lanes of a subgroup walking the BVH together, a node at a time, its record loaded once for the subgroup from a storage buffer at a subgroup-uniform index (`KernelOptions {{ traversal: Traversal::Packet }}`, off by default), against the default per-lane walk, for the primary and the shadow rays; {} interleaved pairs in this run (docs/stages.md has the history).\n",
        p.bunny.ratio.samples.len()
    );
    pair_table(o, &p.bunny);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_section_gives_the_packet_ratio_and_is_absent_without_the_part() {
        let mut r = Results::default();
        let mut o = String::new();
        section(&mut o, &r);
        assert_eq!(o, "");
        let stat = |m: f64| Stat::of(&[m, m * 0.9, m * 1.1]);
        r.packet = Some(PacketPart {
            bunny: Pair {
                what: "bunny".into(),
                a: "packet".into(),
                b: "per-lane".into(),
                width: 1024,
                height: 1024,
                a_ms: stat(120.0),
                b_ms: stat(100.0),
                ratio: stat(1.2),
            },
        });
        section(&mut o, &r);
        assert!(o.contains("## 4b. Packet traversal"), "{o}");
        assert!(o.contains("3 interleaved pairs"), "{o}");
        assert!(
            o.contains("| ratio packet/per-lane (per interleaved pair) | **1.20 [1.08–1.32]** |"),
            "{o}"
        );
    }
}
