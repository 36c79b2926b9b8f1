//! End-to-end light tests: falloff of point and spot lights, and the absence
//! of falloff for directional lights, against the formulas evaluated here in
//! f64 for the exact world point of each pixel.
//!
//! Tolerance 1e-3 (absolute on colours below ~1.5, or relative on ratios):
//! the GPU's f32 arithmetic (epsilon 1.2e-7) on camera-relative coordinates
//! below 10 gives relative errors of a few 1e-7 in l, d² and l·n; the spot
//! cone's linear ramp multiplies errors of cos θ by 1/(cos inner − cos outer)
//! ≈ 8 here, and squaring by 2 more: still below 1e-5.

use crate::support;

use glam::DVec3;

const TOL: f64 = 1e-3;

fn d(c: [f32; 3]) -> DVec3 {
    DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64)
}

fn v3(v: DVec3) -> String {
    format!("[{}, {}, {}]", v.x, v.y, v.z)
}

/// Orthographic camera 10 above `centre`, looking straight down; image up is
/// world −Z. With odd image sizes the middle pixel's centre is `centre`.
struct Ortho {
    centre: DVec3,
    half_height: f64,
    w: u32,
    h: u32,
}

impl Ortho {
    fn json(&self) -> String {
        format!(
            r#"{{ "position": {}, "look_at": {}, "up": [0, 0, -1], "projection": "orthographic",
                 "half_height": {}, "width": {}, "height": {} }}"#,
            v3(self.centre + DVec3::new(0.0, 10.0, 0.0)),
            v3(self.centre),
            self.half_height,
            self.w,
            self.h
        )
    }

    /// World point on the plane y = centre.y under the centre of pixel (x, y).
    fn world(&self, x: u32, y: u32) -> DVec3 {
        let hw = self.half_height * self.w as f64 / self.h as f64;
        let sx = ((x as f64 + 0.5) / self.w as f64 * 2.0 - 1.0) * hw;
        let sy = (1.0 - (y as f64 + 0.5) / self.h as f64 * 2.0) * self.half_height;
        self.centre + DVec3::new(sx, 0.0, -sy)
    }
}

const KA: [f32; 3] = [1.0, 0.9, 0.8];
const KD: [f32; 3] = [0.8, 0.6, 0.4];
const KS: [f32; 3] = [0.5, 0.7, 0.3];
const SHININESS: f64 = 10.0;
const I_A: [f32; 3] = [0.02, 0.03, 0.01];
const I_D: [f32; 3] = [1.0, 0.9, 0.7];
const I_S: [f32; 3] = [0.6, 0.5, 0.9];

fn scene(camera: &str, light: &str, specular: bool) -> penumbra::scene::Scene {
    let ks = if specular { KS } else { [0.0; 3] };
    support::load_json(&format!(
        r#"{{
  "camera": {camera},
  "shaders": {{ "m": {{ "type": "phong", "ambient": {:?}, "diffuse": {:?}, "specular": {:?}, "shininess": {SHININESS} }} }},
  "objects": [ {{ "type": "plane", "point": [0, 0, 0], "normal": [0, 1, 0], "shader": "m" }} ],
  "lights": [ {{ {light}, "ambient": {:?}, "diffuse": {:?}, "specular": {:?} }} ]
}}"#,
        KA, KD, ks, I_A, I_D, I_S
    ))
}

/// Phong colour on the plane y = 0 (normal +Y, viewed from above) at p for a
/// light in direction l (unit, towards the light) delivering `scale` =
/// intensity × falloff; `v` towards the viewer.
fn phong(p_l: DVec3, scale: f64, v: DVec3, specular: bool) -> DVec3 {
    let n = DVec3::Y;
    let l = p_l;
    let mut c = d(KA) * d(I_A);
    let ln = l.dot(n);
    if ln > 0.0 && scale > 0.0 {
        let r = 2.0 * ln * n - l;
        let spec = if specular {
            d(KS) * d(I_S) * r.dot(v).max(0.0).powf(SHININESS)
        } else {
            DVec3::ZERO
        };
        c += scale * (d(KD) * d(I_D) * ln + spec);
    }
    c
}

#[test]
fn point_light_falls_off_with_the_inverse_square() {
    let cam = Ortho {
        centre: DVec3::ZERO,
        half_height: 3.0,
        w: 65,
        h: 49,
    };
    let (cx, cy) = (32, 24);
    assert_eq!(cam.world(cx, cy), DVec3::ZERO);
    let intensity = 4.0;
    let mut below = Vec::new();
    for height in [1.5, 3.0] {
        let pos = DVec3::new(0.0, height, 0.0);
        let light = format!(
            r#""type": "point", "position": {}, "intensity": {intensity}"#,
            v3(pos)
        );
        let img = support::render(&scene(&cam.json(), &light, false)).image;
        // Every pixel against the formula.
        for y in 0..cam.h {
            for x in 0..cam.w {
                let p = cam.world(x, y);
                let falloff = 1.0 / (pos - p).length_squared();
                let want = phong((pos - p).normalize(), intensity * falloff, DVec3::Y, false);
                support::assert_rgb(img.at(x, y), want.to_array(), TOL);
            }
        }
        below.push(img.at(cx, cy));
    }
    // Directly below: l·n = 1, so the diffuse term is k_d·I_d·I/h²; twice
    // the height gives a quarter.
    let amb = d(KA) * d(I_A);
    for k in 0..3 {
        let (near, far) = (below[0][k] as f64 - amb[k], below[1][k] as f64 - amb[k]);
        assert!(far > 0.01, "test setup: diffuse too dark");
        let want_near = intensity * KD[k] as f64 * I_D[k] as f64 / (1.5 * 1.5);
        assert!(
            (near - want_near).abs() <= TOL * want_near,
            "channel {k}: {near} vs {want_near}"
        );
        let ratio = near / far;
        assert!(
            (ratio / 4.0 - 1.0).abs() < 1e-3,
            "channel {k}: diffuse ratio {ratio}, want 4"
        );
    }
}

#[test]
fn directional_light_has_no_falloff() {
    // A perspective camera 2 above the plane looking towards the horizon sees
    // plane points from ~2 to ~100 units away.
    let camera = r#"{ "position": [0, 2, 0], "look_at": [0, 0.8, -10], "up": [0, 1, 0], "fov": 40, "width": 64, "height": 48 }"#;
    let dir = DVec3::new(0.3, -0.8, -0.5).normalize();
    let light = format!(
        r#""type": "directional", "direction": {}, "intensity": 1.5"#,
        v3(dir)
    );
    let img = support::render(&scene(camera, &light, false)).image;
    let want = phong(-dir, 1.5, DVec3::Y, false);
    let (mut nearest, mut farthest) = ((f64::MAX, (0, 0)), (0.0, (0, 0)));
    // Spec ray through each pixel centre: eye (0, 2, 0), vfov 40.
    let eye = DVec3::new(0.0, 2.0, 0.0);
    let back = (eye - DVec3::new(0.0, 0.8, -10.0)).normalize();
    let right = DVec3::Y.cross(back).normalize();
    let up = back.cross(right);
    let hh = 20f64.to_radians().tan();
    let hw = hh * 64.0 / 48.0;
    for y in 0..48 {
        for x in 0..64 {
            let sx = ((x as f64 + 0.5) / 64.0 * 2.0 - 1.0) * hw;
            let sy = (1.0 - (y as f64 + 0.5) / 48.0 * 2.0) * hh;
            let ray = (-back + sx * right + sy * up).normalize();
            if ray.y > -1e-3 {
                continue; // at or above the horizon
            }
            let dist = -eye.y / ray.y;
            support::assert_rgb(img.at(x, y), want.to_array(), TOL);
            if dist < nearest.0 {
                nearest = (dist, (x, y));
            }
            if dist > farthest.0 {
                farthest = (dist, (x, y));
            }
        }
    }
    assert!(
        farthest.0 > 20.0 * nearest.0,
        "test setup: {nearest:?} {farthest:?}"
    );
    let (a, b) = (
        img.at(nearest.1 .0, nearest.1 .1),
        img.at(farthest.1 .0, farthest.1 .1),
    );
    for k in 0..3 {
        assert!((a[k] - b[k]).abs() < 1e-5, "near {a:?} vs far {b:?}");
    }
}

#[test]
fn spot_light_cone() {
    let cam = Ortho {
        centre: DVec3::new(0.2, 0.0, -0.1),
        half_height: 3.5,
        w: 96,
        h: 72,
    };
    let pos = DVec3::new(0.3, 4.0, -0.2);
    let axis = DVec3::new(0.15, -1.0, 0.1).normalize();
    let (inner, outer) = (20f64.to_radians(), 35f64.to_radians());
    let intensity = 20.0;
    let light = format!(
        r#""type": "spot", "position": {}, "direction": {}, "inner_angle": 20, "outer_angle": 35, "intensity": {intensity}"#,
        v3(pos),
        v3(axis)
    );
    let img = support::render(&scene(&cam.json(), &light, true)).image;
    let (ci, co) = (inner.cos(), outer.cos());
    let amb = d(KA) * d(I_A);
    let (mut full, mut dark, mut between) = (0, 0, 0);
    for y in 0..cam.h {
        for x in 0..cam.w {
            let p = cam.world(x, y);
            let to_light = (pos - p).normalize();
            let cos = axis.dot(-to_light);
            let cone = ((cos - co) / (ci - co)).clamp(0.0, 1.0).powi(2);
            let falloff = cone / (pos - p).length_squared();
            let want = phong(to_light, intensity * falloff, DVec3::Y, true);
            let got = img.at(x, y);
            support::assert_rgb(got, want.to_array(), TOL);
            if cos > ci + 1e-3 {
                // Full inverse-square light, no cone attenuation.
                let unattenuated = phong(
                    to_light,
                    intensity / (pos - p).length_squared(),
                    DVec3::Y,
                    true,
                );
                support::assert_rgb(got, unattenuated.to_array(), TOL);
                full += 1;
            } else if cos < co - 1e-3 {
                // Outside the outer cone: ambient only.
                support::assert_rgb(got, amb.to_array(), 1e-6);
                dark += 1;
            } else if cone > 0.05 && cone < 0.95 {
                // Partially attenuated, and clearly different from both.
                let unattenuated = phong(
                    to_light,
                    intensity / (pos - p).length_squared(),
                    DVec3::Y,
                    true,
                );
                assert!((got[0] as f64 - unattenuated.x).abs() > 10.0 * TOL);
                assert!((got[0] as f64 - amb.x).abs() > 10.0 * TOL);
                between += 1;
            }
        }
    }
    assert!(
        full > 300 && dark > 300 && between > 300,
        "coverage: {full} full, {dark} dark, {between} between"
    );
}

/// More lights than the uniform light block holds (`UNIFORM_LIGHTS`: the
/// hit stage reads the first ones from it and the rest from the storage
/// buffer): every light still counts, against the diffuse sum in f64. The
/// two lights past the block are the brightest, so reading them wrong
/// changes every pixel by far more than the tolerance.
#[test]
fn lights_past_the_uniform_block_count() {
    let n = penumbra::render::layout::UNIFORM_LIGHTS + 2;
    let cam = Ortho {
        centre: DVec3::ZERO,
        half_height: 3.0,
        w: 33,
        h: 25,
    };
    let lights: Vec<(DVec3, f64)> = (0..n)
        .map(|k| {
            let a = k as f64 * 2.399963;
            let pos = DVec3::new(2.0 * a.cos(), 1.5 + 0.01 * k as f64, 2.0 * a.sin());
            let intensity = if k + 2 >= n { 2.0 } else { 0.02 };
            (pos, intensity)
        })
        .collect();
    let json: Vec<String> = lights
        .iter()
        .map(|(pos, i)| {
            format!(
                r#"{{ "type": "point", "position": {}, "intensity": {i}, "ambient": [0, 0, 0], "diffuse": {:?}, "specular": [0, 0, 0] }}"#,
                v3(*pos),
                I_D
            )
        })
        .collect();
    let scene = support::load_json(&format!(
        r#"{{
  "camera": {},
  "shaders": {{ "m": {{ "type": "phong", "ambient": [0, 0, 0], "diffuse": {:?}, "specular": [0, 0, 0], "shininess": 1 }} }},
  "objects": [ {{ "type": "plane", "point": [0, 0, 0], "normal": [0, 1, 0], "shader": "m" }} ],
  "lights": [ {} ]
}}"#,
        cam.json(),
        KD,
        json.join(", ")
    ));
    let img = support::render(&scene).image;
    let diffuse = |p: DVec3, lights: &[(DVec3, f64)]| -> DVec3 {
        lights.iter().fold(DVec3::ZERO, |sum, (pos, i)| {
            let l = (*pos - p).normalize();
            sum + d(KD) * d(I_D) * l.y.max(0.0) * *i / (*pos - p).length_squared()
        })
    };
    let mut differs = 0;
    for y in 0..cam.h {
        for x in 0..cam.w {
            let p = cam.world(x, y);
            let want = diffuse(p, &lights);
            support::assert_rgb(img.at(x, y), want.to_array(), TOL);
            let without = diffuse(p, &lights[..n - 2]);
            differs += usize::from((want - without).x > 10.0 * TOL);
        }
    }
    assert_eq!(
        differs as u32,
        cam.w * cam.h,
        "test setup: the last lights must show"
    );
}
