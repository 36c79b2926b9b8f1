//! glTF's metallic-roughness BRDF (`shaders/shading/metallic_roughness.wgsl`)
//! against the glTF 2.0 specification's Appendix B, written out again here
//! in f64 from the specification (not from the renderer's code), with the
//! exact primary ray of each pixel.
//!
//! Tolerance: the GPU works in f32 on camera-relative coordinates of
//! magnitude < 10, so n, v, l and h carry relative errors of a few 1e-7.
//! The sharpest amplification is Trowbridge-Reitz's denominator near the
//! peak, `(n·h)²(α²−1)+1 ≈ α²`: its relative error is about
//! `4·δ(n·h)/α²`, 2500·δ at roughness 0.2 (α² = 0.0016), a few 1e-4
//! relative; pixel values reach ~100 there. So the test allows
//! `TOL·max(1, |want|)` with TOL = 2e-3, ten times over that estimate,
//! while a wrong term (α for α², a missing π, Fresnel on the wrong
//! vector, metallic and roughness swapped) moves pixels by far more.

use crate::support;

use glam::DVec3;

const TOL: f64 = 2e-3;
const PI: f64 = std::f64::consts::PI;

/// glTF 2.0 Appendix B, B.3.2–B.3.5: the BRDF for unit n, l, v.
fn gltf_brdf(n: DVec3, l: DVec3, v: DVec3, c: DVec3, metallic: f64, roughness: f64) -> DVec3 {
    let h = (l + v).normalize();
    let chi = |x: f64| if x > 0.0 { 1.0 } else { 0.0 };
    let alpha = roughness * roughness;
    let a2 = alpha * alpha;
    let nh = n.dot(h);
    let d = a2 * chi(nh) / (PI * (nh * nh * (a2 - 1.0) + 1.0).powi(2));
    let g = |x: f64| x.abs() + (a2 + (1.0 - a2) * x * x).sqrt();
    let vis = chi(h.dot(l)) * chi(h.dot(v)) / (g(n.dot(l)) * g(n.dot(v)));
    let specular = vis * d;
    let schlick = (1.0 - v.dot(h).abs()).powi(5);
    let metal = specular * (c + (DVec3::ONE - c) * schlick);
    let fresnel = 0.04 + 0.96 * schlick;
    let dielectric = c / PI * (1.0 - fresnel) + DVec3::splat(specular * fresnel);
    dielectric * (1.0 - metallic) + metal * metallic
}

const EYE: DVec3 = DVec3::new(0.0, 0.0, 4.0);
const FOV: f64 = 40.0;
/// Odd, so that the centre pixel's ray is the axis.
const SIZE: u32 = 65;
const RADIUS: f64 = 1.0;
const BASE: [f64; 3] = [0.9, 0.6, 0.3];
const INTENSITY: f64 = 2.0;

/// The scene: a sphere at the origin seen head-on from +Z, lit by a
/// directional light travelling along −Z (from behind the camera).
fn sphere_json(metallic: f64, roughness: f64) -> String {
    format!(
        r#"{{
  "camera": {{ "position": [0, 0, {}], "look_at": [0, 0, 0], "up": [0, 1, 0], "fov": {FOV}, "width": {SIZE}, "height": {SIZE} }},
  "background": [0, 0, 0],
  "shaders": {{ "m": {{ "type": "metallic_roughness", "base_colour": [{}, {}, {}], "metallic": {metallic}, "roughness": {roughness} }} }},
  "objects": [ {{ "type": "sphere", "center": [0, 0, 0], "radius": {RADIUS}, "shader": "m" }} ],
  "lights": [ {{ "type": "directional", "direction": [0, 0, -1], "intensity": {INTENSITY}, "ambient": [0, 0, 0], "diffuse": [1, 1, 1], "specular": [1, 1, 1] }} ]
}}"#,
        EYE.z, BASE[0], BASE[1], BASE[2]
    )
}

/// The primary ray through pixel (x, y)'s centre (the look-at camera of the
/// scene format: −Z forward, +Y up).
fn ray(x: u32, y: u32) -> DVec3 {
    let hh = (FOV.to_radians() / 2.0).tan();
    let sx = ((x as f64 + 0.5) / SIZE as f64 * 2.0 - 1.0) * hh;
    let sy = (1.0 - (y as f64 + 0.5) / SIZE as f64 * 2.0) * hh;
    DVec3::new(sx, sy, -1.0).normalize()
}

/// The expected colour of pixel (x, y), `None` off the sphere and
/// `Err` within 1e-3 of its silhouette (not judged).
fn expected(x: u32, y: u32, metallic: f64, roughness: f64) -> Result<Option<DVec3>, ()> {
    let dir = ray(x, y);
    let along = -EYE.dot(dir);
    let dist2 = (-EYE - along * dir).length_squared();
    if (dist2.sqrt() - RADIUS).abs() < 1e-3 {
        return Err(());
    }
    if dist2 > RADIUS * RADIUS {
        return Ok(None);
    }
    let p = EYE + (along - (RADIUS * RADIUS - dist2).sqrt()) * dir;
    let n = p / RADIUS;
    let l = DVec3::Z;
    let f = gltf_brdf(n, l, -dir, DVec3::from(BASE), metallic, roughness);
    Ok(Some(f * INTENSITY * n.dot(l)))
}

/// Renders the sphere and checks every judged pixel; returns the largest
/// expected value met (to show the highlight was judged).
fn check(metallic: f64, roughness: f64) -> f64 {
    let img = support::render(&support::load_json(&sphere_json(metallic, roughness))).image;
    let (mut judged, mut peak) = (0, 0.0f64);
    for y in 0..SIZE {
        for x in 0..SIZE {
            let Ok(want) = expected(x, y, metallic, roughness) else {
                continue;
            };
            let got = img.at(x, y);
            let Some(want) = want else {
                assert_eq!(got, [0.0, 0.0, 0.0, 0.0], "background pixel ({x}, {y})");
                continue;
            };
            judged += 1;
            for k in 0..3 {
                peak = peak.max(want[k]);
                let tol = TOL * want[k].abs().max(1.0);
                assert!(
                    (got[k] as f64 - want[k]).abs() <= tol,
                    "metallic {metallic}, roughness {roughness}, pixel ({x}, {y}): got {:?}, want {want:?}",
                    &got[..3]
                );
            }
        }
    }
    assert!(judged > 1000, "{judged} sphere pixels judged");
    peak
}

#[test]
fn metal_and_dielectric_spheres_match_the_specification() {
    for roughness in [0.2, 0.5, 1.0] {
        for metallic in [0.0, 1.0] {
            let peak = check(metallic, roughness);
            eprintln!("metallic {metallic}, roughness {roughness}: peak {peak:.4}");
        }
    }
    // A half-metal mixes the two.
    check(0.5, 0.5);
}

/// Metal and dielectric of the same base colour differ as the BRDF says:
/// at the centre pixel (n = v = l, so v·h = 1 and Fresnel is c for the
/// metal, 0.04 for the dielectric) the metal's colour is c·D·V·I and the
/// dielectric's 0.96·c/π·I + 0.04·D·V·I, with D·V = 1/(π·α²)·1/4 there.
#[test]
fn metal_and_dielectric_differ_at_the_centre_as_the_brdf_says() {
    let roughness: f64 = 0.5;
    let a2 = roughness.powi(4);
    // D(n·h = 1) = α²/(π·α⁴) = 1/(π·α²); V(n·l = n·v = 1) = 1/(2·2) = 1/4.
    let dv = 1.0 / (PI * a2) / 4.0;
    let c = DVec3::from(BASE);
    let metal = c * dv * INTENSITY;
    let dielectric = (0.96 * c / PI + DVec3::splat(0.04 * dv)) * INTENSITY;
    let centre = SIZE / 2;
    let mut got = Vec::new();
    for (metallic, want) in [(1.0, metal), (0.0, dielectric)] {
        let img = support::render(&support::load_json(&sphere_json(metallic, roughness))).image;
        // Pixel (32, 32)'s ray is the axis: n = v = l there.
        let exact = expected(centre, centre, metallic, roughness)
            .unwrap()
            .unwrap();
        for k in 0..3 {
            assert!(
                (exact[k] - want[k]).abs() <= 1e-12 * want[k],
                "metallic {metallic}: {exact:?} vs closed form {want:?}"
            );
        }
        let g = img.at(centre, centre);
        support::assert_rgb(g, exact.to_array(), TOL * exact.max_element());
        got.push(g);
    }
    // The metal's highlight is tinted by c (red/blue as c's), the
    // dielectric adds a white highlight to its tinted diffuse part: its
    // red/blue ratio is below c's.
    let ratio = |g: [f32; 4]| g[0] as f64 / g[2] as f64;
    assert!((ratio(got[0]) - BASE[0] / BASE[2]).abs() < 1e-3, "{got:?}");
    assert!(
        (ratio(got[1]) - dielectric.x / dielectric.z).abs() < 1e-3,
        "{got:?}"
    );
    assert!(ratio(got[1]) < 0.8 * BASE[0] / BASE[2], "{got:?}");
}
