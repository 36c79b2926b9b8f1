//! `penumbra farm slurm` against a real Slurm: a single-host cluster that
//! `tools/slurm-local.sh up` starts (as root; `tools/setup.sh --tests`
//! installs the packages). Without Slurm or root this test fails and says
//! so; it never skips. One test function, since the steps share the cluster:
//!
//! * the showcase in 6 tiles is byte-identical to a single render;
//! * a task made to fail (its part path is a directory) leaves the merge
//!   cancelled, and `--resume` resubmits that task alone and completes the
//!   same image;
//! * the area-light scene in 4 sample splits of 64 spp is within the stated
//!   bound of a single 64-spp render;
//! * a batch of 20 scenes, one broken, in 4 tasks renders 19 images and
//!   names the broken one; fixed, `--resume` reruns that task alone.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn repo(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path)
}

fn slurm_local(arg: &str) -> Output {
    Command::new("bash")
        .arg(repo("tools/slurm-local.sh"))
        .arg(arg)
        .output()
        .expect("run tools/slurm-local.sh")
}

fn penumbra(args: &[&str], dir: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .args(args)
        .current_dir(dir)
        .env_remove("PENUMBRA")
        .output()
        .expect("run penumbra")
}

fn text(o: &Output) -> String {
    format!(
        "status {:?}\nstdout:\n{}\nstderr:\n{}",
        o.status,
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

fn ok(args: &[&str], dir: &Path) -> String {
    let o = penumbra(args, dir);
    assert!(o.status.success(), "penumbra {args:?}:\n{}", text(&o));
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// Stops the daemons at the end if this test started them.
struct Cluster {
    started: bool,
}

impl Drop for Cluster {
    fn drop(&mut self) {
        if self.started {
            slurm_local("down");
        }
    }
}

fn exr(path: &Path) -> Vec<f32> {
    image::open(path)
        .expect("read exr")
        .into_rgb32f()
        .into_raw()
}

#[test]
fn farm_slurm_on_a_local_cluster() {
    let running = Command::new("sinfo")
        .arg("-h")
        .output()
        .is_ok_and(|o| o.status.success());
    let _cluster = Cluster { started: !running };
    if !running {
        let up = slurm_local("up");
        assert!(
            up.status.success(),
            "this test needs a local Slurm (as root, after tools/setup.sh --tests):\n{}",
            text(&up)
        );
    }
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // Relative paths, as a user would give them; the jobs start in `d`.
    std::fs::create_dir(d.join("scenes")).unwrap();
    for f in ["showcase.json", "area_lights.json", "bunny.glb"] {
        std::fs::copy(repo("scenes").join(f), d.join("scenes").join(f)).unwrap();
    }
    let size = ["--width", "320", "--height", "180"];

    // Tiles: the same bytes as one render.
    ok(
        &[
            &["render", "scenes/showcase.json", "-o", "single.png"],
            &size[..],
        ]
        .concat(),
        d,
    );
    let farm = [
        &[
            "farm",
            "slurm",
            "scenes/showcase.json",
            "-o",
            "tiled.png",
            "--tiles",
            "6",
        ],
        &size[..],
    ]
    .concat();
    let report = ok(&[&farm[..], &["--submit"]].concat(), d);
    for i in 0..6 {
        assert!(report.contains(&format!("task {i}: ")), "{report}");
    }
    assert!(report.contains("merge job"), "{report}");
    let single = std::fs::read(d.join("single.png")).unwrap();
    assert!(
        single == std::fs::read(d.join("tiled.png")).unwrap(),
        "tiled render differs"
    );
    let script = std::fs::read_to_string(d.join("tiled.png.farm/job.sh")).unwrap();
    assert!(
        !script.contains(d.to_str().unwrap()),
        "script holds the test folder's path"
    );
    let n = Command::new("bash")
        .arg("-n")
        .arg(d.join("tiled.png.farm/job.sh"))
        .status()
        .unwrap();
    assert!(n.success());

    // A failed task: the merge is cancelled, nothing is written; --resume
    // resubmits that task only and gives the same image.
    let farm = [
        &[
            "farm",
            "slurm",
            "scenes/showcase.json",
            "-o",
            "failed.png",
            "--tiles",
            "6",
        ],
        &size[..],
    ]
    .concat();
    std::fs::create_dir_all(d.join("failed.png.farm/parts/part-4.exr")).unwrap();
    let o = penumbra(&[&farm[..], &["--submit"]].concat(), d);
    let t = text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert!(t.contains("task 4: failed"), "{t}");
    assert!(t.contains("CANCELLED"), "{t}");
    let errors: Vec<&str> = t.lines().filter(|l| l.starts_with("error:")).collect();
    assert_eq!(errors.len(), 1, "{t}");
    assert!(errors[0].contains("task 4 failed"), "{t}");
    assert!(!d.join("failed.png").exists());
    std::fs::remove_dir(d.join("failed.png.farm/parts/part-4.exr")).unwrap();
    let resumed = ok(&[&farm[..], &["--resume"]].concat(), d);
    assert!(resumed.contains("resubmitting tasks [4]"), "{resumed}");
    assert!(
        single == std::fs::read(d.join("failed.png")).unwrap(),
        "resumed render differs"
    );
    let again = ok(&[&farm[..], &["--resume"]].concat(), d);
    assert!(again.contains("nothing submitted"), "{again}");

    // Sample splits: within 2n * 2^-24 of the mean (docs/farm.md).
    let small = ["--width", "96", "--height", "64", "--spp", "64"];
    ok(
        &[
            &["render", "scenes/area_lights.json", "-o", "single.exr"],
            &small[..],
        ]
        .concat(),
        d,
    );
    ok(
        &[
            &[
                "farm",
                "slurm",
                "scenes/area_lights.json",
                "-o",
                "split.exr",
                "--sample-splits",
                "4",
                "--submit",
            ],
            &small[..],
        ]
        .concat(),
        d,
    );
    let (a, b) = (exr(&d.join("single.exr")), exr(&d.join("split.exr")));
    assert_eq!(a.len(), b.len());
    for (x, y) in a.iter().zip(&b) {
        let bound = 2.0 * 64.0 * f32::EPSILON / 2.0 * x.abs() + f32::MIN_POSITIVE;
        assert!((x - y).abs() <= bound, "{x} vs {y}");
    }

    // A batch of 20, one broken, in 4 tasks.
    let mut list = String::new();
    for i in 0..20 {
        let radius = if i == 13 { -1 } else { 1 };
        let scene = format!(
            r#"{{"camera": {{"position": [0, 1, 5], "look_at": [0, 0.5, 0], "up": [0, 1, 0], "fov": 45, "width": 32, "height": 24}},
"shaders": {{"s": {{"type": "phong", "diffuse": [0.{i:02}, 0.5, 0.2]}}}},
"objects": [{{"type": "sphere", "center": [0, 1, 0], "radius": {radius}, "shader": "s"}}],
"lights": [{{"type": "point", "position": [2, 3, 2], "intensity": 10}}]}}"#
        );
        std::fs::write(d.join(format!("f{i:02}.json")), scene).unwrap();
        list.push_str(&format!("f{i:02}.json\n"));
    }
    std::fs::write(d.join("list.txt"), list).unwrap();
    let o = penumbra(
        &[
            "farm", "slurm", "--batch", "list.txt", "--tasks", "4", "-o", "frames", "--submit",
        ],
        d,
    );
    let t = text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    // Scene 13 is task 1's (every 4th from the 1st).
    assert!(t.contains("task 1: failed"), "{t}");
    let log = std::fs::read_to_string(d.join("frames.farm/logs/task-1.log")).unwrap();
    assert!(log.contains("f13.json"), "{log}");
    let images = std::fs::read_dir(d.join("frames")).unwrap().count();
    assert_eq!(images, 19, "{t}");
    // Fixed, --resume resubmits task 1 alone, which renders only f13.
    let fixed = std::fs::read_to_string(d.join("f13.json"))
        .unwrap()
        .replace("-1", "1");
    std::fs::write(d.join("f13.json"), fixed).unwrap();
    let resumed = ok(
        &[
            "farm", "slurm", "--batch", "list.txt", "--tasks", "4", "-o", "frames", "--resume",
        ],
        d,
    );
    assert!(resumed.contains("resubmitting tasks [1]"), "{resumed}");
    let log = std::fs::read_to_string(d.join("frames.farm/logs/task-1.log")).unwrap();
    assert!(log.contains("1 rendered, 4 skipped"), "{log}");
    assert_eq!(std::fs::read_dir(d.join("frames")).unwrap().count(), 20);
}
