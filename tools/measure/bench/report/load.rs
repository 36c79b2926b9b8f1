//! The report's last section: the machine's load during the run.

use std::fmt::Write as _;

use super::verdict::*;
use crate::schema::*;

/// The last section: each measuring process's own and other processes'
/// CPU use, and the benchmark's priority.
pub fn section(o: &mut String, r: &Results) {
    let _ = writeln!(o, "## Machine load during the run\n");
    let _ = writeln!(
        o,
        "This machine is shared: other processes (builds) sometimes take one of its 2 cores for minutes. Each part waits (up to 30 s) for a quiet second before it starts, and section 1 is repeated (up to three times) while others used more than half a core, keeping the quietest run. For every measuring process: its own CPU use (with its child processes: the peers) and everyone else's, averaged over its run (from /proc/stat), in cores; niced processes (nice > 0, which yield the cores to the benchmark) are counted apart and are not waited for. Ratios of interleaved variants are robust to this; absolute times of a part with other processes at ≈1 core are up to 2× slower.\n"
    );
    let (nice, what) = match r.autogroup_nice {
        Some(n) => (
            n,
            "its session's autogroup, by which the kernel shares the cores between sessions",
        ),
        None => (
            r.nice,
            "its processes, inherited by its children and the peers",
        ),
    };
    if nice != 0 {
        let _ = writeln!(
            o,
            "The benchmark ran at nice {nice} ({what}): on a contested core the scheduler gives it about {:.1}× the share of a nice-0 competitor, so other processes disturbed it {} than their CPU time below suggests.\n",
            1.25f64.powi(-nice as i32),
            nice_effect(nice)
        );
    }
    let _ = writeln!(
        o,
        "| Part | Environment | Wall | Own cores | Other cores | Niced cores |\n|---|---|---|---|---|---|"
    );
    for p in &r.parts {
        let env = p
            .env
            .iter()
            .map(|(k, v)| format!("{k}={v}"))
            .collect::<Vec<_>>()
            .join(" ");
        let _ = writeln!(
            o,
            "| {} | {} | {:.1} s | {:.2} | {:.2} | {:.2} |",
            p.part, env, p.wall_s, p.own_cores, p.other_cores, p.niced_cores
        );
    }
}
