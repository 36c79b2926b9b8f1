//! End-to-end shading tests: rendered colours against the Phong and
//! Blinn-Phong formulas, evaluated here in f64 with the exact primary ray of
//! each pixel (never against earlier renders).
//!
//! Tolerance: the GPU works in f32 (epsilon 1.2e-7) on camera-relative
//! coordinates of magnitude < 10, so hit points, normals, l, v and r/h carry
//! relative errors of a few 1e-7 (tens of ulps at most after normalisation
//! and the dot products). Colours here are below ~2, and the largest
//! amplification is the specular power n_s = 20, which multiplies the
//! relative error of r·v (or h·n) by 20: a few 1e-5 at worst. 1e-3 leaves a
//! margin of ~30x over that, while any formula error (a wrong vector, a
//! missing factor, ambient scaled by the intensity...) changes colours by
//! far more than 1e-3.

use crate::support;

use glam::{DMat3, DVec3, Vec3};
use penumbra::scene::{
    Camera, Light, LightKind, Mesh, Object, Phong, Projection, Scene, Shader, Shape,
};

const TOL: f64 = 1e-3;

/// A perspective look-at camera as the spec defines it.
#[derive(Clone, Copy)]
struct Cam {
    eye: DVec3,
    target: DVec3,
    up: DVec3,
    fov: f64,
    w: u32,
    h: u32,
}

impl Cam {
    fn ray(&self, x: u32, y: u32) -> (DVec3, DVec3) {
        let back = (self.eye - self.target).normalize();
        let right = self.up.cross(back).normalize();
        let up = back.cross(right);
        let hh = (self.fov.to_radians() / 2.0).tan();
        let hw = hh * self.w as f64 / self.h as f64;
        let sx = ((x as f64 + 0.5) / self.w as f64 * 2.0 - 1.0) * hw;
        let sy = (1.0 - (y as f64 + 0.5) / self.h as f64 * 2.0) * hh;
        (self.eye, (-back + sx * right + sy * up).normalize())
    }

    fn json(&self) -> String {
        format!(
            r#"{{ "position": {}, "look_at": {}, "up": {}, "fov": {}, "width": {}, "height": {} }}"#,
            v3(self.eye),
            v3(self.target),
            v3(self.up),
            self.fov,
            self.w,
            self.h
        )
    }
}

fn v3(v: DVec3) -> String {
    format!("[{}, {}, {}]", v.x, v.y, v.z)
}

fn c3(c: [f32; 3]) -> String {
    format!("[{}, {}, {}]", c[0], c[1], c[2])
}

fn d(c: [f32; 3]) -> DVec3 {
    DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64)
}

/// Phong coefficients of the test material.
#[derive(Clone, Copy)]
struct Mat {
    ka: [f32; 3],
    kd: [f32; 3],
    ks: [f32; 3],
    shininess: f32,
    blinn: bool,
}

impl Mat {
    fn json(&self) -> String {
        format!(
            r#"{{ "type": "{}", "ambient": {}, "diffuse": {}, "specular": {}, "shininess": {} }}"#,
            if self.blinn { "blinn_phong" } else { "phong" },
            c3(self.ka),
            c3(self.kd),
            c3(self.ks),
            self.shininess
        )
    }
}

#[derive(Clone, Copy)]
enum Kind {
    /// Direction the light travels.
    Directional(DVec3),
    Point(DVec3),
}

#[derive(Clone, Copy)]
struct Lamp {
    kind: Kind,
    intensity: f32,
    ambient: [f32; 3],
    diffuse: [f32; 3],
    specular: [f32; 3],
}

impl Lamp {
    fn json(&self) -> String {
        let place = match self.kind {
            Kind::Directional(dir) => format!(r#""type": "directional", "direction": {}"#, v3(dir)),
            Kind::Point(p) => format!(r#""type": "point", "position": {}"#, v3(p)),
        };
        format!(
            r#"{{ {place}, "intensity": {}, "ambient": {}, "diffuse": {}, "specular": {} }}"#,
            self.intensity,
            c3(self.ambient),
            c3(self.diffuse),
            c3(self.specular)
        )
    }

    /// Unit vector towards the light and the falloff at `p`.
    fn at(&self, p: DVec3) -> (DVec3, f64) {
        match self.kind {
            Kind::Directional(dir) => (-dir.normalize(), 1.0),
            Kind::Point(q) => ((q - p).normalize(), 1.0 / (q - p).length_squared()),
        }
    }
}

/// The specular lobe: Phong max(0, r·v)^n, Blinn-Phong max(0, h·n)^n.
fn lobe(m: &Mat, n: DVec3, l: DVec3, v: DVec3) -> f64 {
    let s = m.shininess as f64;
    if m.blinn {
        let h = (l + v).normalize();
        h.dot(n).max(0.0).powf(s)
    } else {
        let r = 2.0 * l.dot(n) * n - l;
        r.dot(v).max(0.0).powf(s)
    }
}

/// The spec's colour at point `p` with facing normal `n`, viewed along `v`
/// (unit, towards the viewer). No occluders in these scenes.
fn expected(m: &Mat, lamps: &[Lamp], p: DVec3, n: DVec3, v: DVec3) -> DVec3 {
    let mut c = DVec3::ZERO;
    for lamp in lamps {
        c += d(m.ka) * d(lamp.ambient);
        let (l, falloff) = lamp.at(p);
        let ln = l.dot(n);
        if ln > 0.0 {
            let i = lamp.intensity as f64 * falloff;
            c += i
                * (d(m.kd) * d(lamp.diffuse) * ln + d(m.ks) * d(lamp.specular) * lobe(m, n, l, v));
        }
    }
    c
}

fn rgb(c: DVec3) -> [f64; 3] {
    c.to_array()
}

const BACKGROUND: [f32; 3] = [0.1, 0.2, 0.3];

/// The sphere of the shading tests, seen from slightly above and to the right.
const CAM: Cam = Cam {
    eye: DVec3::new(0.4, 0.6, 4.5),
    target: DVec3::ZERO,
    up: DVec3::Y,
    fov: 40.0,
    w: 96,
    h: 72,
};
const CENTER: DVec3 = DVec3::new(0.05, -0.1, 0.0);
const RADIUS: f64 = 1.2;

const MAT: Mat = Mat {
    ka: [0.8, 0.6, 1.0],
    kd: [0.6, 0.8, 0.4],
    ks: [0.5, 0.4, 0.9],
    shininess: 20.0,
    blinn: false,
};

/// Lit from the right and above, so the left part of the sphere faces away
/// from the light (l·n < 0) and the highlight is on the visible side.
fn sun(intensity: f32) -> Lamp {
    Lamp {
        kind: Kind::Directional(DVec3::new(-1.0, -0.6, -0.4)),
        intensity,
        ambient: [0.05, 0.02, 0.01],
        diffuse: [0.7, 0.6, 0.5],
        specular: [0.9, 0.8, 0.3],
    }
}

fn sphere_json(m: &Mat, lamps: &[Lamp]) -> String {
    let lights: Vec<String> = lamps.iter().map(Lamp::json).collect();
    format!(
        r#"{{
  "camera": {},
  "background": {},
  "shaders": {{ "m": {} }},
  "objects": [ {{ "type": "sphere", "center": {}, "radius": {RADIUS}, "shader": "m" }} ],
  "lights": [ {} ]
}}"#,
        CAM.json(),
        c3(BACKGROUND),
        m.json(),
        v3(CENTER),
        lights.join(", ")
    )
}

/// What a sphere pixel should be, or None for a background pixel; `Err` for
/// pixels the test does not judge (rays grazing the silhouette, points on the
/// terminator where the specular term jumps).
struct Expect {
    colour: Option<DVec3>,
    ln: f64,
    lobe: f64,
}

fn sphere_pixel(m: &Mat, lamps: &[Lamp], x: u32, y: u32) -> Result<Expect, ()> {
    let (o, dir) = CAM.ray(x, y);
    let f = CENTER - o;
    let along = f.dot(dir);
    let dist2 = (f - along * dir).length_squared();
    let r2 = RADIUS * RADIUS;
    if (dist2.sqrt() - RADIUS).abs() < 1e-3 * RADIUS {
        return Err(());
    }
    if dist2 > r2 {
        return Ok(Expect {
            colour: None,
            ln: 0.0,
            lobe: 0.0,
        });
    }
    let t = along - (r2 - dist2).sqrt();
    let p = o + t * dir;
    let n = (p - CENTER) / RADIUS;
    let v = -dir;
    let (l, _) = lamps[0].at(p);
    let ln = l.dot(n);
    if ln.abs() < 1e-4 {
        return Err(());
    }
    let lb = if ln > 0.0 { lobe(m, n, l, v) } else { 0.0 };
    Ok(Expect {
        colour: Some(expected(m, lamps, p, n, v)),
        ln,
        lobe: lb,
    })
}

/// Checks every judged pixel of a sphere render against the formula; returns
/// (background, unlit, highlight) pixel counts.
fn check_sphere(m: &Mat, lamps: &[Lamp]) -> (u32, u32, u32) {
    let frame = support::render(&support::load_json(&sphere_json(m, lamps)));
    let img = &frame.image;
    let (mut bg, mut dark, mut highlight) = (0, 0, 0);
    for y in 0..CAM.h {
        for x in 0..CAM.w {
            let Ok(e) = sphere_pixel(m, lamps, x, y) else {
                continue;
            };
            let got = img.at(x, y);
            match e.colour {
                None => {
                    // The background colour exactly, alpha 0.
                    assert_eq!(
                        got,
                        [BACKGROUND[0], BACKGROUND[1], BACKGROUND[2], 0.0],
                        "background pixel ({x}, {y})"
                    );
                    bg += 1;
                }
                Some(c) => {
                    assert_eq!(got[3], 1.0, "pixel ({x}, {y}) should hit the sphere");
                    for k in 0..3 {
                        assert!(
                            (got[k] as f64 - c[k]).abs() <= TOL,
                            "pixel ({x}, {y}), l·n = {:.4}, lobe = {:.4}: got {:?}, want {c:?}",
                            e.ln,
                            e.lobe,
                            &got[..3]
                        );
                    }
                    if e.ln < 0.0 {
                        dark += 1;
                    }
                    if e.lobe > 0.5 {
                        highlight += 1;
                    }
                }
            }
        }
    }
    (bg, dark, highlight)
}

#[test]
fn phong_sphere_matches_the_formula() {
    for shininess in [20.0, 1.0] {
        let m = Mat { shininess, ..MAT };
        let (bg, dark, highlight) = check_sphere(&m, &[sun(1.0)]);
        assert!(
            bg > 500 && dark > 50 && highlight > 5,
            "coverage: {bg} background, {dark} unlit, {highlight} highlight"
        );
    }
}

#[test]
fn blinn_phong_sphere_matches_the_formula() {
    for shininess in [1.0, 20.0] {
        let m = Mat {
            shininess,
            blinn: true,
            ..MAT
        };
        let (bg, dark, highlight) = check_sphere(&m, &[sun(1.0)]);
        assert!(
            bg > 500 && dark > 50 && highlight > 5,
            "coverage: {bg} background, {dark} unlit, {highlight} highlight"
        );
    }
}

#[test]
fn unlit_side_gets_exactly_the_ambient_term() {
    // Independent of the specular model: where l·n < 0 the colour is k_a·I_a.
    let img = support::render(&support::load_json(&sphere_json(&MAT, &[sun(1.0)]))).image;
    let amb = d(MAT.ka) * d(sun(1.0).ambient);
    let mut n = 0;
    for y in 0..CAM.h {
        for x in 0..CAM.w {
            if let Ok(Expect {
                colour: Some(_),
                ln,
                ..
            }) = sphere_pixel(&MAT, &[sun(1.0)], x, y)
            {
                if ln < -1e-3 {
                    support::assert_rgb(img.at(x, y), rgb(amb), 1e-6);
                    n += 1;
                }
            }
        }
    }
    assert!(n > 50, "{n}");
}

#[test]
fn intensity_scales_diffuse_and_specular_but_not_ambient() {
    let json1 = sphere_json(&MAT, &[sun(1.0)]);
    let json2 = sphere_json(&MAT, &[sun(2.0)]);
    let (i1, i2) = (
        support::render(&support::load_json(&json1)).image,
        support::render(&support::load_json(&json2)).image,
    );
    // The doubled light also matches the formula everywhere.
    let (_, dark, highlight) = check_sphere(&MAT, &[sun(2.0)]);
    assert!(dark > 50 && highlight > 5);
    let amb = d(MAT.ka) * d(sun(1.0).ambient);
    let (mut lit, mut unlit) = (0, 0);
    for y in 0..CAM.h {
        for x in 0..CAM.w {
            let Ok(Expect {
                colour: Some(_),
                ln,
                ..
            }) = sphere_pixel(&MAT, &[sun(1.0)], x, y)
            else {
                continue;
            };
            let (a, b) = (i1.at(x, y), i2.at(x, y));
            if ln < 0.0 {
                // Ambient only: unchanged by the intensity.
                assert_eq!(&a[..3], &b[..3], "unlit pixel ({x}, {y})");
                unlit += 1;
                continue;
            }
            for k in 0..3 {
                let (da, db) = (a[k] as f64 - amb[k], b[k] as f64 - amb[k]);
                if da > 0.05 {
                    let ratio = db / da;
                    assert!(
                        (ratio - 2.0).abs() < 2e-3,
                        "pixel ({x}, {y}) channel {k}: (I=2 - ambient)/(I=1 - ambient) = {ratio}"
                    );
                    lit += 1;
                }
            }
        }
    }
    assert!(lit > 500 && unlit > 50, "{lit} {unlit}");
}

#[test]
fn lights_add_up() {
    let sun = sun(1.0);
    let lamp = Lamp {
        kind: Kind::Point(DVec3::new(-2.0, 1.5, 2.5)),
        intensity: 6.0,
        ambient: [0.03, 0.04, 0.02],
        diffuse: [0.4, 0.5, 0.9],
        specular: [0.6, 0.2, 0.7],
    };
    let render =
        |lamps: &[Lamp]| support::render(&support::load_json(&sphere_json(&MAT, lamps))).image;
    let (a, b, both) = (render(&[sun]), render(&[lamp]), render(&[sun, lamp]));
    let mut n = 0;
    for y in 0..CAM.h {
        for x in 0..CAM.w {
            let (o, dir) = CAM.ray(x, y);
            let f = CENTER - o;
            let along = f.dot(dir);
            let dist2 = (f - along * dir).length_squared();
            if dist2 > (RADIUS * 0.98) * (RADIUS * 0.98) {
                continue;
            }
            let p = o + (along - (RADIUS * RADIUS - dist2).sqrt()) * dir;
            let nrm = (p - CENTER) / RADIUS;
            // Stay off both terminators, where the specular term jumps.
            if [sun, lamp].iter().any(|l| l.at(p).0.dot(nrm).abs() < 1e-4) {
                continue;
            }
            let want = expected(&MAT, &[sun, lamp], p, nrm, -dir);
            support::assert_rgb(both.at(x, y), rgb(want), TOL);
            let sum = [
                (a.at(x, y)[0] + b.at(x, y)[0]) as f64,
                (a.at(x, y)[1] + b.at(x, y)[1]) as f64,
                (a.at(x, y)[2] + b.at(x, y)[2]) as f64,
            ];
            support::assert_rgb(both.at(x, y), sum, 1e-5);
            n += 1;
        }
    }
    assert!(n > 1000, "{n}");
}

/// Interpolated vertex normals: a quad of two triangles filling the view,
/// with tilted vertex normals, shaded with the normal interpolated at each
/// pixel's barycentric coordinates.
#[test]
fn vertex_normals_are_interpolated() {
    let (w, h) = (80u32, 60u32);
    let cam = Cam {
        eye: DVec3::ZERO,
        target: DVec3::new(0.0, 0.0, -1.0),
        up: DVec3::Y,
        fov: 50.0,
        w,
        h,
    };
    let z = -4.0;
    let corners = [
        DVec3::new(-3.0, -2.5, z),
        DVec3::new(3.0, -2.5, z),
        DVec3::new(3.0, 2.5, z),
        DVec3::new(-3.0, 2.5, z),
    ];
    let normals = [
        DVec3::new(-0.4, -0.3, 1.0).normalize(),
        DVec3::new(0.5, -0.2, 1.0).normalize(),
        DVec3::new(0.3, 0.45, 1.0).normalize(),
        DVec3::new(-0.25, 0.5, 1.0).normalize(),
    ];
    let tris: [[usize; 3]; 2] = [[0, 1, 2], [0, 2, 3]];
    let m = Mat {
        ka: [0.2, 0.1, 0.3],
        kd: [0.7, 0.6, 0.5],
        ks: [0.6, 0.7, 0.2],
        shininess: 8.0,
        blinn: false,
    };
    let lamp = Lamp {
        kind: Kind::Directional(-DVec3::new(0.3, 0.4, 1.0).normalize()),
        intensity: 1.0,
        ambient: [0.1, 0.1, 0.1],
        diffuse: [0.9, 0.8, 0.7],
        specular: [1.0, 0.9, 0.8],
    };
    let phong = |c: [f32; 3]| Vec3::from_array(c);
    let scene = Scene {
        textures: vec![],
        camera: Camera {
            position: cam.eye,
            // Looking along −Z with +Y up: the identity rotation.
            orientation: DMat3::IDENTITY,
            projection: Projection::Perspective { vfov_deg: cam.fov },
            width: w,
            height: h,
        },
        background: Vec3::from_array(BACKGROUND),
        shaders: vec![Shader::Phong(Phong {
            textures: Default::default(),
            ambient: phong(m.ka),
            diffuse: phong(m.kd),
            specular: phong(m.ks),
            shininess: m.shininess,
        })],
        objects: vec![Object {
            maps: Default::default(),
            shape: Shape::Mesh(Mesh {
                uvs: vec![],
                colours: None,
                tangents: None,
                positions: corners.to_vec(),
                normals: Some(normals.to_vec()),
                indices: tris.iter().map(|t| t.map(|i| i as u32)).collect(),
            }),
            shader: 0,
        }],
        lights: vec![Light {
            kind: LightKind::Directional {
                direction: match lamp.kind {
                    Kind::Directional(dir) => dir,
                    Kind::Point(_) => unreachable!(),
                },
            },
            intensity: lamp.intensity,
            ambient: phong(lamp.ambient),
            diffuse: phong(lamp.diffuse),
            specular: phong(lamp.specular),
        }],
    };
    let img = support::render(&scene).image;
    let mut max_vs_flat: f64 = 0.0;
    let mut checked = 0;
    for y in 0..h {
        for x in 0..w {
            let (o, dir) = cam.ray(x, y);
            let p = o + (z - o.z) / dir.z * dir;
            // Barycentric coordinates (u of vertex b, v of vertex c) in the
            // plane z = const, for whichever triangle contains p.
            let mut found = None;
            for t in tris {
                let (a, b, c) = (corners[t[0]], corners[t[1]], corners[t[2]]);
                let (e1, e2, q) = (b - a, c - a, p - a);
                let det = e1.x * e2.y - e1.y * e2.x;
                let u = (q.x * e2.y - q.y * e2.x) / det;
                let v = (e1.x * q.y - e1.y * q.x) / det;
                if u >= 0.0 && v >= 0.0 && u + v <= 1.0 {
                    found = Some((t, u, v));
                    break;
                }
            }
            let (t, u, v) = found.expect("the quad fills the view");
            let n =
                ((1.0 - u - v) * normals[t[0]] + u * normals[t[1]] + v * normals[t[2]]).normalize();
            let want = expected(&m, &[lamp], p, n, -dir);
            support::assert_rgb(img.at(x, y), rgb(want), TOL);
            let flat = expected(&m, &[lamp], p, DVec3::Z, -dir);
            max_vs_flat = max_vs_flat.max((want - flat).abs().max_element());
            checked += 1;
        }
    }
    assert_eq!(checked, w * h);
    // The interpolation matters: flat shading would be far off somewhere.
    assert!(max_vs_flat > 0.1, "{max_vs_flat}");
}

/// Surfaces are two-sided: a plane with its normal pointing up, seen from
/// below, is lit by a light below it and not by a light above it.
#[test]
fn plane_seen_from_below_is_lit_from_below() {
    let cam = Cam {
        eye: DVec3::new(0.3, -2.0, 3.0),
        target: DVec3::new(0.0, 0.0, -2.0),
        up: DVec3::Y,
        fov: 50.0,
        w: 80,
        h: 60,
    };
    let m = Mat {
        ka: [0.3, 0.2, 0.1],
        kd: [0.5, 0.7, 0.9],
        ks: [0.8, 0.6, 0.4],
        shininess: 10.0,
        blinn: true,
    };
    for (light_y, lit) in [(-1.0, true), (1.0, false)] {
        let lamp = Lamp {
            kind: Kind::Point(DVec3::new(0.5, light_y, -1.5)),
            intensity: 3.0,
            ambient: [0.1, 0.15, 0.2],
            diffuse: [1.0, 0.9, 0.8],
            specular: [0.7, 0.8, 0.9],
        };
        let json = format!(
            r#"{{ "camera": {}, "background": {}, "shaders": {{ "m": {} }},
                 "objects": [ {{ "type": "plane", "point": [0, 0, 0], "normal": [0, 1, 0], "shader": "m" }} ],
                 "lights": [ {} ] }}"#,
            cam.json(),
            c3(BACKGROUND),
            m.json(),
            lamp.json()
        );
        let img = support::render(&support::load_json(&json)).image;
        let (mut hits, mut brighter) = (0, 0);
        let amb = d(m.ka) * d(lamp.ambient);
        for y in 0..cam.h {
            for x in 0..cam.w {
                let (o, dir) = cam.ray(x, y);
                if dir.y.abs() < 1e-3 {
                    continue; // near the horizon
                }
                let t = -o.y / dir.y;
                if t <= 0.0 {
                    assert_eq!(img.at(x, y)[3], 0.0, "({x}, {y}) looks away from the plane");
                    continue;
                }
                let p = o + t * dir;
                // The normal facing the viewer (below) is −Y.
                let want = expected(&m, &[lamp], p, -DVec3::Y, -dir);
                support::assert_rgb(img.at(x, y), rgb(want), TOL);
                hits += 1;
                if (want - amb).max_element() > 0.05 {
                    brighter += 1;
                }
            }
        }
        assert!(hits > 1000, "{hits}");
        if lit {
            assert!(
                brighter > 1000,
                "light below should light the underside: {brighter}"
            );
        } else {
            assert_eq!(brighter, 0);
        }
    }
}
