//! Running a part in a child process: this binary re-invoked with the hidden
//! `--child` flag, so that the environment variables Mesa reads when the
//! driver loads apply (`MESA_SHADER_CACHE_DISABLE=true` for honest cold
//! compiles, lavapipe's knobs), with the machine's load sampled around it
//! ([`PartInfo`]: its own cores, everyone else's, niced processes').

use std::process::Command;
use std::time::Instant;

use anyhow::{bail, Context as _};
use common::load::{machine_busy_ticks, machine_nice_ticks, wait_quiet};
use serde::Deserialize;

use crate::schema::PartInfo;
use crate::Args;

/// Runs `part` in a child process with Mesa's shader cache disabled and
/// `env` set.
pub fn child<T: for<'de> Deserialize<'de>>(
    args: &Args,
    parts: &mut Vec<PartInfo>,
    part: &str,
    env: &[(&str, &str)],
) -> anyhow::Result<T> {
    child_with(args, parts, part, env, None)
}

/// [`child`], optionally run under `wrapper` (e.g. `perf record ...`).
pub fn child_with<T: for<'de> Deserialize<'de>>(
    args: &Args,
    parts: &mut Vec<PartInfo>,
    part: &str,
    env: &[(&str, &str)],
    wrapper: Option<&[String]>,
) -> anyhow::Result<T> {
    let dir = tempfile::tempdir()?;
    let out = dir.path().join("part.json");
    let exe = std::env::current_exe()?;
    let mut cmd = match wrapper {
        Some(w) => {
            let mut c = Command::new(&w[0]);
            c.args(&w[1..]).arg("--").arg(&exe);
            c
        }
        None => Command::new(&exe),
    };
    cmd.args(["--child", part, "--child-out"]).arg(&out);
    if args.quick {
        cmd.arg("--quick");
    }
    if let Some(d) = &args.device.device {
        cmd.args(["--device", d]);
    }
    if args.subdivide > 0 {
        cmd.args(["--subdivide", &args.subdivide.to_string()]);
    }
    cmd.env("MESA_SHADER_CACHE_DISABLE", "true");
    for (k, v) in env {
        cmd.env(k, v);
    }
    let waited = wait_quiet();
    if waited > 1.0 {
        eprintln!("bench: waited {waited:.0} s for other processes to quieten");
    }
    let t0 = Instant::now();
    let busy0 = machine_busy_ticks();
    let nice0 = machine_nice_ticks();
    eprintln!("bench: {part} {env:?}");
    let status = cmd
        .status()
        .with_context(|| format!("running part {part}"))?;
    if !status.success() {
        bail!("part {part} {env:?} failed: {status}");
    }
    let wall = t0.elapsed().as_secs_f64();
    let busy = machine_busy_ticks().saturating_sub(busy0) as f64 / 100.0;
    let nice = machine_nice_ticks().saturating_sub(nice0) as f64 / 100.0;
    let own = std::fs::read_to_string(out.with_extension("ticks"))
        .ok()
        .and_then(|t| t.trim().parse::<u64>().ok())
        .unwrap_or(0) as f64
        / 100.0;
    let info = PartInfo {
        part: part.into(),
        env: env
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect(),
        wall_s: wall,
        own_cores: own / wall,
        other_cores: ((busy - own) / wall).max(0.0),
        niced_cores: nice / wall,
    };
    eprintln!(
        "bench: {part} took {wall:.1} s (own {:.2} cores, others {:.2} cores)",
        info.own_cores, info.other_cores
    );
    parts.push(info);
    let text = std::fs::read_to_string(&out)?;
    Ok(serde_json::from_str(&text)?)
}
