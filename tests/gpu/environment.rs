//! The environment's light (docs/materials.md, "Environment") on a sphere,
//! against its definition evaluated here from the camera ray and the
//! sphere's normal of each pixel: `L(ω) = I·g(ω·up)`, `g(u) = a + b·u`.

use crate::support;

use std::f64::consts::PI;

use glam::DVec3;
use penumbra::render::{KernelOptions, Sampling};
use penumbra::scene::{ENVIRONMENT_GRADIENT, ENVIRONMENT_MIXTURE};

const EYE: DVec3 = DVec3::new(0.0, 0.0, 4.0);
const FOV: f64 = 40.0;
const SIZE: u32 = 33;
const INTENSITY: f64 = 1.5;

/// A unit sphere at the origin seen head-on from +Z, with shader `shader`
/// (JSON), under a white environment of `samples` directions (up +Y) only.
fn sphere_json(shader: &str, samples: u32) -> String {
    format!(
        r#"{{
  "camera": {{ "position": [0, 0, {}], "look_at": [0, 0, 0], "up": [0, 1, 0], "fov": {FOV}, "width": {SIZE}, "height": {SIZE} }},
  "background": [0, 0, 0],
  "shaders": {{ "m": {shader} }},
  "objects": [ {{ "type": "sphere", "center": [0, 0, 0], "radius": 1, "shader": "m" }} ],
  "lights": [ {{ "type": "environment", "up": [0, 1, 0], "samples": {samples}, "intensity": {INTENSITY}, "ambient": [0, 0, 0], "diffuse": [1, 1, 1], "specular": [1, 1, 1] }} ]
}}"#,
        EYE.z
    )
}

/// The primary ray through pixel (x, y)'s centre (the look-at camera of the
/// scene format: −Z forward, +Y up), and the unit normal where it meets the
/// sphere, unless it misses or passes within 1e-3 of the silhouette.
fn ray_and_normal(x: u32, y: u32) -> (DVec3, Option<DVec3>) {
    let hh = (FOV.to_radians() / 2.0).tan();
    let sx = ((x as f64 + 0.5) / SIZE as f64 * 2.0 - 1.0) * hh;
    let sy = (1.0 - (y as f64 + 0.5) / SIZE as f64 * 2.0) * hh;
    let d = DVec3::new(sx, sy, -1.0).normalize();
    let along = -EYE.dot(d);
    let miss2 = (EYE + along * d).length_squared();
    if miss2.sqrt() > 1.0 - 1e-3 {
        return (d, None);
    }
    let t = along - (1.0 - miss2).sqrt();
    (d, Some((EYE + t * d).normalize()))
}

/// One pass (pixel centres, no jitter), seeded.
fn one_pass(seed: u32) -> Sampling {
    Sampling {
        spp: 1,
        seed,
        time_budget: None,
    }
}

/// White furnace with the gradient: a Lambert sphere (Phong with `k_d` =
/// 0.8 and no specular, radiance `k_d·E`, no 1/π) takes at normal `n`
/// `E = I·(π·a + (2π/3)·b·(n·up))` (environment_light_on_a_plane derives
/// it). Each pixel is an estimate from N directions of the mixture; with
/// `X = k_d·I·g·cos/p(ω)`, E[X²] = ∫ (k_d·I·g)²·cos²/p over the hemisphere
/// is at most the same integral with `p` replaced by the mixture's uniform
/// and cosine parts alone (its Phong lobes only add density), computed here
/// by the midpoint rule. Every pixel lies within 4σ/√N of `k_d·E`, the
/// mean over the sphere within 4σ/√(N·pixels).
#[test]
fn white_furnace_on_a_lambert_sphere() {
    let (a, b) = ENVIRONMENT_GRADIENT;
    let (wu, wc) = (ENVIRONMENT_MIXTURE.uniform, ENVIRONMENT_MIXTURE.cosine);
    let kd = 0.8;
    let samples = 1024;
    let scene = support::load_json(&sphere_json(
        r#"{"type": "phong", "ambient": [0, 0, 0], "diffuse": [0.8, 0.8, 0.8], "specular": [0, 0, 0], "shininess": 1}"#,
        samples,
    ));
    let frame = support::render_with(&scene, KernelOptions::default(), one_pass(3));
    let up = DVec3::Y;
    let bound_sigma = |n: DVec3, want: f64| {
        let t = n.any_orthonormal_vector();
        let s = n.cross(t);
        let m = 200;
        let mut second = 0.0;
        for i in 0..m {
            let cos = (i as f64 + 0.5) / m as f64;
            let sin = (1.0 - cos * cos).sqrt();
            for j in 0..m {
                let phi = (j as f64 + 0.5) / m as f64 * 2.0 * PI;
                let w = n * cos + (t * phi.cos() + s * phi.sin()) * sin;
                let x = kd * INTENSITY * (a + b * w.dot(up)) * cos;
                second += x * x / (wu / (4.0 * PI) + wc * cos / PI);
            }
        }
        second *= 2.0 * PI / (m * m) as f64;
        (second - want * want).max(0.0).sqrt()
    };
    let (mut sum, mut sum_want, mut sum_var, mut count) = (0.0, 0.0, 0.0, 0usize);
    for y in 0..SIZE {
        for x in 0..SIZE {
            let Some(n) = ray_and_normal(x, y).1 else {
                continue;
            };
            let want = kd * INTENSITY * (PI * a + 2.0 * PI / 3.0 * b * n.dot(up));
            let sigma = bound_sigma(n, want) / (samples as f64).sqrt();
            let got = frame.image.pixels[(y * SIZE + x) as usize][0] as f64;
            assert!(
                (got - want).abs() <= 4.0 * sigma,
                "pixel ({x}, {y}): {got} vs {want} ± {}",
                4.0 * sigma
            );
            sum += got;
            sum_want += want;
            sum_var += sigma * sigma;
            count += 1;
        }
    }
    assert!(count > 400, "{count} pixels on the sphere");
    let bound = 4.0 * sum_var.sqrt() / count as f64;
    assert!(
        ((sum - sum_want) / count as f64).abs() <= bound,
        "mean {} vs {} ± {bound}",
        sum / count as f64,
        sum_want / count as f64
    );
}

/// A smooth metal sphere (glTF metallic-roughness, base colour 1, metallic
/// 1, roughness 0.05) mirrors the environment: each pixel ≈ `L(r)`, with
/// `r` the camera ray reflected about the sphere's normal. Base colour 1
/// makes Fresnel 1; the reflected lobe is about 2α = 0.005 rad wide, so a
/// linear `g` averages over it to `g(r)` within b·(2α)² ≈ 1e-5; Smith's
/// masking at α = 0.0025 takes well under 1 % where n·v ≥ 0.5 (the pixels
/// judged). What remains is the estimate's noise (over these pixels the
/// relative deviation from `L(r)` has a standard deviation of 1.1 % at 1024
/// directions) and the f32 shader's Trowbridge-Reitz peak (relative error
/// about 4·δ(n·h)/α² per sample, of either sign). So each pixel must lie
/// within 5 % of `L(r)` (4.5σ) and the mean of pixel / `L(r)` within 2 %
/// of one. Uniform sampling of the sphere (the environment's former estimator)
/// almost never lands in a lobe of 2·10⁻⁵ sr and fails both by far.
#[test]
fn smooth_metal_sphere_mirrors_the_environment() {
    let (a, b) = ENVIRONMENT_GRADIENT;
    let samples = 1024;
    let scene = support::load_json(&sphere_json(
        r#"{"type": "metallic_roughness", "base_colour": [1, 1, 1], "metallic": 1, "roughness": 0.05}"#,
        samples,
    ));
    let frame = support::render_with(&scene, KernelOptions::default(), one_pass(7));
    let mut judged = 0;
    let mut ratio_sum = 0.0;
    for y in 0..SIZE {
        for x in 0..SIZE {
            let (d, Some(n)) = ray_and_normal(x, y) else {
                continue;
            };
            if n.dot(-d) < 0.5 {
                continue;
            }
            let r = d - 2.0 * d.dot(n) * n;
            let want = INTENSITY * (a + b * r.dot(DVec3::Y));
            let got = frame.image.pixels[(y * SIZE + x) as usize][0] as f64;
            assert!(
                (got - want).abs() <= 0.05 * want,
                "pixel ({x}, {y}): {got} vs L(r) = {want}"
            );
            ratio_sum += got / want;
            judged += 1;
        }
    }
    assert!(judged > 300, "{judged} pixels judged");
    let mean = ratio_sum / judged as f64;
    assert!((mean - 1.0).abs() <= 0.02, "mean of pixel / L(r): {mean}");
}

/// Where the mirror direction is the eye's (the sphere's centre seen
/// head-on), the environment's lobes put samples at `l ≈ v`, so `h ≈ v` and
/// `|v·h|` can round above 1 in f32: the Fresnel term's `1 − |v·h|` must not
/// go negative into WGSL's `pow` (NaN). Every pixel of glTF's BRDF, metal
/// and dielectric at several roughnesses, is finite.
#[test]
fn no_sample_of_glossy_materials_is_nan_where_the_light_comes_from_the_eye() {
    for shader in [
        r#"{"type": "metallic_roughness", "base_colour": [0.8, 0.1, 0.1], "metallic": 0, "roughness": 0.2}"#,
        r#"{"type": "metallic_roughness", "base_colour": [1, 0.8, 0.4], "metallic": 1, "roughness": 0.5}"#,
        r#"{"type": "specular_glossiness", "diffuse": [0.5, 0.5, 0.5], "specular": [0.5, 0.5, 0.5], "glossiness": 0.8}"#,
    ] {
        let scene = support::load_json(&sphere_json(shader, 4096));
        for seed in 0..4 {
            let frame = support::render_with(&scene, KernelOptions::default(), one_pass(seed));
            let bad = frame
                .image
                .pixels
                .iter()
                .filter(|p| p.iter().any(|v| !v.is_finite()))
                .count();
            assert_eq!(bad, 0, "{shader}, seed {seed}: {bad} pixels not finite");
        }
    }
}

/// The environment's samples are evaluated without visibility: they trace
/// no shadow ray and the summary counts none, while a point light beside it
/// still traces one per lit pixel.
#[test]
fn the_environment_traces_and_counts_no_shadow_rays() {
    let shader = r#"{"type": "phong", "ambient": [0, 0, 0], "diffuse": [0.8, 0.8, 0.8], "specular": [0, 0, 0], "shininess": 1}"#;
    let scene = support::load_json(&sphere_json(shader, 64));
    let frame = support::render_with(&scene, KernelOptions::default(), one_pass(3));
    let hits = frame.image.pixels.iter().filter(|p| p[3] == 1.0).count() as u64;
    assert!(hits > 300, "{hits} hits");
    assert_eq!(frame.stats.shadow_rays, 0);
    // A point light at the eye lights every hit pixel (n·l > 0 wherever the
    // camera sees the sphere): one shadow ray each.
    let json = sphere_json(shader, 64).replace(
        r#""lights": ["#,
        r#""lights": [ { "type": "point", "position": [0, 0, 4], "intensity": 1 },"#,
    );
    let scene = support::load_json(&json);
    let frame = support::render_with(&scene, KernelOptions::default(), one_pass(3));
    assert_eq!(frame.stats.shadow_rays, hits);
}
