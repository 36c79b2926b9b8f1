//! The pipeline cache on disk (src/vulkan/pipeline_cache.rs) on lavapipe,
//! which ignores its data (a header alone) but must still get one file per
//! device and driver, survive a corrupt, truncated or foreign file, and
//! render the same image. Its header's checks are unit-tested beside it;
//! its speed-up is measured on a GPU by tools/gpu_check.sh.

use std::path::{Path, PathBuf};
use std::process::Command;

fn render(xdg: &Path, out: &Path, env: &[(&str, &str)]) -> String {
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/showcase.json");
    let mesa = std::env::var_os("MESA_SHADER_CACHE_DIR")
        .map(PathBuf::from)
        .or_else(|| penumbra::user_cache::user_cache_dir(|k| std::env::var_os(k)))
        .unwrap_or_else(|| xdg.join("mesa"));
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_penumbra"));
    cmd.arg("render")
        .arg(&scene)
        .arg("-o")
        .arg(out)
        .args(["--device", "llvmpipe", "--width", "96", "--height", "54"])
        .args(["--vector-width", "256"])
        .env("XDG_CACHE_HOME", xdg)
        .env("MESA_SHADER_CACHE_DIR", mesa)
        .env_remove("PENUMBRA_PIPELINE_CACHE");
    for (k, v) in env {
        cmd.env(k, v);
    }
    let o = cmd.output().unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success(), "{stderr}");
    assert!(!stderr.contains("error"), "{stderr}");
    stderr
}

/// The pipeline cache files in the cache directory.
fn cache_files(xdg: &Path) -> Vec<PathBuf> {
    let Ok(dir) = std::fs::read_dir(xdg.join("penumbra")) else {
        return Vec::new();
    };
    dir.map(|e| e.unwrap().path())
        .filter(|p| {
            p.file_name()
                .unwrap()
                .to_string_lossy()
                .starts_with("pipelines-")
        })
        .collect()
}

/// Vulkan's VkPipelineCacheHeaderVersionOne: headerSize (at least 32) and
/// headerVersion 1, least significant byte first.
fn has_header_version_one(data: &[u8]) -> bool {
    data.len() >= 32
        && u32::from_le_bytes(data[0..4].try_into().unwrap()) >= 32
        && u32::from_le_bytes(data[4..8].try_into().unwrap()) == 1
}

#[test]
fn a_render_writes_one_cache_file_with_a_vulkan_header() {
    let dir = tempfile::tempdir().unwrap();
    let xdg = dir.path().join("xdg");
    render(&xdg, &dir.path().join("a.png"), &[]);
    let files = cache_files(&xdg);
    assert_eq!(files.len(), 1, "{files:?}");
    let data = std::fs::read(&files[0]).unwrap();
    assert!(has_header_version_one(&data), "{data:?}");
    // The file name holds the vendor ID that the header holds.
    let vendor = u32::from_le_bytes(data[8..12].try_into().unwrap());
    let name = files[0].file_name().unwrap().to_string_lossy().into_owned();
    assert!(
        name.starts_with(&format!("pipelines-{vendor:04x}-")),
        "{name}"
    );
    // No temporary file is left beside it.
    let all = std::fs::read_dir(xdg.join("penumbra")).unwrap().count();
    assert_eq!(all, 1);
}

#[test]
fn a_corrupt_truncated_or_foreign_file_is_ignored_and_replaced() {
    let dir = tempfile::tempdir().unwrap();
    let xdg = dir.path().join("xdg");
    let first = dir.path().join("first.png");
    render(&xdg, &first, &[]);
    let file = cache_files(&xdg).pop().unwrap();
    let good = std::fs::read(&file).unwrap();
    let mut foreign = good.clone();
    foreign[16] ^= 0xff; // another pipelineCacheUUID
    let mut big_header = good.clone();
    big_header[0..4].copy_from_slice(&4096u32.to_le_bytes());
    for (what, bad) in [
        (
            "corrupt",
            b"not a pipeline cache at all, but long enough".to_vec(),
        ),
        ("truncated", good[..20].to_vec()),
        ("foreign", foreign),
        ("header past the end", big_header),
    ] {
        std::fs::write(&file, &bad).unwrap();
        let out = dir.path().join("again.png");
        render(&xdg, &out, &[]);
        assert_eq!(
            std::fs::read(&out).unwrap(),
            std::fs::read(&first).unwrap(),
            "{what}: the image changed"
        );
        let now = std::fs::read(&file).unwrap();
        assert!(has_header_version_one(&now), "{what}: not rewritten");
        assert_eq!(now, good, "{what}");
    }
}

#[test]
fn the_variable_turns_it_off() {
    let dir = tempfile::tempdir().unwrap();
    let xdg = dir.path().join("xdg");
    render(
        &xdg,
        &dir.path().join("a.png"),
        &[("PENUMBRA_PIPELINE_CACHE", "0")],
    );
    assert!(cache_files(&xdg).is_empty());
}
