//! Error metrics (`penumbra::metrics`) on images with hand-computed values,
//! and `penumbra diff` on good and bad input: every bad case fails with a
//! non-zero exit status, exactly one `error: ` line naming the file, and no
//! output file.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use penumbra::metrics::{self, compare, pixel_metrics, read_image, srgb_decode};
use penumbra::output::{srgb8, write_image};
use penumbra::render::Image;

fn image(width: u32, height: u32, rgb: &[[f32; 3]]) -> Image {
    assert_eq!(rgb.len(), (width * height) as usize);
    Image {
        width,
        height,
        pixels: rgb.iter().map(|&[r, g, b]| [r, g, b, 1.0]).collect(),
    }
}

/// A deterministic test pattern with gradients and edges.
fn pattern(width: u32, height: u32) -> Image {
    let mut rgb = Vec::new();
    for y in 0..height {
        for x in 0..width {
            let u = x as f32 / width as f32;
            let v = y as f32 / height as f32;
            let check = ((x / 4 + y / 4) % 2) as f32;
            rgb.push([u, v, 0.2 + 0.6 * check]);
        }
    }
    image(width, height, &rgb)
}

#[test]
fn identical_images_give_zeros() {
    let a = pattern(32, 24);
    let m = compare(&a, &a.clone()).unwrap();
    assert_eq!((m.width, m.height), (32, 24));
    assert_eq!(m.max_abs_error, 0.0);
    assert_eq!(m.mean_abs_error, 0.0);
    assert_eq!(m.rmse, 0.0);
    assert_eq!(m.pixels_off_by_more_than_1, 0);
    assert_eq!(m.off_by_more_than_1_of_255, 0.0);
    assert_eq!(m.flip_mean, 0.0);
    assert_eq!(m.flip_max, 0.0);
}

#[test]
fn hand_computed_metrics() {
    // Differences: pixel 0 (0.1, 0.2, 0.3), pixel 1 (0, 0, 0.5), pixel 2 and 3 none.
    let a = image(2, 2, &[[0.0; 3], [1.0; 3], [0.25; 3], [0.75; 3]]);
    let b = image(
        2,
        2,
        &[[0.1, 0.2, 0.3], [1.0, 1.0, 0.5], [0.25; 3], [0.75; 3]],
    );
    let m = pixel_metrics(&a, &b).unwrap();
    let close = |x: f64, y: f64| (x - y).abs() < 1e-6;
    assert!(close(m.max_abs_error, 0.5), "{m:?}");
    assert!(close(m.mean_abs_error, 1.1 / 12.0), "{m:?}");
    assert!(close(m.rmse, (0.39f64 / 12.0).sqrt()), "{m:?}");
    // Pixel 0: code 0 against 89 (R); pixel 1: 255 against 188 (B).
    assert_eq!(m.pixels_off_by_more_than_1, 2);
    assert_eq!(m.off_by_more_than_1_of_255, 0.5);
    // Symmetric.
    let n = pixel_metrics(&b, &a).unwrap();
    assert_eq!(m, n);
}

#[test]
fn one_code_apart_is_not_off_two_codes_apart_is() {
    let code = |c: u8| srgb_decode(c as f32 / 255.0);
    let a = image(3, 1, &[[code(100); 3], [code(100); 3], [code(0); 3]]);
    let b = image(
        3,
        1,
        &[
            [code(101), code(100), code(99)],
            [code(100), code(102), code(100)],
            [code(1); 3],
        ],
    );
    assert_eq!(srgb8(code(101)), 101);
    let m = pixel_metrics(&a, &b).unwrap();
    assert_eq!(m.pixels_off_by_more_than_1, 1);
    assert!((m.off_by_more_than_1_of_255 - 1.0 / 3.0).abs() < 1e-12);
}

#[test]
fn nan_is_not_hidden() {
    let a = image(2, 1, &[[0.0; 3], [0.5; 3]]);
    let b = image(2, 1, &[[f32::NAN, 0.0, 0.0], [0.5; 3]]);
    let m = pixel_metrics(&a, &b).unwrap();
    assert!(m.max_abs_error.is_nan() && m.mean_abs_error.is_nan() && m.rmse.is_nan());
}

#[test]
fn size_mismatch_is_an_error() {
    let e = compare(&pattern(4, 4), &pattern(4, 5)).unwrap_err();
    assert!(e.to_string().contains("4x5"), "{e}");
}

#[test]
fn flip_sees_a_visible_difference() {
    let a = pattern(64, 64);
    let mut b = a.clone();
    // A bright square in the middle.
    for y in 24..40 {
        for x in 24..40 {
            b.pixels[y * 64 + x] = [1.0, 1.0, 1.0, 1.0];
        }
    }
    let m = compare(&a, &b).unwrap();
    assert!(m.flip_mean > 0.0 && m.flip_mean < 1.0, "{m:?}");
    assert!(m.flip_max > 0.5 && m.flip_max <= 1.0, "{m:?}");
    let map = metrics::flip_map(&a, &b).unwrap();
    assert_eq!(map.len(), 64 * 64);
    // Largest inside the square, small far from it.
    assert!(map[32 * 64 + 32] > 0.5);
    assert!(map[2 * 64 + 2] < 0.05, "{}", map[2 * 64 + 2]);
    // The false-colour map is magma: black for no error.
    let fc = metrics::flip_false_colour(64, 64, &map);
    let corner = fc.pixels[0];
    assert!(
        corner[0] < 0.01 && corner[1] < 0.01 && corner[2] < 0.05,
        "{corner:?}"
    );
}

#[test]
fn files_round_trip_exr_exactly_and_png_within_one_code() {
    let dir = tempfile::tempdir().unwrap();
    let a = pattern(16, 8);
    let exr = dir.path().join("a.exr");
    let png = dir.path().join("a.png");
    write_image(&exr, &a).unwrap();
    write_image(&png, &a).unwrap();
    let e = read_image(&exr).unwrap();
    assert_eq!((e.width, e.height), (16, 8));
    for (p, q) in a.pixels.iter().zip(&e.pixels) {
        assert_eq!(&p[..3], &q[..3]);
    }
    let p = read_image(&png).unwrap();
    // Row 0 stays the top row.
    assert!((p.pixels[0][1] - srgb_decode(srgb8(0.0) as f32 / 255.0)).abs() < 1e-6);
    let m = compare(&a, &p).unwrap();
    assert_eq!(m.pixels_off_by_more_than_1, 0, "{m:?}");
    // Half a code of sRGB quantisation at most.
    assert!(m.max_abs_error < 0.01, "{m:?}");
}

// ---- the CLI ----

fn penumbra(args: &[&Path]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .arg("diff")
        .args(args)
        .output()
        .expect("run penumbra")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// Fails with exactly one `error:` line that contains `names`, and no output.
fn assert_fails(out: &Output, names: &str, output_file: &Path) {
    let stderr = text(&out.stderr);
    assert!(
        !out.status.success() && out.status.code().is_some(),
        "status {:?}, stderr: {stderr}",
        out.status
    );
    let errors: Vec<&str> = stderr.lines().filter(|l| l.starts_with("error:")).collect();
    assert_eq!(errors.len(), 1, "stderr: {stderr}");
    assert!(errors[0].contains(names), "{names} not in: {stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(
        !output_file.exists(),
        "{} was written",
        output_file.display()
    );
    assert!(
        text(&out.stdout).is_empty(),
        "stdout: {}",
        text(&out.stdout)
    );
}

struct Files {
    dir: tempfile::TempDir,
}

impl Files {
    fn new() -> Files {
        let dir = tempfile::tempdir().unwrap();
        write_image(&dir.path().join("a.png"), &pattern(32, 16)).unwrap();
        write_image(&dir.path().join("a.exr"), &pattern(32, 16)).unwrap();
        let mut b = pattern(32, 16);
        b.pixels[5] = [1.0, 0.0, 1.0, 1.0];
        write_image(&dir.path().join("b.png"), &b).unwrap();
        write_image(&dir.path().join("small.png"), &pattern(16, 16)).unwrap();
        std::fs::write(dir.path().join("garbage.png"), b"not a png at all").unwrap();
        std::fs::write(dir.path().join("garbage.exr"), b"not an exr").unwrap();
        std::fs::write(dir.path().join("a.jpg"), b"whatever").unwrap();
        Files { dir }
    }

    fn path(&self, name: &str) -> PathBuf {
        self.dir.path().join(name)
    }
}

#[test]
fn diff_prints_metrics_and_writes_the_flip_map() {
    let f = Files::new();
    let out_png = f.path("diff.png");
    let out = penumbra(&[&f.path("a.png"), &f.path("b.png"), "-o".as_ref(), &out_png]);
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "stderr: {}", text(&out.stderr));
    let value = |name: &str| -> f64 {
        let line = stdout
            .lines()
            .find(|l| l.starts_with(&format!("{name}: ")))
            .unwrap_or_else(|| panic!("no {name} in {stdout}"));
        line[name.len() + 2..].trim().parse().unwrap()
    };
    assert!(stdout.contains("size: 32x16"), "{stdout}");
    // One pixel of 512 changed, far beyond a code.
    assert_eq!(value("pixels_off_by_more_than_1_of_255"), 1.0);
    assert_eq!(value("off_by_more_than_1_of_255"), 1.0 / 512.0);
    assert!(value("max_abs_error") > 0.5);
    assert!(value("rmse") > 0.0 && value("mean_abs_error") > 0.0);
    assert!(value("flip_mean") > 0.0 && value("flip_max") > 0.0);
    let map = image::open(&out_png).unwrap();
    assert_eq!((map.width(), map.height()), (32, 16));
    // Nothing else left in the directory (the temporary file was renamed).
    let names: Vec<_> = std::fs::read_dir(f.dir.path()).unwrap().collect();
    assert_eq!(names.len(), 8);

    // The same image as PNG and as EXR: the PNG's quantisation only.
    let out = penumbra(&[&f.path("a.exr"), &f.path("a.png")]);
    assert!(out.status.success(), "stderr: {}", text(&out.stderr));
    assert!(text(&out.stdout).contains("\npixels_off_by_more_than_1_of_255: 0\n"));
}

#[test]
fn diff_rejects_bad_input() {
    let f = Files::new();
    let out_png = f.path("diff.png");
    let o: &Path = "-o".as_ref();
    let cases: Vec<(Vec<PathBuf>, &str)> = vec![
        (vec![f.path("missing.png"), f.path("a.png")], "missing.png"),
        (vec![f.path("a.png"), f.path("missing.exr")], "missing.exr"),
        (vec![f.path("a.jpg"), f.path("a.png")], "a.jpg"),
        (vec![f.path("a.png"), f.path("garbage.png")], "garbage.png"),
        (vec![f.path("garbage.exr"), f.path("a.png")], "garbage.exr"),
        (vec![f.path("a.png"), f.path("small.png")], "small.png"),
        // A directory is not an image.
        (
            vec![f.dir.path().to_path_buf(), f.path("a.png")],
            "unknown image format",
        ),
    ];
    for (inputs, names) in cases {
        let mut args: Vec<&Path> = inputs.iter().map(PathBuf::as_path).collect();
        args.extend([o, out_png.as_path()]);
        let out = penumbra(&args);
        assert_fails(&out, names, &out_png);
    }
    // Size mismatch names both files.
    let out = penumbra(&[&f.path("a.png"), &f.path("small.png")]);
    assert_fails(&out, "a.png is 32x16", &out_png);
    // Unwritable outputs: wrong extension, missing directory.
    for bad in [f.path("diff.txt"), f.path("nope/diff.png")] {
        let out = penumbra(&[&f.path("a.png"), &f.path("b.png"), o, &bad]);
        assert_fails(&out, &bad.display().to_string(), &bad);
    }
}
