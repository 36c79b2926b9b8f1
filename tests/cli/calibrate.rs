//! `penumbra calibrate` and the calibration's use by `render`, through the
//! binary with a fake measurement (`PENUMBRA_CALIBRATION_FAKE`: the probes
//! report given frame times for a given CPU and driver), so that every branch
//! runs on any machine whatever its CPU; and one real probe on lavapipe. The
//! choice itself is tested as a pure function in src/calibration/mod.rs.
//! Every test has its own XDG_CACHE_HOME, so none reads the user's cache.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use penumbra::calibration::wisdom::{self, Wisdom};
use penumbra::calibration::Candidate;

fn scene() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/showcase.json")
}

/// Made-up medians: 512 bits 1.25x, AVX2 code 1.05x the default's speed.
const TIMES: &str = "256=10,10.5,9.5;512=8,8.2,7.8;256-avx2=9.5,9.6,9.4";

struct Home {
    dir: tempfile::TempDir,
}

impl Home {
    fn new() -> Home {
        Home {
            dir: tempfile::tempdir().unwrap(),
        }
    }

    fn cache(&self) -> PathBuf {
        self.dir.path().join("xdg")
    }

    fn file(&self) -> PathBuf {
        self.cache().join("penumbra").join(wisdom::FILE_NAME)
    }

    fn log(&self) -> PathBuf {
        self.dir.path().join("probes.log")
    }

    /// How many probes have run.
    fn probes(&self) -> usize {
        std::fs::read_to_string(self.log())
            .map(|s| s.lines().count())
            .unwrap_or(0)
    }

    fn fake(&self, cpu: &str, driver: &str) -> String {
        format!(
            "cpu={cpu};driver={driver};{TIMES};log={}",
            self.log().display()
        )
    }

    /// `penumbra ARGS` with this cache directory, the fake, and Mesa's shader
    /// cache where it would be without the test's XDG_CACHE_HOME (so that
    /// compiles stay cached between tests).
    fn run(&self, args: &[&str], fake: &str, env: &[(&str, &str)]) -> Output {
        let mesa = std::env::var_os("MESA_SHADER_CACHE_DIR")
            .map(PathBuf::from)
            .or_else(|| wisdom::user_cache_dir(|k| std::env::var_os(k)))
            .unwrap_or_else(|| self.dir.path().join("mesa"));
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_penumbra"));
        cmd.args(args)
            .env("XDG_CACHE_HOME", self.cache())
            .env("MESA_SHADER_CACHE_DIR", mesa)
            .env("PENUMBRA_CALIBRATION_FAKE", fake)
            .env_remove("LP_NATIVE_VECTOR_WIDTH")
            .env_remove("GALLIUM_OVERRIDE_CPU_CAPS");
        for (k, v) in env {
            cmd.env(k, v);
        }
        cmd.output().unwrap()
    }

    /// A short render (96x54, 1 pass) on lavapipe: its summary line and stderr.
    fn short_render(&self, fake: &str, args: &[&str], env: &[(&str, &str)]) -> (String, String) {
        let out = self.dir.path().join("out.png");
        let scene = scene();
        let mut all = vec![
            "render",
            scene.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--device",
            "llvmpipe",
            "--width",
            "96",
            "--height",
            "54",
        ];
        all.extend_from_slice(args);
        let o = self.run(&all, fake, env);
        let stdout = String::from_utf8_lossy(&o.stdout).into_owned();
        let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
        assert!(o.status.success(), "{stdout}{stderr}");
        let line = stdout
            .lines()
            .find(|l| l.contains(" Mrays/s"))
            .unwrap_or_else(|| panic!("no summary line: {stdout}"))
            .to_owned();
        (line, stderr)
    }

    /// A long render (64 passes at the assumed 1024x1024) that fails at once
    /// after choosing its settings (its output's extension is refused): bad
    /// input, one `error:` line and nothing else. Returns stderr.
    fn long_render_failing(&self, fake: &str) -> String {
        let o = self.run(
            &[
                "render",
                scene().to_str().unwrap(),
                "--spp",
                "64",
                "-o",
                self.dir.path().join("out.txt").to_str().unwrap(),
            ],
            fake,
            &[],
        );
        let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
        assert!(!o.status.success(), "{stderr}");
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
        assert!(
            stderr.starts_with("error: ") && stderr.contains("out.txt"),
            "{stderr}"
        );
        stderr
    }

    /// A long render that succeeds: 96x54 at 16384 passes is past 2^26
    /// primary rays, and a time budget of 5 s (which keeps a render long)
    /// ends it. Its summary line and stderr.
    fn long_render(&self, fake: &str) -> (String, String) {
        self.short_render(fake, &["--spp", "16384", "--time-budget", "5"], &[])
    }

    fn wisdom(&self) -> Wisdom {
        Wisdom::read(&self.file()).unwrap().unwrap()
    }
}

/// Every probe of a calibration: 3 rounds of the 3 candidates.
const PROBES: usize = 9;

#[test]
fn calibrate_measures_prints_and_remembers() {
    let home = Home::new();
    let o = home.run(&["calibrate"], &home.fake("cpu A", "Mesa 1"), &[]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert_eq!(
        home.probes(),
        PROBES,
        "3 interleaved rounds of 3 candidates"
    );
    // Each candidate's median and range over its three rounds' frames.
    assert!(
        stdout.contains(
            "256 bits             median 10.00 ms [9.50–10.50] of CPU time a frame, 9 frames"
        ),
        "{stdout}"
    );
    assert!(
        stdout.contains(
            "512 bits             median 8.00 ms [7.80–8.20] of CPU time a frame, 9 frames"
        ),
        "{stdout}"
    );
    assert!(
        stdout.contains(
            "256 bits, AVX2 code  median 9.50 ms [9.40–9.60] of CPU time a frame, 9 frames"
        ),
        "{stdout}"
    );
    assert!(stdout.contains("long renders: vector width 512 (calibrated on this machine: 1.25x the default's speed)"), "{stdout}");
    assert!(stdout.contains("short renders and watch: vector width 256, AVX2 code (calibrated on this machine: 1.05x the default's speed)"), "{stdout}");
    let w = home.wisdom();
    assert_eq!(w.entries.len(), 1);
    let e = &w.entries[0];
    assert_eq!(
        (e.key.cpu.as_str(), e.key.driver.as_str()),
        ("cpu A", "Mesa 1")
    );
    let medians: Vec<(Candidate, f64)> = e
        .measured
        .iter()
        .map(|m| (m.candidate, m.median_ms))
        .collect();
    assert_eq!(
        medians,
        vec![
            (Candidate::Wide256, 10.0),
            (Candidate::Wide512, 8.0),
            (Candidate::Avx2At256, 9.5)
        ]
    );
}

#[test]
fn a_long_render_calibrates_after_itself_and_the_next_one_uses_it() {
    let home = Home::new();
    let fake = home.fake("cpu A", "Mesa 1");
    let (line, stderr) = home.long_render(&fake);
    assert!(
        line.ends_with(
            " | vector width 256 (auto: AVX-512, not calibrated; `penumbra calibrate` measures)"
        ),
        "{line}"
    );
    assert!(
        stderr.contains(
            "note: calibrating lavapipe on this machine for the long renders after this one"
        ),
        "{stderr}"
    );
    assert_eq!(home.probes(), PROBES);
    assert!(home.file().exists());
    // The second long render reads the file (no probe) and renders at 512
    // bits (the device's name says so).
    let (line, stderr) = home.long_render(&fake);
    assert_eq!(home.probes(), PROBES, "the second run measured again");
    assert!(!stderr.contains("calibrating"), "{stderr}");
    assert!(
        line.ends_with(
            " | vector width 512 (calibrated on this machine: 1.25x the default's speed)"
        ),
        "{line}"
    );
    assert!(
        line.contains(", 512 bits)"),
        "the driver did not get it: {line}"
    );
}

#[test]
fn a_long_render_that_fails_does_not_calibrate() {
    let home = Home::new();
    home.long_render_failing(&home.fake("cpu A", "Mesa 1"));
    assert_eq!(home.probes(), 0);
    assert!(!home.file().exists());
}

#[test]
fn short_renders_never_calibrate_and_use_the_remembered_choice() {
    let home = Home::new();
    let fake = home.fake("cpu A", "Mesa 1");
    let (line, _) = home.short_render(&fake, &[], &[]);
    assert_eq!(home.probes(), 0, "a short render calibrated");
    assert!(!home.file().exists());
    assert!(
        line.ends_with(
            " | vector width 256 (auto: AVX-512, not calibrated; `penumbra calibrate` measures)"
        ),
        "{line}"
    );
    assert!(home.run(&["calibrate"], &fake, &[]).status.success());
    let (line, _) = home.short_render(&fake, &[], &[]);
    assert_eq!(home.probes(), PROBES);
    assert!(
        line.ends_with(" | vector width 256, AVX2 code (calibrated on this machine: 1.05x the default's speed)"),
        "{line}"
    );
    assert!(line.contains(", 256 bits)"), "{line}");
}

#[test]
fn another_cpu_recalibrates_and_keeps_both() {
    let home = Home::new();
    assert!(home
        .run(&["calibrate"], &home.fake("cpu A", "Mesa 1"), &[])
        .status
        .success());
    assert_eq!(home.probes(), PROBES);
    let (line, _) = home.long_render(&home.fake("cpu B", "Mesa 1"));
    assert!(
        line.contains("not calibrated"),
        "cpu A's calibration used for cpu B: {line}"
    );
    assert_eq!(home.probes(), 2 * PROBES, "cpu B was not calibrated");
    let cpus: Vec<String> = home
        .wisdom()
        .entries
        .iter()
        .map(|e| e.key.cpu.clone())
        .collect();
    assert_eq!(cpus, vec!["cpu A", "cpu B"]);
}

#[test]
fn another_driver_forgets_the_calibration() {
    let home = Home::new();
    assert!(home
        .run(&["calibrate"], &home.fake("cpu A", "Mesa 1"), &[])
        .status
        .success());
    let (line, stderr) = home.short_render(&home.fake("cpu A", "Mesa 2"), &[], &[]);
    assert!(
        stderr.contains("calibrated with driver `Mesa 1`, this is `Mesa 2`: forgotten"),
        "{stderr}"
    );
    assert!(line.contains("calibrated on this machine"), "{line}");
    assert!(
        home.wisdom().entries.is_empty(),
        "so the next long render calibrates"
    );
    let (line, stderr) = home.short_render(&home.fake("cpu A", "Mesa 2"), &[], &[]);
    assert!(line.contains("not calibrated"), "{line}");
    assert!(!stderr.contains("forgotten"), "{stderr}");
}

#[test]
fn the_users_flag_and_variables_win_over_the_calibration() {
    let home = Home::new();
    let fake = home.fake("cpu A", "Mesa 1");
    assert!(home.run(&["calibrate"], &fake, &[]).status.success());
    let (line, _) = home.short_render(&fake, &["--vector-width", "128"], &[]);
    assert!(
        line.ends_with(" | vector width 128 (--vector-width)"),
        "{line}"
    );
    assert!(line.contains(", 128 bits)"), "{line}");
    let (line, _) = home.short_render(&fake, &[], &[("LP_NATIVE_VECTOR_WIDTH", "128")]);
    assert!(
        line.ends_with(" | vector width 128 (LP_NATIVE_VECTOR_WIDTH set)"),
        "{line}"
    );
    // The user's cap below AVX-512 leaves no AVX-512 to choose with.
    let (line, _) = home.short_render(&fake, &[], &[("GALLIUM_OVERRIDE_CPU_CAPS", "avx")]);
    assert!(
        line.ends_with(" | vector width 256 (auto: no AVX-512)"),
        "{line}"
    );
    assert_eq!(home.probes(), PROBES, "only `calibrate` measured");
}

#[test]
fn a_corrupt_or_foreign_file_is_noted_and_replaced() {
    let texts = [
        "{\"format\": \"penumbra calibration\", \"version\": 99, \"entries\": []}",
        "not json \u{1b}[31m",
        "",
    ];
    for (i, text) in texts.iter().enumerate() {
        let home = Home::new();
        std::fs::create_dir_all(home.file().parent().unwrap()).unwrap();
        std::fs::write(home.file(), text).unwrap();
        let fake = home.fake("cpu A", "Mesa 1");
        // A short render: one note, the default, no measurement.
        let (line, stderr) = home.short_render(&fake, &[], &[]);
        let notes: Vec<_> = stderr
            .lines()
            .filter(|l| l.contains("not a calibration of this version"))
            .collect();
        assert_eq!(notes.len(), 1, "{stderr}");
        assert!(!notes[0].contains('\u{1b}'), "unescaped: {stderr}");
        assert!(line.contains("not calibrated"), "{line}");
        assert_eq!(home.probes(), 0);
        // A long render (once: it takes 5 s): one note, and it recalibrates.
        if i == 0 {
            let (_, stderr) = home.long_render(&fake);
            let notes = stderr.matches("not a calibration of this version").count();
            assert_eq!(notes, 1, "{stderr}");
            assert_eq!(home.probes(), PROBES, "{text}: not recalibrated");
            assert_eq!(home.wisdom().entries.len(), 1);
        }
    }
}

#[test]
fn a_bad_fake_is_one_error_naming_the_variable() {
    let home = Home::new();
    for bad in ["cpu=A", "cpu=A;driver=B;256=fast", "cpu=A;driver=B;1024=1"] {
        let o = home.run(&["calibrate"], bad, &[]);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{bad}");
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
        assert!(
            stderr.starts_with("error: PENUMBRA_CALIBRATION_FAKE: "),
            "{stderr}"
        );
    }
}

/// The probe on lavapipe itself: warm frames of the built-in scene at the
/// width it was given (the device's name says it).
#[test]
fn a_real_probe_times_frames_at_its_width() {
    let home = Home::new();
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_penumbra"));
    let o = cmd
        .args(["calibrate", "--probe", "256", "--device", "llvmpipe"])
        .env("XDG_CACHE_HOME", home.cache())
        .env_remove("PENUMBRA_CALIBRATION_FAKE")
        .env("LP_NATIVE_VECTOR_WIDTH", "256")
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let v: serde_json::Value = serde_json::from_str(stdout.trim()).unwrap();
    assert!(v["device"].as_str().unwrap().contains(", 256 bits)"), "{v}");
    assert_eq!(v["device_type"], "CPU");
    assert!(v["driver"].as_str().unwrap().contains("Mesa"), "{v}");
    let frames = v["frames_ms"].as_array().unwrap();
    assert_eq!(frames.len(), 8, "{v}");
    assert!(frames.iter().all(|f| f.as_f64().unwrap() > 0.0), "{v}");
}
