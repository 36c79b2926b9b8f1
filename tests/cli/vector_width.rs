//! `penumbra render --vector-width`: the SIMD width lavapipe runs with, chosen
//! before the driver loads and said in the summary line. The device's own name
//! ("llvmpipe (LLVM 15.0.6, 128 bits)") shows that the width reached the driver.
//! The choice's every branch (AVX-512 or not, calibrated or not, long or
//! short, watch) is tested as a pure function in src/vector_width.rs, the
//! calibration's use in tests/cli/calibrate.rs; here the wiring. Each render
//! has its own XDG_CACHE_HOME, so that no calibration of the user's is read.

use std::path::Path;
use std::process::{Command, Output};

use penumbra::calibration::wisdom;
use penumbra::vector_width::{self, CpuVectors, Job, Request};

fn scene() -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes/showcase.json")
        .to_str()
        .unwrap()
        .to_owned()
}

/// Renders the showcase small on lavapipe, with `LP_NATIVE_VECTOR_WIDTH` set to
/// `env` or removed, and no calibration (an empty XDG_CACHE_HOME; Mesa's
/// shader cache where it would be without it).
fn render(dir: &Path, args: &[&str], env: Option<&str>) -> (Output, String) {
    let out = dir.join("out.png");
    let mesa = std::env::var_os(vector_width::CACHE_VARIABLE)
        .map(std::path::PathBuf::from)
        .or_else(|| wisdom::user_cache_dir(|k| std::env::var_os(k)))
        .unwrap_or_else(|| dir.join("mesa"));
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_penumbra"));
    cmd.args(["render", &scene(), "-o", out.to_str().unwrap()])
        .args(["--device", "llvmpipe"])
        .args(args)
        .env("XDG_CACHE_HOME", dir.join("xdg"))
        .env(vector_width::CACHE_VARIABLE, mesa)
        .env_remove("PENUMBRA_CALIBRATION_FAKE")
        .env_remove("GALLIUM_OVERRIDE_CPU_CAPS");
    match env {
        Some(v) => cmd.env(vector_width::VARIABLE, v),
        None => cmd.env_remove(vector_width::VARIABLE),
    };
    let output = cmd.output().unwrap();
    let stdout = String::from_utf8_lossy(&output.stdout).into_owned();
    (output, stdout)
}

/// The summary line, which must say the width and end with it.
fn summary(output: &Output, stdout: &str) -> String {
    assert!(
        output.status.success(),
        "render failed: {stdout}{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let line = stdout
        .lines()
        .find(|l| l.contains(" Mrays/s"))
        .unwrap_or_else(|| panic!("no summary line in {stdout}"));
    line.to_owned()
}

/// Without a calibration, a short render takes the CPU's default. (A long
/// one on a CPU with AVX-512 would calibrate first: tests/cli/calibrate.rs.)
#[test]
fn auto_says_its_choice_and_the_driver_uses_it() {
    let dir = tempfile::tempdir().unwrap();
    let job = Job::Render {
        pixels: Some(96 * 54),
        passes: 1,
        time_budget: None,
    };
    let want = vector_width::choose(Request::Auto, None, CpuVectors::detect(), job, None);
    let (output, stdout) = render(dir.path(), &["--width", "96", "--height", "54"], None);
    let line = summary(&output, &stdout);
    assert!(line.ends_with(&format!(" | {want}")), "want {want}: {line}");
    if let Some(bits) = want.bits {
        assert!(line.contains(&format!(", {bits} bits)")), "{line}");
    }
    assert!(
        !dir.path().join("xdg/penumbra/calibration.json").exists(),
        "a short render calibrated"
    );
}

#[test]
fn the_flag_overrides_auto() {
    let dir = tempfile::tempdir().unwrap();
    let (output, stdout) = render(
        dir.path(),
        &["--width", "96", "--height", "54", "--vector-width", "128"],
        None,
    );
    let line = summary(&output, &stdout);
    assert!(
        line.ends_with(" | vector width 128 (--vector-width)"),
        "{line}"
    );
    assert!(
        line.contains(", 128 bits)"),
        "the driver did not get it: {line}"
    );
}

#[test]
fn the_users_environment_wins_over_the_flag() {
    let dir = tempfile::tempdir().unwrap();
    let (output, stdout) = render(
        dir.path(),
        &["--width", "96", "--height", "54", "--vector-width", "256"],
        Some("128"),
    );
    let line = summary(&output, &stdout);
    assert!(
        line.ends_with(" | vector width 128 (LP_NATIVE_VECTOR_WIDTH set)"),
        "{line}"
    );
    assert!(line.contains(", 128 bits)"), "{line}");
}

#[test]
fn a_bad_width_is_one_error_naming_the_flag() {
    let dir = tempfile::tempdir().unwrap();
    for bad in ["300", "auto512", ""] {
        let (output, stdout) = render(dir.path(), &["--vector-width", bad], None);
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(!output.status.success(), "{bad}: {stdout}");
        let errors: Vec<_> = stderr.lines().filter(|l| l.starts_with("error:")).collect();
        assert_eq!(errors.len(), 1, "{stderr}");
        assert!(errors[0].contains("--vector-width"), "{stderr}");
        assert!(stdout.is_empty(), "{stdout}");
        assert!(!dir.path().join("out.png").exists());
    }
}

/// Mesa 25.0's shader cache does not key its entries by the vector width, so a
/// render at one width after another would run the first one's cached machine
/// code. Each width gets its own cache directory under the user's
/// `MESA_SHADER_CACHE_DIR`, and each render fills its own.
#[test]
fn each_width_compiles_into_its_own_shader_cache() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let files = |bits: u32| -> usize {
        let d = cache.join(format!("{}{bits}", vector_width::CACHE_PREFIX));
        walk(&d)
    };
    for bits in [256, 128] {
        let out = dir.path().join("out.png");
        let output = Command::new(env!("CARGO_BIN_EXE_penumbra"))
            .args(["render", &scene(), "-o", out.to_str().unwrap()])
            .args(["--device", "llvmpipe", "--width", "96", "--height", "54"])
            .args(["--vector-width", &bits.to_string()])
            .env_remove("GALLIUM_OVERRIDE_CPU_CAPS")
            .env_remove(vector_width::VARIABLE)
            .env_remove("MESA_SHADER_CACHE_DISABLE")
            .env(vector_width::CACHE_VARIABLE, &cache)
            .output()
            .unwrap();
        let stdout = String::from_utf8_lossy(&output.stdout).into_owned();
        let line = summary(&output, &stdout);
        assert!(line.contains(&format!(", {bits} bits)")), "{line}");
        assert!(
            files(bits) > 0,
            "{bits}-bit code went to no cache of its own"
        );
    }
    assert!(
        files(256) > 0,
        "the 128-bit render removed the 256-bit cache"
    );
    let stray: Vec<_> = std::fs::read_dir(&cache)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| !n.starts_with(vector_width::CACHE_PREFIX))
        .collect();
    assert!(
        stray.is_empty(),
        "cache entries outside the widths' directories: {stray:?}"
    );
}

/// The number of files under `dir` (0 if it does not exist).
fn walk(dir: &Path) -> usize {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return 0;
    };
    entries
        .map(|e| {
            let e = e.unwrap();
            if e.file_type().unwrap().is_dir() {
                walk(&e.path())
            } else {
                1
            }
        })
        .sum()
}
