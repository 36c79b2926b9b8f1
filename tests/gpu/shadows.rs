//! End-to-end hard-shadow tests. Which points are in shadow is decided here
//! in f64 (the ray from the surface point towards the light against the
//! occluder, analytically), and the colour of every judged pixel is checked
//! against the Phong formula: ambient only in shadow, the full sum outside.
//!
//! Tolerance 1e-3: f32 on the GPU (epsilon 1.2e-7) over camera-relative
//! coordinates below ~200 gives relative errors of a few 1e-7 in l·n and r·v;
//! with shininess 10 and colours below ~2 that is below 1e-5. A wrongly
//! shadowed (or wrongly lit) pixel differs by k_d·I_d·l·n, which the scenes
//! keep well above 1e-3 (grazing light: sin 1.5° · 0.8 ≈ 0.02).

use crate::support;

use glam::DVec3;
use penumbra::render::Image;

const TOL: f64 = 1e-3;

const KA: [f32; 3] = [0.5, 0.6, 0.7];
const KD: [f32; 3] = [0.8, 0.7, 0.6];
const KS: [f32; 3] = [0.4, 0.5, 0.3];
const SHININESS: f64 = 10.0;
const I_A: [f32; 3] = [0.1, 0.1, 0.1];
const I_D: [f32; 3] = [1.0, 0.95, 0.9];
const I_S: [f32; 3] = [0.8, 0.8, 0.8];

fn d(c: [f32; 3]) -> DVec3 {
    DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64)
}

fn v3(v: DVec3) -> String {
    format!("[{}, {}, {}]", v.x, v.y, v.z)
}

fn ambient() -> DVec3 {
    d(KA) * d(I_A)
}

/// Phong colour for a directional light towards `l` (unit), facing normal n,
/// viewer direction v; `visible` false gives the ambient term only.
fn phong(n: DVec3, l: DVec3, v: DVec3, visible: bool) -> DVec3 {
    let mut c = ambient();
    let ln = l.dot(n);
    if ln > 0.0 && visible {
        let r = 2.0 * ln * n - l;
        c += d(KD) * d(I_D) * ln + d(KS) * d(I_S) * r.dot(v).max(0.0).powf(SHININESS);
    }
    c
}

fn scene(camera: &str, objects: &[String], light_dir: DVec3) -> penumbra::scene::Scene {
    support::load_json(&format!(
        r#"{{
  "camera": {camera},
  "shaders": {{ "m": {{ "type": "phong", "ambient": {:?}, "diffuse": {:?}, "specular": {:?}, "shininess": {SHININESS} }} }},
  "objects": [ {} ],
  "lights": [ {{ "type": "directional", "direction": {}, "ambient": {:?}, "diffuse": {:?}, "specular": {:?} }} ]
}}"#,
        KA,
        KD,
        KS,
        objects.join(",\n    "),
        v3(light_dir),
        I_A,
        I_D,
        I_S
    ))
}

fn plane(y: f64, offset: DVec3) -> String {
    format!(
        r#"{{ "type": "plane", "point": {}, "normal": [0, 1, 0], "shader": "m" }}"#,
        v3(offset + DVec3::new(0.0, y, 0.0))
    )
}

fn sphere(c: DVec3, r: f64) -> String {
    format!(
        r#"{{ "type": "sphere", "center": {}, "radius": {r}, "shader": "m" }}"#,
        v3(c)
    )
}

fn triangle(v: [DVec3; 3]) -> String {
    format!(
        r#"{{ "type": "triangle", "vertices": [{}, {}, {}], "shader": "m" }}"#,
        v3(v[0]),
        v3(v[1]),
        v3(v[2])
    )
}

/// Orthographic camera `height` above `centre`, looking straight down, image
/// up = world −Z; the world (x, z) under each pixel centre is exact.
struct Ortho {
    centre: DVec3,
    height: f64,
    half_height: f64,
    w: u32,
    h: u32,
}

impl Ortho {
    fn json(&self) -> String {
        format!(
            r#"{{ "position": {}, "look_at": {}, "up": [0, 0, -1], "projection": "orthographic",
                 "half_height": {}, "width": {}, "height": {} }}"#,
            v3(self.centre + DVec3::new(0.0, self.height, 0.0)),
            v3(self.centre),
            self.half_height,
            self.w,
            self.h
        )
    }

    /// (x, z) of the vertical ray through the centre of pixel (px, py).
    fn xz(&self, px: u32, py: u32) -> (f64, f64) {
        let hw = self.half_height * self.w as f64 / self.h as f64;
        let sx = ((px as f64 + 0.5) / self.w as f64 * 2.0 - 1.0) * hw;
        let sy = (1.0 - (py as f64 + 0.5) / self.h as f64 * 2.0) * self.half_height;
        (self.centre.x + sx, self.centre.z - sy)
    }
}

/// A perspective look-at camera, with the spec's ray through a pixel centre.
struct Persp {
    eye: DVec3,
    target: DVec3,
    fov: f64,
    w: u32,
    h: u32,
}

impl Persp {
    fn json(&self) -> String {
        format!(
            r#"{{ "position": {}, "look_at": {}, "up": [0, 1, 0], "fov": {}, "width": {}, "height": {} }}"#,
            v3(self.eye),
            v3(self.target),
            self.fov,
            self.w,
            self.h
        )
    }

    fn ray(&self, x: u32, y: u32) -> DVec3 {
        let back = (self.eye - self.target).normalize();
        let right = DVec3::Y.cross(back).normalize();
        let up = back.cross(right);
        let hh = (self.fov.to_radians() / 2.0).tan();
        let hw = hh * self.w as f64 / self.h as f64;
        let sx = ((x as f64 + 0.5) / self.w as f64 * 2.0 - 1.0) * hw;
        let sy = (1.0 - (y as f64 + 0.5) / self.h as f64 * 2.0) * hh;
        (-back + sx * right + sy * up).normalize()
    }
}

/// Where a ray from `o` along unit `dir` meets the sphere: `Some(t)` for a hit
/// in front, `None` for a miss; `Err` when the ray grazes the silhouette
/// (within `band`·r), where f32 may decide either way.
fn sphere_hit(o: DVec3, dir: DVec3, c: DVec3, r: f64, band: f64) -> Result<Option<f64>, ()> {
    let f = c - o;
    let along = f.dot(dir);
    let dist = (f - along * dir).length();
    if (dist - r).abs() < band * r {
        return Err(());
    }
    if dist > r {
        return Ok(None);
    }
    let t = along - (r * r - dist * dist).sqrt();
    Ok((t > 0.0).then_some(t))
}

#[derive(Default, Debug)]
struct Counts {
    shadowed: Vec<(u32, u32)>,
    lit_plane: Vec<(u32, u32)>,
    sphere: u32,
}

/// Plane y = 0 with a sphere above it, lit by a directional light travelling
/// along `dir`; every judged pixel checked against the formula with the
/// test's own shadow decision.
fn check_sphere_over_plane(cam: &Ortho, c: DVec3, r: f64, dir: DVec3) -> Counts {
    let l = -dir.normalize();
    let img = support::render(&scene(
        &cam.json(),
        &[plane(0.0, DVec3::ZERO), sphere(c, r)],
        dir,
    ))
    .image;
    let mut counts = Counts::default();
    for py in 0..cam.h {
        for px in 0..cam.w {
            let (x, z) = cam.xz(px, py);
            let o = DVec3::new(x, cam.height + 1.0, z);
            let got = img.at(px, py);
            match sphere_hit(o, -DVec3::Y, c, r, 1e-3) {
                Err(()) => continue,
                Ok(Some(t)) => {
                    // Top of the sphere: nothing lies between it and the light
                    // (the plane is below, the sphere shadows only its far side).
                    let p = o - t * DVec3::Y;
                    let n = (p - c) / r;
                    support::assert_rgb(got, phong(n, l, DVec3::Y, true).to_array(), TOL);
                    counts.sphere += 1;
                }
                Ok(None) => {
                    let p = DVec3::new(x, 0.0, z);
                    // The shadow ray from the plane point towards the light.
                    let Ok(blocker) = sphere_hit(p, l, c, r, 1e-3) else {
                        continue;
                    };
                    let shadowed = blocker.is_some();
                    let want = phong(DVec3::Y, l, DVec3::Y, !shadowed);
                    let what = if shadowed {
                        "in shadow (ambient only)"
                    } else {
                        "lit"
                    };
                    for k in 0..3 {
                        assert!(
                            (got[k] as f64 - want[k]).abs() <= TOL,
                            "plane pixel ({px}, {py}) at ({x:.3}, {z:.3}) should be {what}: got {:?}, want {want:?}",
                            &got[..3]
                        );
                    }
                    if shadowed {
                        counts.shadowed.push((px, py));
                    } else {
                        counts.lit_plane.push((px, py));
                    }
                }
            }
        }
    }
    counts
}

const SPHERE_C: DVec3 = DVec3::new(0.0, 1.0, 0.0);
const SPHERE_R: f64 = 0.6;
const CAM: Ortho = Ortho {
    centre: DVec3::new(-0.3, 0.0, -0.2),
    height: 10.0,
    half_height: 2.0,
    w: 96,
    h: 72,
};

#[test]
fn sphere_casts_a_shadow_on_the_plane() {
    let counts = check_sphere_over_plane(&CAM, SPHERE_C, SPHERE_R, DVec3::new(-1.0, -1.5, -0.6));
    assert!(
        counts.shadowed.len() > 200 && counts.lit_plane.len() > 1000 && counts.sphere > 200,
        "coverage: {} shadowed, {} lit, {} sphere",
        counts.shadowed.len(),
        counts.lit_plane.len(),
        counts.sphere
    );
}

#[test]
fn shadow_moves_away_with_the_light() {
    let before = check_sphere_over_plane(&CAM, SPHERE_C, SPHERE_R, DVec3::new(-1.0, -1.5, -0.6));
    // Light straight from above: the shadow hides exactly under the sphere,
    // so no visible plane pixel is shadowed any more...
    let after = check_sphere_over_plane(&CAM, SPHERE_C, SPHERE_R, DVec3::new(0.0, -1.0, 0.0));
    assert!(after.shadowed.is_empty(), "{:?}", after.shadowed);
    // ...and the pixels that were in shadow are fully lit now.
    let lit: std::collections::HashSet<_> = after.lit_plane.iter().copied().collect();
    let now_lit = before.shadowed.iter().filter(|p| lit.contains(p)).count();
    assert!(
        now_lit > 200 && now_lit * 10 > before.shadowed.len() * 9,
        "{now_lit} of {}",
        before.shadowed.len()
    );
    // Light from the other side: the shadow falls elsewhere.
    let other = check_sphere_over_plane(&CAM, SPHERE_C, SPHERE_R, DVec3::new(1.0, -1.5, 0.8));
    let other_shadow: std::collections::HashSet<_> = other.shadowed.iter().copied().collect();
    assert!(other.shadowed.len() > 100);
    assert!(before.shadowed.iter().all(|p| !other_shadow.contains(p)));
}

/// Whether the point (x, z) lies inside the triangle's (x, z) footprint;
/// `Err` within `margin` (in barycentric units) of an edge.
fn inside_xz(v: &[DVec3; 3], x: f64, z: f64, margin: f64) -> Result<bool, ()> {
    let (a, b, c) = (v[0], v[1], v[2]);
    let det = (b.x - a.x) * (c.z - a.z) - (b.z - a.z) * (c.x - a.x);
    let u = ((x - a.x) * (c.z - a.z) - (z - a.z) * (c.x - a.x)) / det;
    let w = ((b.x - a.x) * (z - a.z) - (b.z - a.z) * (x - a.x)) / det;
    let bary = [1.0 - u - w, u, w];
    if bary.iter().any(|b| b.abs() < margin) {
        return Err(());
    }
    Ok(bary.iter().all(|&b| b > 0.0))
}

/// A triangle 1e-3 above the plane, under light 5° above the horizon: its
/// shadow sticks out ~1e-3·cot 5° ≈ 0.011 beyond its edge, a strip several
/// pixels wide in a zoomed-in top view. Points in that strip must be in
/// shadow: a shadow-ray origin pushed off the plane by more than 1e-3, or a
/// minimum distance of that order, would let light leak under the occluder.
fn check_thin_occluder(height: f64) {
    let gap = 1e-3;
    let tri = [
        DVec3::new(-0.05, gap, -0.05),
        DVec3::new(0.05, gap, -0.04),
        DVec3::new(0.0, gap, 0.06),
    ];
    let elev = 5f64.to_radians();
    let l = (DVec3::new(0.8, 0.0, 0.6) * elev.cos() + DVec3::Y * elev.sin()).normalize();
    let cam = Ortho {
        centre: DVec3::new(-0.01, 0.0, -0.005),
        height,
        half_height: 0.08,
        w: 96,
        h: 72,
    };
    let img = support::render(&scene(
        &cam.json(),
        &[plane(0.0, DVec3::ZERO), triangle(tri)],
        -l,
    ))
    .image;
    let (mut shadowed, mut lit, mut top) = (0, 0, 0);
    for py in 0..cam.h {
        for px in 0..cam.w {
            let (x, z) = cam.xz(px, py);
            let got = img.at(px, py);
            let Ok(on_triangle) = inside_xz(&tri, x, z, 1e-3) else {
                continue;
            };
            if on_triangle {
                support::assert_rgb(got, phong(DVec3::Y, l, DVec3::Y, true).to_array(), TOL);
                top += 1;
                continue;
            }
            // Shadow ray from (x, 0, z): where it crosses the triangle's height.
            let q = DVec3::new(x, 0.0, z) + gap / l.y * l;
            let Ok(blocked) = inside_xz(&tri, q.x, q.z, 1e-3) else {
                continue;
            };
            let want = phong(DVec3::Y, l, DVec3::Y, !blocked);
            let what = if blocked { "in shadow" } else { "lit" };
            for k in 0..3 {
                assert!(
                    (got[k] as f64 - want[k]).abs() <= TOL,
                    "camera {height} up: plane pixel ({px}, {py}) at ({x:.4}, {z:.4}) should be {what}: got {:?}, want {want:?}",
                    &got[..3]
                );
            }
            if blocked {
                shadowed += 1;
            } else {
                lit += 1;
            }
        }
    }
    assert!(
        shadowed > 100 && lit > 1000 && top > 500,
        "coverage: {shadowed} shadowed, {lit} lit, {top} on top"
    );
}

#[test]
fn thin_occluder_casts_a_shadow() {
    check_thin_occluder(1.0);
    check_thin_occluder(10.0);
}

#[test]
fn thin_occluder_casts_a_shadow_seen_from_afar() {
    // The same, with the (orthographic) camera 100 units above the plane.
    check_thin_occluder(100.0);
}

/// Grazing light (1.5° above the horizon) on a plane, a plane made of many
/// coplanar triangles, and the lit side of a sphere: every pixel equals the
/// formula, with no dark speckles. `offset` translates everything (camera
/// included).
fn check_no_acne(offset: DVec3) {
    let elev = 1.5f64.to_radians();
    let l = (DVec3::new(-0.6, 0.0, -0.8) * elev.cos() + DVec3::Y * elev.sin()).normalize();
    let cam = Persp {
        eye: offset + DVec3::new(0.0, 3.0, 3.0),
        target: offset + DVec3::new(0.0, 0.0, -0.5),
        fov: 40.0,
        w: 96,
        h: 72,
    };
    // Infinite plane, then a 12x12 grid of triangle pairs on y = 0 covering
    // the view (corners shared exactly).
    let mut grid = Vec::new();
    let (n, x0, z0, dx, dz) = (12, -6.0, -7.0, 1.0, 11.0 / 12.0);
    for i in 0..n {
        for j in 0..n {
            let p = |a: usize, b: usize| {
                offset + DVec3::new(x0 + (i + a) as f64 * dx, 0.0, z0 + (j + b) as f64 * dz)
            };
            grid.push(triangle([p(0, 0), p(1, 0), p(1, 1)]));
            grid.push(triangle([p(0, 0), p(1, 1), p(0, 1)]));
        }
    }
    for (what, objects) in [("plane", vec![plane(0.0, offset)]), ("triangle grid", grid)] {
        let img = support::render(&scene(&cam.json(), &objects, -l)).image;
        let mut checked = 0;
        for y in 0..cam.h {
            for x in 0..cam.w {
                let dir = cam.ray(x, y);
                assert!(dir.y < -0.1, "test setup: every pixel sees the plane");
                let p = cam.eye - (cam.eye.y - offset.y) / dir.y * dir;
                let want = phong(DVec3::Y, l, -dir, true);
                let got = img.at(x, y);
                for k in 0..3 {
                    assert!(
                        (got[k] as f64 - want[k]).abs() <= TOL,
                        "{what} at offset {offset}: pixel ({x}, {y}) at {:?}: got {:?}, want {want:?}",
                        p - offset,
                        &got[..3]
                    );
                }
                checked += 1;
            }
        }
        assert_eq!(checked, cam.w * cam.h);
    }

    // A sphere's lit side under light from the side, in front of the viewer
    // (so that the Phong lobe is zero at the terminator and the colour is
    // continuous there: no pixel needs to be skipped but the silhouette).
    let c = offset + DVec3::new(0.0, 0.5, -0.5);
    let r = 1.0;
    let l = DVec3::new(1.0, 0.02, 0.3).normalize();
    let img = support::render(&scene(&cam.json(), &[sphere(c, r)], -l)).image;
    let (mut lit, mut dark) = (0, 0);
    for y in 0..cam.h {
        for x in 0..cam.w {
            let dir = cam.ray(x, y);
            let Ok(Some(t)) = sphere_hit(cam.eye, dir, c, r, 1e-3) else {
                continue;
            };
            let p = cam.eye + t * dir;
            let n = (p - c) / r;
            let want = phong(n, l, -dir, true);
            let got = img.at(x, y);
            for k in 0..3 {
                assert!(
                    (got[k] as f64 - want[k]).abs() <= TOL,
                    "sphere at offset {offset}: pixel ({x}, {y}), l·n = {:.5}: got {:?}, want {want:?}",
                    l.dot(n),
                    &got[..3]
                );
            }
            if l.dot(n) > 0.0 {
                lit += 1;
            } else {
                dark += 1;
            }
        }
    }
    assert!(lit > 300 && dark > 300, "{lit} {dark}");
}

#[test]
fn no_shadow_acne_under_grazing_light() {
    check_no_acne(DVec3::ZERO);
}

#[test]
fn no_shadow_acne_far_from_the_origin() {
    check_no_acne(DVec3::new(1e5, 1e5, -1e5));
}

fn count(img: &Image) -> u64 {
    img.pixels.iter().filter(|p| p[3] == 1.0).count() as u64
}

#[test]
fn one_shadow_ray_per_lit_pixel_and_light() {
    let cam = Persp {
        eye: DVec3::new(0.0, 2.0, 0.0),
        target: DVec3::new(0.0, 1.2, -5.0),
        fov: 45.0,
        w: 64,
        h: 48,
    };
    // Pixels whose ray hits the plane y = 0, counted here.
    let mut hits = 0u64;
    for y in 0..cam.h {
        for x in 0..cam.w {
            let dir = cam.ray(x, y);
            assert!(
                dir.y.abs() > 1e-4,
                "test setup: a ray parallel to the plane"
            );
            hits += (dir.y < 0.0) as u64;
        }
    }
    assert!(hits > 500 && hits < 64 * 48 - 300, "test setup: {hits}");
    let above = DVec3::new(0.3, -1.0, 0.2);
    let below = DVec3::new(0.3, 1.0, 0.2);

    let frame = support::render(&scene(&cam.json(), &[plane(0.0, DVec3::ZERO)], above));
    assert_eq!(count(&frame.image), hits);
    assert_eq!(frame.stats.primary_rays, 64 * 48);
    assert_eq!(
        frame.stats.shadow_rays, hits,
        "one shadow ray per lit pixel"
    );

    // A light below the plane: l·n < 0 everywhere, no shadow rays.
    let frame = support::render(&scene(&cam.json(), &[plane(0.0, DVec3::ZERO)], below));
    assert_eq!(frame.stats.shadow_rays, 0);

    // Both: only the light above the plane costs a shadow ray.
    let mut s = scene(&cam.json(), &[plane(0.0, DVec3::ZERO)], above);
    let mut second = s.lights[0];
    second.kind = penumbra::scene::LightKind::Directional {
        direction: below.normalize(),
    };
    s.lights.push(second);
    let frame = support::render(&s);
    assert_eq!(frame.stats.shadow_rays, hits);

    // Sphere over the plane, seen from above: plane pixels plus the sphere
    // pixels facing the light (l·n > 0), counted here.
    let dir = DVec3::new(-1.0, -1.5, -0.6);
    let l = -dir.normalize();
    let frame = support::render(&scene(
        &CAM.json(),
        &[plane(0.0, DVec3::ZERO), sphere(SPHERE_C, SPHERE_R)],
        dir,
    ));
    let (mut sure, mut unsure) = (0u64, 0u64);
    for py in 0..CAM.h {
        for px in 0..CAM.w {
            let (x, z) = CAM.xz(px, py);
            let o = DVec3::new(x, CAM.height + 1.0, z);
            match sphere_hit(o, -DVec3::Y, SPHERE_C, SPHERE_R, 1e-4) {
                Err(()) => unsure += 1,
                Ok(None) => sure += 1, // plane: l·n = l.y > 0
                Ok(Some(t)) => {
                    let ln = l.dot((o - t * DVec3::Y - SPHERE_C) / SPHERE_R);
                    if ln.abs() < 1e-5 {
                        unsure += 1;
                    } else if ln > 0.0 {
                        sure += 1;
                    }
                }
            }
        }
    }
    let got = frame.stats.shadow_rays;
    assert!(
        got >= sure && got <= sure + unsure,
        "shadow rays {got}, want {sure} (+ up to {unsure} ambiguous)"
    );
    assert!(
        sure < (CAM.w * CAM.h) as u64,
        "test setup: some sphere pixels face away"
    );
}
