//! The profile under section 6 ("where the time goes"): a bunny run in a
//! child process under `perf record -e cpu-clock`, summarised by shared
//! object and by symbol.

use std::process::Command;

use crate::child::child_with;
use crate::schema::{PartInfo, Profile, ThroughputPart};
use crate::Args;

/// Profiles a bunny run (compile and frames) with `perf record -e
/// cpu-clock` when perf is available: which shared objects the time goes
/// to (lavapipe's JIT-compiled kernel shows as `[JIT]`).
pub fn run(args: &Args, parts: &mut Vec<PartInfo>) -> Profile {
    let skipped = |why: String| Profile {
        skipped: Some(why),
        ..Default::default()
    };
    if Command::new("perf").arg("--version").output().is_err() {
        return skipped("perf is not installed".into());
    }
    let dir = match tempfile::tempdir() {
        Ok(d) => d,
        Err(e) => return skipped(e.to_string()),
    };
    let data = dir.path().join("perf.data");
    let wrapper: Vec<String> = ["perf", "record", "-q", "-e", "cpu-clock", "-F", "999", "-o"]
        .iter()
        .map(|s| s.to_string())
        .chain([data.display().to_string()])
        .collect();
    if let Err(e) = child_with::<ThroughputPart>(args, parts, "knob", &[], Some(&wrapper)) {
        return skipped(format!("perf record failed: {e:#}"));
    }
    let report = |sort: &str| -> (u64, Vec<(String, f64)>) {
        let out = Command::new("perf")
            .args([
                "report",
                "--stdio",
                "--no-children",
                "-g",
                "none",
                "--sort",
                sort,
            ])
            .arg("-i")
            .arg(&data)
            .output();
        let Ok(out) = out else {
            return (0, Vec::new());
        };
        let text = String::from_utf8_lossy(&out.stdout).to_string();
        // "# Samples: 3K of event 'cpu-clock'" is rounded; count from the
        // "# Event count" line when there is one.
        let samples = text
            .lines()
            .find(|l| l.starts_with("# Samples:"))
            .and_then(|l| l.split_whitespace().nth(2))
            .map_or(0, |n| {
                let (num, k) = n.strip_suffix('K').map_or((n, 1.0), |x| (x, 1000.0));
                (num.parse::<f64>().unwrap_or(0.0) * k) as u64
            });
        let rows = text
            .lines()
            .filter(|l| !l.starts_with('#') && l.contains('%'))
            .filter_map(|l| {
                let (pct, name) = l.trim().split_once('%')?;
                Some((name.trim().to_string(), pct.trim().parse().ok()?))
            })
            .collect();
        (samples, rows)
    };
    let (samples, mut dsos) = report("dso");
    // One `[JIT] tid N` entry per thread: merge them.
    let jit: f64 = dsos
        .iter()
        .filter(|d| d.0.starts_with("[JIT]"))
        .map(|d| d.1)
        .sum();
    dsos.retain(|d| !d.0.starts_with("[JIT]"));
    dsos.push(("[JIT] (lavapipe's compiled kernel)".into(), jit));
    dsos.sort_by(|a, b| b.1.total_cmp(&a.1));
    dsos.truncate(6);
    let mut symbols: Vec<(String, f64)> = report("dso,sym")
        .1
        .into_iter()
        .filter(|s| !s.0.starts_with("[JIT]"))
        .collect();
    symbols.truncate(8);
    Profile {
        skipped: None,
        samples,
        dsos,
        symbols,
    }
}
