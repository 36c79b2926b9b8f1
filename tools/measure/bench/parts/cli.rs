//! The one-shot CLI render (section 1's "one-shot" row): the `penumbra`
//! binary of the same build profile renders the bunny scene to a PNG, each
//! run a new process timed from spawn to exit, so the figure is what a user
//! waits for, not the steady frame. Cold runs get a fresh, empty
//! `MESA_SHADER_CACHE_DIR` each; warm runs share one that a first, unmeasured
//! run filled. The benchmark's `MESA_SHADER_CACHE_DISABLE` is removed for
//! these processes, since the cache is what the two cases differ in.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use anyhow::{bail, Context as _};
use common::{ms, Stat};

use crate::schema::CliPart;
use crate::Args;

/// The scene the CLI renders, relative to the repository root.
const SCENE: &str = "scenes/bunny_scene.glb";

/// The `penumbra` binary next to this one (same target directory and
/// profile).
pub fn binary() -> anyhow::Result<PathBuf> {
    let exe = std::env::current_exe()?;
    let dir = exe.parent().context("the benchmark's directory")?;
    Ok(dir.join("penumbra"))
}

/// Builds the `penumbra` binary in the profile this benchmark was built in
/// (release for a measurement), so that the timed binary is this commit's.
pub fn build() -> anyhow::Result<PathBuf> {
    let bin = binary()?;
    let release = bin
        .parent()
        .and_then(Path::file_name)
        .is_some_and(|p| p == "release");
    let mut cmd = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()));
    cmd.args(["build", "--quiet", "-p", "penumbra", "--bin", "penumbra"])
        .current_dir(common::repo_root());
    if release {
        cmd.arg("--release");
    }
    let status = cmd.status().context("running cargo build")?;
    if !status.success() {
        bail!("cargo build of the penumbra binary failed: {status}");
    }
    Ok(bin)
}

/// One process: `penumbra render SCENE -o OUT` with the shader cache in
/// `cache`; its wall time in ms.
fn once(bin: &Path, args: &Args, cache: &Path, out: &Path) -> anyhow::Result<f64> {
    let mut cmd = Command::new(bin);
    cmd.arg("render")
        .arg(common::repo_root().join(SCENE))
        .arg("-o")
        .arg(out)
        .env_remove("MESA_SHADER_CACHE_DISABLE")
        .env("MESA_SHADER_CACHE_DIR", cache)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null());
    if let Some(d) = &args.device.device {
        cmd.args(["--device", d]);
    }
    let t0 = Instant::now();
    let status = cmd.status().context("running penumbra render")?;
    let t = ms(t0.elapsed());
    if !status.success() {
        bail!("penumbra render failed: {status}");
    }
    Ok(t)
}

/// The part: cold runs, then warm runs after one that fills the cache.
pub fn run(args: &Args) -> anyhow::Result<CliPart> {
    let bin = binary()?;
    if !bin.is_file() {
        bail!("no penumbra binary at {}", bin.display());
    }
    let runs = if args.quick { 2 } else { 5 };
    let tmp = tempfile::tempdir()?;
    let out = tmp.path().join("bunny.png");
    let mut cold = Vec::new();
    for i in 0..runs {
        eprintln!("  cli: cold run {}/{runs}", i + 1);
        let cache = tempfile::tempdir()?;
        cold.push(once(&bin, args, cache.path(), &out)?);
    }
    let cache = tmp.path().join("mesa-cache");
    std::fs::create_dir_all(&cache)?;
    once(&bin, args, &cache, &out)?;
    let mut warm = Vec::new();
    for i in 0..runs {
        eprintln!("  cli: warm run {}/{runs}", i + 1);
        warm.push(once(&bin, args, &cache, &out)?);
    }
    Ok(CliPart {
        not_measured: None,
        command: format!("penumbra render {SCENE} -o bunny.png"),
        cold_ms: Stat::of(&cold),
        warm_ms: Stat::of(&warm),
    })
}
