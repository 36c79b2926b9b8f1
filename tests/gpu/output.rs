//! End-to-end output tests: render small scenes, write them with
//! `penumbra::output::write_image`, decode the files with the `image` crate,
//! and compare with values computed here: the IEC 61966-2-1 sRGB curve for
//! PNG, the exact linear floats for EXR. Also the atomic-write guarantees.

use crate::support;

use std::path::Path;

use penumbra::output::write_image;
use penumbra::render::Frame;

/// IEC 61966-2-1: the sRGB encoding of a linear value, clamped to [0, 1],
/// then rounded to 8 bits.
fn srgb8(linear: f64) -> u8 {
    let c = linear.clamp(0.0, 1.0);
    let e = if c <= 0.0031308 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    };
    (e * 255.0).round() as u8
}

/// A plane filling an orthographic view, coloured k_a·I_a with I_a = 1 and
/// nothing else: every pixel is exactly `colour`.
fn flat(colour: [f32; 3]) -> Frame {
    let json = format!(
        r#"{{
  "camera": {{ "position": [0, 0, 5], "look_at": [0, 0, 0], "projection": "orthographic", "half_height": 1, "width": 24, "height": 16 }},
  "shaders": {{ "flat": {{ "type": "phong", "ambient": {colour:?}, "diffuse": [0, 0, 0] }} }},
  "objects": [ {{ "type": "plane", "point": [0, 0, 0], "normal": [0, 0, 1], "shader": "flat" }} ],
  "lights": [ {{ "type": "directional", "direction": [0, 0, -1], "ambient": [1, 1, 1], "diffuse": [0, 0, 0], "specular": [0, 0, 0] }} ]
}}"#
    );
    let frame = support::render(&support::load_json(&json));
    for p in &frame.image.pixels {
        assert_eq!(
            *p,
            [colour[0], colour[1], colour[2], 1.0],
            "test setup: flat colour"
        );
    }
    frame
}

/// A lit sphere with a bright highlight (values above 1) on a background:
/// varied values for round trips and pixel order.
fn varied() -> Frame {
    let json = r#"{
  "camera": { "position": [0.3, 0.2, 4], "look_at": [0, 0, 0], "fov": 40, "width": 40, "height": 28 },
  "background": [0.01, 0.2, 3.5],
  "shaders": { "m": { "type": "phong", "ambient": [0.3, 0.2, 0.1], "diffuse": [0.9, 0.5, 0.3], "specular": [1, 1, 1], "shininess": 15 } },
  "objects": [ { "type": "sphere", "center": [0.2, 0, 0], "radius": 1, "shader": "m" } ],
  "lights": [ { "type": "point", "position": [3, 3, 3], "intensity": 40, "ambient": [0.1, 0.1, 0.1] } ]
}"#;
    let frame = support::render(&support::load_json(json));
    let img = &frame.image;
    assert!(
        img.pixels.iter().any(|p| p[0] > 1.0),
        "test setup: some value above 1"
    );
    assert!(
        img.pixels.iter().any(|p| p[3] == 0.0),
        "test setup: some background"
    );
    frame
}

fn decode_png(path: &Path) -> image::RgbImage {
    let img = image::ImageReader::open(path)
        .unwrap()
        .with_guessed_format()
        .unwrap()
        .decode()
        .unwrap();
    assert_eq!(img.color(), image::ColorType::Rgb8, "PNG is 8-bit RGB");
    img.into_rgb8()
}

fn decode_exr(path: &Path) -> image::Rgb32FImage {
    let img = image::ImageReader::open(path)
        .unwrap()
        .with_guessed_format()
        .unwrap()
        .decode()
        .unwrap();
    img.into_rgb32f()
}

fn entries(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn png_holds_srgb_encoded_8_bit_values() {
    let dir = tempfile::tempdir().unwrap();
    // (linear colour, its sRGB codes from the standard: 0.18 -> 117.7,
    // 0.5 -> 187.5, above 1 clamps to 255, 0.002 is on the linear segment
    // (12.92 · 0.002 · 255 = 6.6), 0 -> 0, 1 -> 255).
    for (colour, want) in [
        ([0.18, 0.5, 2.0], [118, 188, 255]),
        ([0.002, 0.0, 1.0], [7, 0, 255]),
        ([0.0031308, 0.9, 1e3], [10, 243, 255]),
    ] {
        let frame = flat(colour);
        let path = dir.path().join("flat.png");
        write_image(&path, &frame.image).unwrap();
        let png = decode_png(&path);
        assert_eq!(png.dimensions(), (24, 16));
        let computed = colour.map(|c| srgb8(c as f64));
        assert_eq!(computed, want, "the test's own sRGB formula");
        for p in png.pixels() {
            assert_eq!(p.0, want, "linear {colour:?}");
        }
    }
}

#[test]
fn png_pixels_are_in_image_order() {
    // Every pixel of a varied image, row 0 at the top, against the sRGB
    // formula applied to the rendered linear value.
    let frame = varied();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("varied.png");
    write_image(&path, &frame.image).unwrap();
    let png = decode_png(&path);
    let img = &frame.image;
    assert_eq!(png.dimensions(), (img.width, img.height));
    for y in 0..img.height {
        for x in 0..img.width {
            let lin = img.at(x, y);
            let want = [0, 1, 2].map(|c| srgb8(lin[c] as f64));
            assert_eq!(
                png.get_pixel(x, y).0,
                want,
                "pixel ({x}, {y}), linear {lin:?}"
            );
        }
    }
}

#[test]
fn exr_round_trips_linear_floats_exactly() {
    let dir = tempfile::tempdir().unwrap();
    for frame in [varied(), flat([0.18, 0.5, 2.0])] {
        let path = dir.path().join("linear.exr");
        write_image(&path, &frame.image).unwrap();
        let exr = decode_exr(&path);
        let img = &frame.image;
        assert_eq!(exr.dimensions(), (img.width, img.height));
        for y in 0..img.height {
            for x in 0..img.width {
                let got = exr.get_pixel(x, y).0;
                let want = img.at(x, y);
                // Bit-exact f32 (no clamping, no transfer curve).
                assert_eq!(
                    got.map(f32::to_bits),
                    [want[0], want[1], want[2]].map(f32::to_bits),
                    "pixel ({x}, {y})"
                );
            }
        }
    }
}

#[test]
fn writing_into_a_missing_directory_fails_and_leaves_nothing() {
    let frame = flat([0.5, 0.5, 0.5]);
    let dir = tempfile::tempdir().unwrap();
    for name in ["out.png", "out.exr"] {
        let path = dir.path().join("missing").join("deeper").join(name);
        assert!(write_image(&path, &frame.image).is_err(), "{name}");
        assert!(!path.exists());
    }
    assert!(entries(dir.path()).is_empty(), "{:?}", entries(dir.path()));
}

#[test]
fn writing_over_an_existing_file_replaces_it_entirely() {
    let dir = tempfile::tempdir().unwrap();
    let small = flat([0.18, 0.5, 2.0]);
    for name in ["out.png", "out.exr"] {
        let path = dir.path().join(name);
        // A larger file full of junk: none of it may survive.
        std::fs::write(&path, vec![0xA5u8; 1 << 20]).unwrap();
        write_image(&path, &small.image).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        assert!(
            bytes.len() < 1 << 19,
            "{name}: {} bytes: the old content survived",
            bytes.len()
        );
        assert_eq!(
            bytes,
            penumbra::output::encode(
                &small.image,
                penumbra::output::Format::from_path(&path).unwrap()
            )
            .unwrap()
        );
        assert!(
            !bytes.windows(64).any(|w| w.iter().all(|&b| b == 0xA5)),
            "{name}: junk left"
        );
        // And it decodes to the new image.
        if name.ends_with("png") {
            assert!(decode_png(&path).pixels().all(|p| p.0 == [118, 188, 255]));
        } else {
            assert!(decode_exr(&path).pixels().all(|p| p.0 == [0.18, 0.5, 2.0]));
        }
    }
    // Nothing else in the directory (no temporary files left behind).
    assert_eq!(entries(dir.path()), ["out.exr", "out.png"]);
}

#[test]
fn a_failed_write_leaves_no_temporary_files() {
    let frame = flat([0.5, 0.5, 0.5]);
    let dir = tempfile::tempdir().unwrap();
    // The target is a non-empty directory: the final rename must fail.
    let target = dir.path().join("taken.png");
    std::fs::create_dir(&target).unwrap();
    std::fs::write(target.join("keep.txt"), b"keep").unwrap();
    assert!(write_image(&target, &frame.image).is_err());
    assert_eq!(entries(dir.path()), ["taken.png"]);
    assert_eq!(entries(&target), ["keep.txt"]);
    assert_eq!(std::fs::read(target.join("keep.txt")).unwrap(), b"keep");

    // An unknown extension fails before anything is written.
    assert!(write_image(&dir.path().join("out.bmp"), &frame.image).is_err());
    assert_eq!(entries(dir.path()), ["taken.png"]);

    // A successful write next to it leaves exactly the one file.
    write_image(&dir.path().join("ok.png"), &frame.image).unwrap();
    assert_eq!(entries(dir.path()), ["ok.png", "taken.png"]);
}
