//! `--gltf-materials`: glTF files render with glTF's own metallic-roughness
//! model by default, and with the seminar's Phong mapping on request, so
//! that renders made before issue 38 can be reproduced.

use std::path::Path;
use std::process::Command;

/// Renders `scenes/bunny_scene.glb` at 64×64 to a linear EXR with `extra`
/// arguments and returns its RGBA pixels.
fn render(extra: &[&str]) -> Vec<[f32; 4]> {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.exr");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/bunny_scene.glb");
    let status = Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .arg("render")
        .arg(&scene)
        .args(["--width", "64", "--height", "64", "-o"])
        .arg(&out)
        .args(extra)
        .status()
        .expect("run penumbra");
    assert!(status.success(), "{extra:?}");
    let img = image::open(&out).unwrap().to_rgba32f();
    img.pixels().map(|p| p.0).collect()
}

/// The ground of the benchmark scene is a rough dielectric of base colour
/// 0.8 lit at cos θ = 2/3 by a directional light of intensity 1 (the file's
/// KHR_lights_punctual light). Phong maps it to k_d = 0.8: the lit ground
/// is 0.8·2/3 exactly (tests/gpu/bunny.rs). glTF's BRDF gives its diffuse
/// part (1 − F)·0.8/π·2/3 plus a specular part, never 0.8·2/3.
#[test]
fn phong_reproduces_the_seminar_mapping_and_the_default_is_gltfs_brdf() {
    let lambert = |pixels: &[[f32; 4]]| {
        pixels
            .iter()
            .filter(|p| p[3] == 1.0 && (f64::from(p[0]) - 0.8 * 2.0 / 3.0).abs() < 1e-5)
            .count()
    };
    let phong = render(&["--gltf-materials", "phong"]);
    assert!(lambert(&phong) > 64 * 64 / 3, "{}", lambert(&phong));
    let pbr = render(&[]);
    assert_eq!(lambert(&pbr), 0);
    // The default's lit ground: at most the diffuse part 0.8/π·2/3 (F ≥ 0.04
    // takes some) plus a small highlight, far below Phong's 0.533.
    let lit = pbr
        .iter()
        .filter(|p| p[3] == 1.0 && p[0] > 0.1 && p[0] < 0.2)
        .count();
    assert!(
        lit > 64 * 64 / 3,
        "{lit} ground pixels near 0.8/π·2/3 = 0.170"
    );
    assert_eq!(pbr, render(&["--gltf-materials", "metallic-roughness"]));
}

/// `--exposure` and `--tonemap` change the PNG only: the EXR of the same
/// render stays linear and bit-identical, and the PNG is the sRGB code of
/// PBR Neutral of 2^EV × the EXR's values.
#[test]
fn exposure_and_tone_mapping_apply_to_the_png_only() {
    let dir = tempfile::tempdir().unwrap();
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/bunny_scene.glb");
    let run = |out: &str, extra: &[&str]| {
        let status = Command::new(env!("CARGO_BIN_EXE_penumbra"))
            .arg("render")
            .arg(&scene)
            .args(["--width", "32", "--height", "32", "-o"])
            .arg(dir.path().join(out))
            .args(extra)
            .status()
            .expect("run penumbra");
        assert!(status.success(), "{extra:?}");
    };
    let flags = ["--exposure", "3", "--tonemap", "pbr-neutral"];
    run("plain.exr", &[]);
    run("mapped.exr", &flags);
    run("mapped.png", &flags);
    let read = |f: &str| std::fs::read(dir.path().join(f)).unwrap();
    assert_eq!(
        read("plain.exr"),
        read("mapped.exr"),
        "EXR output stays linear"
    );
    let linear = image::open(dir.path().join("plain.exr"))
        .unwrap()
        .to_rgba32f();
    let png = image::open(dir.path().join("mapped.png"))
        .unwrap()
        .to_rgba8();
    let mut bright = 0;
    for (l, p) in linear.pixels().zip(png.pixels()) {
        let scaled = [l[0], l[1], l[2]].map(|v| v * 3f32.exp2());
        let mapped = penumbra::tonemap::pbr_neutral(scaled);
        for c in 0..3 {
            assert_eq!(p[c], penumbra::output::srgb8(mapped[c]), "{l:?} -> {p:?}");
        }
        bright += usize::from(scaled[0] > 0.76);
    }
    assert!(bright > 100, "{bright} pixels in the compressed range");
}
