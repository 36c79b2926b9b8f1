//! `docs/bench.md`, the benchmark's report, written from [`Results`] alone
//! (so `--from-json` rewrites it without measuring): one function per
//! section, in the order the report has them. Numbers are formatted by
//! `fmt`; the verdicts ("met", "faster than the default", …) are decided
//! from the figures by the small functions of `verdict`.

pub mod analysis;
pub mod fmt;
pub mod header;
pub mod knobs;
pub mod load;
pub mod packet;
pub mod peers;
pub mod scaling;
pub mod seminar;
pub mod specialise;
pub mod standing;
pub mod targets;
pub mod textures;
pub mod throughput;
pub mod verdict;

use crate::schema::Results;

/// The sections, in the report's order.
const SECTIONS: &[fn(&mut String, &Results)] = &[
    header::header,
    header::headline,
    throughput::section,
    seminar::section,
    scaling::section,
    specialise::section,
    packet::section,
    textures::section,
    knobs::section,
    knobs::drivers_section,
    targets::section,
    targets::profile,
    targets::obstacles,
    peers::section,
    standing::section,
    load::section,
];

/// The whole report.
pub fn markdown(r: &Results) -> String {
    let mut o = String::new();
    for section in SECTIONS {
        section(&mut o, r);
    }
    o
}
