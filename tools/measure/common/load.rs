//! The machine's load and a process's own CPU use, sampled from `/proc`
//! (Linux). The tools run on shared machines: the benchmark waits for a quiet
//! moment and reports how busy everyone else was during each part; `ab`
//! compares the CPU time of the driver's threads, which other processes do
//! not inflate; `bench_reload` watches its memory. Where `/proc` cannot be
//! read the figures are zero.

use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use anyhow::Context as _;

/// The fields after the command name in `/proc/self/stat` (the name is in
/// parentheses and may hold spaces).
fn self_stat_fields() -> Vec<String> {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let rest = stat.rsplit_once(')').map_or("", |r| r.1);
    rest.split_whitespace().map(str::to_string).collect()
}

/// This process's user + system CPU time in clock ticks (1/100 s), with
/// that of its children it has waited for (the benchmark's peers), so that
/// they count as the process's own load, not as other processes'.
pub fn own_ticks() -> u64 {
    // utime, stime, cutime, cstime: the 12th to 15th fields after the
    // command name.
    let f: Vec<u64> = self_stat_fields()
        .iter()
        .map(|x| x.parse().unwrap_or(0))
        .collect();
    (11..15).map(|i| f.get(i).copied().unwrap_or(0)).sum()
}

/// This process's nice value (the 19th field of /proc/self/stat).
pub fn own_nice() -> i64 {
    self_stat_fields()
        .get(16)
        .and_then(|x| x.parse().ok())
        .unwrap_or(0)
}

/// The nice value of this process's autogroup, from /proc/self/autogroup
/// (`/autogroup-5 nice -10`), when the kernel groups by session.
pub fn autogroup_nice() -> Option<i64> {
    let on = std::fs::read_to_string("/proc/sys/kernel/sched_autogroup_enabled").ok()?;
    if on.trim() != "1" {
        return None;
    }
    let text = std::fs::read_to_string("/proc/self/autogroup").ok()?;
    text.split_whitespace().last()?.parse().ok()
}

/// Busy CPU time of the whole machine in clock ticks (1/100 s), without
/// that of niced processes ([`machine_nice_ticks`]).
pub fn machine_busy_ticks() -> u64 {
    stat_ticks(|i| i != 1 && i != 3 && i != 4)
}

/// CPU time of niced processes (nice > 0) in clock ticks: they yield the
/// cores to a benchmark, so they are counted apart from the others.
pub fn machine_nice_ticks() -> u64 {
    stat_ticks(|i| i == 1)
}

/// The sum of the fields of /proc/stat's `cpu` line that `keep` keeps, by
/// index: user nice system idle iowait irq softirq steal.
fn stat_ticks(keep: impl Fn(usize) -> bool) -> u64 {
    let stat = std::fs::read_to_string("/proc/stat").unwrap_or_default();
    let line = stat.lines().next().unwrap_or("");
    line.split_whitespace()
        .skip(1)
        .take(8)
        .enumerate()
        .filter(|(i, _)| keep(*i))
        .map(|(_, x)| x.parse::<u64>().unwrap_or(0))
        .sum()
}

/// Waits (at most 30 s per call and 120 s per process) until other
/// processes use less than a third of a core over one second, so that
/// measurements start on a quiet machine where possible; returns the
/// seconds waited. The caller reports the machine's load either way.
pub fn wait_quiet() -> f64 {
    static WAITED_MS: AtomicU64 = AtomicU64::new(0);
    let budget =
        Duration::from_millis(120_000u64.saturating_sub(WAITED_MS.load(Ordering::Relaxed)))
            .min(Duration::from_secs(30));
    let t0 = Instant::now();
    while t0.elapsed() < budget {
        let b0 = machine_busy_ticks();
        std::thread::sleep(Duration::from_secs(1));
        if (machine_busy_ticks() - b0) < 33 {
            break;
        }
    }
    WAITED_MS.fetch_add(t0.elapsed().as_millis() as u64, Ordering::Relaxed);
    t0.elapsed().as_secs_f64()
}

/// Nanoseconds on the CPU of every thread of this process but the main one
/// (lavapipe's workers; the main thread only submits and waits), from
/// /proc/self/task/*/schedstat.
pub fn worker_cpu_ns() -> anyhow::Result<u64> {
    let main = std::process::id().to_string();
    let mut total = 0;
    for task in std::fs::read_dir("/proc/self/task")? {
        let task = task?;
        if task.file_name().to_str() == Some(main.as_str()) {
            continue;
        }
        // A thread that ended meanwhile has no schedstat any more.
        let Ok(stat) = std::fs::read_to_string(task.path().join("schedstat")) else {
            continue;
        };
        let on_cpu = stat.split_whitespace().next().unwrap_or("0");
        total += on_cpu.parse::<u64>().context("schedstat")?;
    }
    Ok(total)
}

/// This process's resident memory (VmRSS) in KiB.
pub fn rss_kib() -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmRSS:"))
                .and_then(|l| l.split_whitespace().nth(1)?.parse().ok())
        })
        .unwrap_or(0)
}
