//! Split renders end to end through the binary: `render --tile I/N` and
//! `--passes A..B` write part files, `merge` puts them back together. Tiles
//! merge to the same bytes as an undivided render; pass splits merge to its
//! pixels within the stated float bound (docs/farm.md); every bad merge and
//! every bad split value is one `error:` line naming the part or the flag,
//! a non-zero exit and no output. Needs a Vulkan device (lavapipe in CI).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use penumbra::farm::part;

fn repo(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path)
}

fn penumbra(args: &[&str], dir: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("run penumbra")
}

fn ok(args: &[&str], dir: &Path) {
    let out = penumbra(args, dir);
    assert!(
        out.status.success(),
        "penumbra {args:?} failed (a Vulkan device is needed: tools/setup.sh):\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// The run failed cleanly: non-zero status, one `error:` line containing
/// every one of `needles`, and `output` not written.
fn fails(args: &[&str], dir: &Path, needles: &[&str], output: &str) {
    let out = penumbra(args, dir);
    let stderr = String::from_utf8_lossy(&out.stderr);
    let code = out.status.code();
    assert!(
        code.is_some_and(|c| c != 0 && c != 101),
        "{args:?}: {code:?} {stderr}"
    );
    let errors: Vec<&str> = stderr.lines().filter(|l| l.starts_with("error:")).collect();
    assert_eq!(
        errors.len(),
        1,
        "{args:?}: expected one error line:\n{stderr}"
    );
    for n in needles {
        assert!(
            errors[0].contains(n),
            "{args:?}: `{n}` not in `{}`",
            errors[0]
        );
    }
    assert!(!dir.join(output).exists(), "{args:?} left {output}");
    let leftovers: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().starts_with(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "{args:?} left temporary files");
}

fn exr_pixels(path: &Path) -> Vec<f32> {
    image::open(path)
        .expect("read exr")
        .into_rgb32f()
        .into_raw()
}

const SIZE: [&str; 4] = ["--width", "200", "--height", "120"];

fn showcase_args<'a>(extra: &[&'a str]) -> Vec<&'a str> {
    let scene = Box::leak(repo("scenes/showcase.json").into_boxed_path());
    let mut v = vec!["render", scene.to_str().unwrap()];
    v.extend_from_slice(&SIZE);
    v.extend_from_slice(extra);
    v
}

#[test]
fn tiles_merge_to_the_bytes_of_an_undivided_render() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    ok(&showcase_args(&["-o", "full.png"]), d);
    ok(&showcase_args(&["-o", "full.exr"]), d);
    for n in [1u32, 4, 7] {
        let mut parts = Vec::new();
        for i in 0..n {
            let name = format!("t{i}of{n}.exr");
            ok(
                &showcase_args(&["--tile", &format!("{i}/{n}"), "-o", &name]),
                d,
            );
            let info = part::read_info(&d.join(&name)).unwrap();
            assert_eq!((info.width, info.height), (200, 120));
            assert_eq!(info.tile.index, i);
            parts.push(name);
        }
        // Given in reverse order: the merge orders them itself.
        parts.reverse();
        let mut args: Vec<&str> = vec!["merge"];
        args.extend(parts.iter().map(String::as_str));
        ok(&[&args[..], &["-o", "merged.png"]].concat(), d);
        let a = std::fs::read(d.join("full.png")).unwrap();
        let b = std::fs::read(d.join("merged.png")).unwrap();
        assert!(
            a == b,
            "{n} tiles: merged PNG differs from the undivided render"
        );
        ok(&[&args[..], &["-o", "merged.exr"]].concat(), d);
        assert_eq!(
            exr_pixels(&d.join("full.exr")),
            exr_pixels(&d.join("merged.exr")),
            "{n} tiles: merged EXR pixels differ"
        );
    }
}

#[test]
fn a_part_is_an_exr_with_the_tile_as_data_window() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    ok(&showcase_args(&["--tile", "2/4", "-o", "p.exr"]), d);
    let meta = exr::meta::MetaData::read_from_file(d.join("p.exr"), false).unwrap();
    let h = &meta.headers[0];
    assert_eq!(
        h.shared_attributes.display_window.size,
        exr::math::Vec2(200, 120)
    );
    // 120 rows = 15 groups of 8: tile 2 of 4 starts at group 7.
    assert_eq!(h.own_attributes.layer_position, exr::math::Vec2(0, 56));
    assert_eq!(h.layer_size, exr::math::Vec2(200, 32));
    let info = part::read_info(&d.join("p.exr")).unwrap();
    assert_eq!(info.rows, 56..88);
    assert_eq!(info.render.len(), 64);
    // Other settings, another render; the same settings, the same render.
    ok(
        &showcase_args(&["--tile", "2/4", "--seed", "1", "-o", "q.exr"]),
        d,
    );
    ok(&showcase_args(&["--tile", "1/4", "-o", "r.exr"]), d);
    assert_ne!(
        part::read_info(&d.join("q.exr")).unwrap().render,
        info.render
    );
    assert_eq!(
        part::read_info(&d.join("r.exr")).unwrap().render,
        info.render
    );
}

/// Passes `0..n` summed in one sequence against the same passes summed in
/// runs and the runs then added: both are within `(n - 1) * 2^-24` of the
/// exact sum relative to it (non-negative terms), and the division by `n`
/// adds `2^-24` to each, so the means differ by at most
/// `2n * 2^-24 * mean` (docs/farm.md).
fn pass_bound(n: u32, value: f32) -> f32 {
    2.0 * n as f32 * f32::EPSILON / 2.0 * value.abs() + f32::MIN_POSITIVE
}

#[test]
fn pass_splits_merge_to_the_undivided_mean_within_the_bound() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = repo("scenes/area_lights.json");
    let s = scene.to_str().unwrap();
    let base = [
        "render", s, "--width", "96", "--height", "64", "--spp", "16",
    ];
    ok(&[&base[..], &["-o", "full.exr"]].concat(), d);
    let mut parts = Vec::new();
    for (t, p) in [
        ("0/2", "0..5"),
        ("0/2", "5..16"),
        ("1/2", "0..9"),
        ("1/2", "9..16"),
    ] {
        let name = format!("t{}p{}.exr", &t[..1], &p[..1]);
        ok(
            &[&base[..], &["--tile", t, "--passes", p, "-o", &name]].concat(),
            d,
        );
        parts.push(name);
    }
    let mut args: Vec<&str> = vec!["merge"];
    args.extend(parts.iter().map(String::as_str));
    ok(&[&args[..], &["-o", "merged.exr"]].concat(), d);
    let a = exr_pixels(&d.join("full.exr"));
    let b = exr_pixels(&d.join("merged.exr"));
    assert_eq!(a.len(), b.len());
    let mut differ = 0;
    for (x, y) in a.iter().zip(&b) {
        assert!((x - y).abs() <= pass_bound(16, *x), "{x} vs {y}");
        differ += (x != y) as u32;
    }
    // Rounding does happen (so the bound is what is tested, not equality).
    assert!(
        differ > 0,
        "no pixel differs: the test would not see a wrong bound"
    );
}

#[test]
fn bad_merges_fail_naming_the_parts_and_write_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for i in 0..3 {
        ok(
            &showcase_args(&["--tile", &format!("{i}/3"), "-o", &format!("t{i}.exr")]),
            d,
        );
    }
    let other = repo("scenes/area_lights.json");
    ok(
        &[
            "render",
            other.to_str().unwrap(),
            "--width",
            "200",
            "--height",
            "120",
            "--tile",
            "1/3",
            "-o",
            "other.exr",
        ],
        d,
    );
    let bytes = std::fs::read(d.join("t2.exr")).unwrap();
    std::fs::write(d.join("cut.exr"), &bytes[..bytes.len() * 2 / 3]).unwrap();
    std::fs::write(d.join("plain.exr"), b"not an exr").unwrap();
    fn merge<'a>(parts: &[&'a str]) -> Vec<&'a str> {
        [&["merge"], parts, &["-o", "out.png"]].concat()
    }
    fails(
        &merge(&["t0.exr", "t2.exr"]),
        d,
        &["tile 1/3: missing"],
        "out.png",
    );
    fails(
        &merge(&["t0.exr", "t1.exr", "t1.exr", "t2.exr"]),
        d,
        &["t1.exr: given 2 times"],
        "out.png",
    );
    std::fs::copy(d.join("t1.exr"), d.join("t1_copy.exr")).unwrap();
    fails(
        &merge(&["t0.exr", "t1.exr", "t1_copy.exr", "t2.exr"]),
        d,
        &[
            "tile 1/3: t1_copy.exr (passes ",
            ") repeats passes already in ",
            "t1.exr",
        ],
        "out.png",
    );
    fails(
        &merge(&["t0.exr", "other.exr", "t2.exr"]),
        d,
        &["other.exr", "another render"],
        "out.png",
    );
    fails(
        &merge(&["t0.exr", "t1.exr", "cut.exr"]),
        d,
        &["cut.exr"],
        "out.png",
    );
    fails(
        &merge(&["t0.exr", "t1.exr", "plain.exr"]),
        d,
        &["plain.exr"],
        "out.png",
    );
    fails(
        &merge(&["t0.exr", "t1.exr", "gone.exr"]),
        d,
        &["gone.exr"],
        "out.png",
    );
    // The same parts merge when complete.
    ok(&merge(&["t0.exr", "t1.exr", "t2.exr"]), d);
}

#[test]
fn bad_split_values_are_one_error_naming_the_flag() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for (extra, needle) in [
        (vec!["--tile", "3/3", "-o", "p.exr"], "--tile"),
        (vec!["--tile", "a/b", "-o", "p.exr"], "--tile"),
        (vec!["--tile", "0/16", "-o", "p.exr"], "--tile"),
        (vec!["--tile", "0/2", "-o", "p.png"], "p.png"),
        (vec!["--passes", "0..4", "-o", "p.exr"], "--passes"),
        (
            vec!["--passes", "4..2", "--spp", "8", "-o", "p.exr"],
            "--passes",
        ),
        (
            vec!["--tile", "0/2", "--time-budget", "1", "-o", "p.exr"],
            "--time-budget",
        ),
    ] {
        let out = if extra.contains(&"p.png") {
            "p.png"
        } else {
            "p.exr"
        };
        fails(&showcase_args(&extra), d, &[needle], out);
    }
}

#[test]
fn a_tile_of_an_image_too_large_for_one_device_buffer_renders() {
    // 4096x4096 needs a 256 MiB image buffer, over lavapipe's 128 MiB
    // maxStorageBufferRange; a tile needs only its rows' buffer.
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = repo("scenes/showcase.json");
    let big = [
        "render",
        scene.to_str().unwrap(),
        "--width",
        "4096",
        "--height",
        "4096",
    ];
    ok(&[&big[..], &["--tile", "5/8", "-o", "p.exr"]].concat(), d);
    let info = part::read_info(&d.join("p.exr")).unwrap();
    assert_eq!(
        (info.width, info.height, info.rows.clone()),
        (4096, 4096, 2560..3072)
    );
    let px = part::read_pixels(&d.join("p.exr"), &info).unwrap();
    assert!(px.iter().any(|p| p[0] > 0.0), "the tile is black");
}

#[test]
fn an_undivided_image_larger_than_one_device_buffer_equals_its_tiles() {
    // 2944x2944 needs a 132 MiB image, over lavapipe's 128 MiB
    // maxStorageBufferRange: one render keeps it in two bands of rows
    // (src/render/bands.rs), and its rows equal a tile's, bit for bit.
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = repo("scenes/showcase.json");
    let big = [
        "render",
        scene.to_str().unwrap(),
        "--width",
        "2944",
        "--height",
        "2944",
    ];
    ok(&[&big[..], &["-o", "full.exr"]].concat(), d);
    ok(&[&big[..], &["--tile", "3/4", "-o", "p.exr"]].concat(), d);
    let info = part::read_info(&d.join("p.exr")).unwrap();
    let rows = info.rows.clone();
    // The tile's rows straddle the boundary of the two bands (row 2848:
    // 128 MiB holds 2849 rows of 2944 pixels, rounded down to 8).
    assert!(rows.start < 2848 && rows.end > 2848, "{rows:?}");
    let tile = part::read_pixels(&d.join("p.exr"), &info).unwrap();
    let full = penumbra::metrics::read_image(&d.join("full.exr")).unwrap();
    assert_eq!((full.width, full.height), (2944, 2944));
    let want = &full.pixels[rows.start as usize * 2944..rows.end as usize * 2944];
    assert_eq!(tile.len(), want.len());
    let differ = tile
        .iter()
        .zip(want)
        .filter(|(t, w)| t[..] != w[..3])
        .count();
    assert_eq!(differ, 0, "{differ} pixels of rows {rows:?} differ");
    assert!(tile.iter().any(|p| p[0] > 0.0), "the tile is black");
}

#[test]
fn farm_slurm_writes_a_script_or_one_error_naming_the_flag() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::create_dir(d.join("scenes")).unwrap();
    for f in ["showcase.json", "bunny.glb"] {
        std::fs::copy(repo("scenes").join(f), d.join("scenes").join(f)).unwrap();
    }
    let farm = ["farm", "slurm", "scenes/showcase.json", "--height", "180"];
    for (extra, needle) in [
        (
            vec!["-o", "x.png", "--tiles", "1000"],
            "--tiles: 1000 tiles",
        ),
        (vec!["-o", "x.tif", "--tiles", "2"], "x.tif"),
        (
            vec!["-o", "x.png", "--sample-splits", "5", "--spp", "4"],
            "--sample-splits",
        ),
        (vec!["-o", "x.png"], "--tiles N"),
    ] {
        fails(
            &[&farm[..], &extra[..]].concat(),
            d,
            &[needle],
            "x.png.farm",
        );
    }
    fails(
        &["farm", "slurm", "nope.json", "-o", "x.png", "--tiles", "2"],
        d,
        &["nope.json"],
        "x.png.farm",
    );
    // Without --submit it only writes the script (no Slurm needed).
    ok(
        &[
            &farm[..],
            &[
                "-o",
                "out/x.png",
                "--tiles",
                "4",
                "--sample-splits",
                "2",
                "--spp",
                "8",
            ],
        ]
        .concat(),
        d,
    );
    let script = d.join("out/x.png.farm/job.sh");
    let text = std::fs::read_to_string(&script).unwrap();
    assert!(
        text.contains("tiles=4\nsplits=2\n") && text.contains("tasks=8"),
        "{text}"
    );
    assert!(!text.contains(d.to_str().unwrap()));
    let n = Command::new("bash")
        .arg("-n")
        .arg(&script)
        .status()
        .unwrap();
    assert!(n.success());
}
