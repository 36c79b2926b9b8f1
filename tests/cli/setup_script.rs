//! `tools/setup.sh` decides by the devices the Vulkan loader reports, not by ICD files. Its
//! decision is driven here with fake device lists (`PENUMBRA_SETUP_DEVICES_FILE`, the output
//! of `vulkaninfo --summary`), which put it in dry-run mode: it prints what it found and what
//! it would do, and changes nothing.

use std::path::Path;
use std::process::Command;

/// `vulkaninfo --summary`'s device section as Debian 12's own Mesa 22.3 prints it.
const LAVAPIPE_22_3: &str = "\
Devices:
========
GPU0:
\tapiVersion         = 1.3.230
\tdriverVersion      = 0.0.1
\tvendorID           = 0x10005
\tdeviceID           = 0x0000
\tdeviceType         = PHYSICAL_DEVICE_TYPE_CPU
\tdeviceName         = llvmpipe (LLVM 15.0.6, 256 bits)
\tdriverID           = DRIVER_ID_MESA_LLVMPIPE
\tdriverName         = llvmpipe
\tdriverInfo         = Mesa 22.3.6 (LLVM 15.0.6)
\tconformanceVersion = 1.3.1.1
";

/// A discrete GPU listed before lavapipe.
const RADV_AND_LAVAPIPE: &str = "\
Devices:
========
GPU0:
\tapiVersion         = 1.3.230
\tdriverVersion      = 22.3.6
\tvendorID           = 0x1002
\tdeviceID           = 0x73bf
\tdeviceType         = PHYSICAL_DEVICE_TYPE_DISCRETE_GPU
\tdeviceName         = AMD Radeon RX 6800 (RADV NAVI21)
\tdriverID           = DRIVER_ID_MESA_RADV
\tdriverName         = radv
\tdriverInfo         = Mesa 22.3.6
GPU1:
\tapiVersion         = 1.3.230
\tdriverVersion      = 0.0.1
\tvendorID           = 0x10005
\tdeviceID           = 0x0000
\tdeviceType         = PHYSICAL_DEVICE_TYPE_CPU
\tdeviceName         = llvmpipe (LLVM 15.0.6, 256 bits)
\tdriverID           = DRIVER_ID_MESA_LLVMPIPE
\tdriverName         = llvmpipe
\tdriverInfo         = Mesa 22.3.6 (LLVM 15.0.6)
";

/// An integrated GPU alone (Intel, ANV).
const ANV: &str = "\
Devices:
========
GPU0:
\tdeviceType         = PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU
\tdeviceName         = Intel(R) UHD Graphics 620 (KBL GT2)
\tdriverInfo         = Mesa 22.3.6
";

struct Run {
    stdout: String,
}

impl Run {
    fn line(&self, prefix: &str) -> &str {
        let mut found = self.stdout.lines().filter(|l| l.starts_with(prefix));
        let line = found
            .next()
            .unwrap_or_else(|| panic!("no `{prefix}` line in:\n{}", self.stdout));
        assert!(
            found.next().is_none(),
            "more than one `{prefix}` line:\n{}",
            self.stdout
        );
        line
    }
}

/// Runs the script with `devices` as the loader's report (`None`: no loader) and `mesa` as the
/// installed mesa-vulkan-drivers version.
fn setup(devices: Option<&str>, mesa: &str, args: &[&str]) -> Run {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("vulkaninfo.txt");
    let value = match devices {
        Some(text) => {
            std::fs::write(&file, text).unwrap();
            file.to_str().unwrap().to_owned()
        }
        None => "no-loader".to_owned(),
    };
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/setup.sh");
    let out = Command::new("bash")
        .arg(&script)
        .args(args)
        .env("PENUMBRA_SETUP_DEVICES_FILE", &value)
        .env("PENUMBRA_SETUP_MESA_VERSION", mesa)
        .output()
        .unwrap();
    let stdout = String::from_utf8(out.stdout).unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "setup.sh failed: {stdout}{stderr}");
    assert!(
        stdout.contains("setup.sh: dry run: would install:"),
        "a fake device list must only print the decision:\n{stdout}"
    );
    Run { stdout }
}

/// On Debian the upgrade comes from `<codename>-backports`.
fn backports_suffix() -> Option<String> {
    let os = std::fs::read_to_string("/etc/os-release").ok()?;
    let field = |k: &str| {
        os.lines()
            .find_map(|l| l.strip_prefix(k))
            .map(|v| v.trim_matches('"').to_owned())
    };
    if field("ID=")? != "debian" {
        return None;
    }
    Some(format!("(-t {}-backports)", field("VERSION_CODENAME=")?))
}

#[test]
fn cpu_only_with_mesa_22_3_installed_is_upgraded() {
    let run = setup(Some(LAVAPIPE_22_3), "22.3.6-1+deb12u1", &[]);
    assert_eq!(
        run.line("setup.sh: found: CPU device:"),
        "setup.sh: found: CPU device: llvmpipe (LLVM 15.0.6, 256 bits) (Mesa 22.3.6 (LLVM 15.0.6))"
    );
    assert!(run
        .line("setup.sh: found: CPU devices only")
        .ends_with("mesa-vulkan-drivers 22.3.6-1+deb12u1"));
    assert!(run
        .line("setup.sh: decision:")
        .starts_with("setup.sh: decision: upgrade: lavapipe"));
    let install = run.line("setup.sh: dry run: would install:");
    assert!(
        install.contains(" libvulkan1 mesa-vulkan-drivers"),
        "{install}"
    );
    if let Some(bp) = backports_suffix() {
        assert!(install.ends_with(&bp), "{install}");
    }
}

#[test]
fn a_gpu_means_nothing_is_touched() {
    for (devices, gpu) in [
        (
            RADV_AND_LAVAPIPE,
            "DISCRETE_GPU device: AMD Radeon RX 6800 (RADV NAVI21)",
        ),
        (ANV, "INTEGRATED_GPU device: Intel(R) UHD Graphics 620"),
    ] {
        let run = setup(Some(devices), "22.3.6-1+deb12u1", &[]);
        let want = format!("setup.sh: found: {gpu}");
        assert!(
            run.stdout.lines().any(|l| l.starts_with(&want)),
            "no `{want}` in:\n{}",
            run.stdout
        );
        assert!(run
            .line("setup.sh: decision:")
            .starts_with("setup.sh: decision: keep:"));
        assert_eq!(
            run.line("setup.sh: dry run: would install:"),
            "setup.sh: dry run: would install: nothing"
        );
    }
}

#[test]
fn a_gpu_with_tests_installs_only_the_test_tools() {
    let run = setup(Some(RADV_AND_LAVAPIPE), "22.3.6-1+deb12u1", &["--tests"]);
    assert!(run
        .line("setup.sh: decision:")
        .starts_with("setup.sh: decision: keep:"));
    assert_eq!(
        run.line("setup.sh: dry run: would install:"),
        "setup.sh: dry run: would install: vulkan-validationlayers chromium"
    );
}

#[test]
fn no_loader_means_install() {
    let run = setup(None, "none", &["--tests"]);
    assert_eq!(
        run.line("setup.sh: found:"),
        "setup.sh: found: no Vulkan loader (libvulkan.so.1); mesa-vulkan-drivers not installed"
    );
    assert!(run
        .line("setup.sh: decision:")
        .starts_with("setup.sh: decision: install: the Vulkan loader and lavapipe"));
    let install = run.line("setup.sh: dry run: would install:");
    assert!(
        install.contains(" libvulkan1 mesa-vulkan-drivers vulkan-validationlayers chromium"),
        "{install}"
    );
    if let Some(bp) = backports_suffix() {
        assert!(install.ends_with(&bp), "{install}");
    }
}

#[test]
fn a_loader_without_devices_means_install() {
    // What vulkaninfo prints when the ICD files (Intel, Radeon) find no hardware: no devices.
    let run = setup(Some(""), "22.3.6-1+deb12u1", &[]);
    assert!(run
        .line("setup.sh: found:")
        .starts_with("setup.sh: found: a Vulkan loader that reports no device"));
    assert!(run
        .line("setup.sh: decision:")
        .starts_with("setup.sh: decision: install:"));
}
