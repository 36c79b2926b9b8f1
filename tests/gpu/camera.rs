//! End-to-end camera tests: a small bright sphere at a known world point must
//! land where the camera model of the spec puts it. Every prediction is made
//! here, in f64, from the camera's definition (position, look_at/up or
//! yaw/pitch/roll, field of view or orthographic window, image size); the
//! library's `Camera::project` is only cross-checked against it.

use crate::support;

use glam::{DMat3, DVec3};
use penumbra::scene::Scene;

/// How the test camera is oriented, exactly as written in the JSON.
#[derive(Clone, Copy, Debug)]
enum Aim {
    LookAt { target: DVec3, up: DVec3 },
    Euler { yaw: f64, pitch: f64, roll: f64 },
}

#[derive(Clone, Copy, Debug)]
enum Proj {
    /// Vertical field of view, degrees.
    Perspective(f64),
    /// Half height of the window, world units.
    Orthographic(f64),
}

/// The camera as the spec defines it, computed independently of penumbra.
#[derive(Clone, Copy, Debug)]
struct Cam {
    eye: DVec3,
    aim: Aim,
    proj: Proj,
    w: u32,
    h: u32,
}

fn rot_x(deg: f64) -> DMat3 {
    let (s, c) = deg.to_radians().sin_cos();
    DMat3::from_cols(
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(0.0, c, s),
        DVec3::new(0.0, -s, c),
    )
}

fn rot_y(deg: f64) -> DMat3 {
    let (s, c) = deg.to_radians().sin_cos();
    DMat3::from_cols(
        DVec3::new(c, 0.0, -s),
        DVec3::new(0.0, 1.0, 0.0),
        DVec3::new(s, 0.0, c),
    )
}

fn rot_z(deg: f64) -> DMat3 {
    let (s, c) = deg.to_radians().sin_cos();
    DMat3::from_cols(
        DVec3::new(c, s, 0.0),
        DVec3::new(-s, c, 0.0),
        DVec3::new(0.0, 0.0, 1.0),
    )
}

impl Cam {
    /// (right, up, back) unit vectors in world space.
    fn basis(&self) -> (DVec3, DVec3, DVec3) {
        match self.aim {
            Aim::LookAt { target, up } => {
                let back = (self.eye - target).normalize();
                let right = up.cross(back).normalize();
                (right, back.cross(right), back)
            }
            Aim::Euler { yaw, pitch, roll } => {
                let r = rot_y(yaw) * rot_x(pitch) * rot_z(roll);
                (r.x_axis, r.y_axis, r.z_axis)
            }
        }
    }

    /// Half width and half height of the image plane at distance 1
    /// (perspective) or of the window (orthographic).
    fn half_extent(&self) -> (f64, f64) {
        let hh = match self.proj {
            Proj::Perspective(fov) => (fov.to_radians() / 2.0).tan(),
            Proj::Orthographic(h) => h,
        };
        (hh * self.w as f64 / self.h as f64, hh)
    }

    /// The primary ray through the centre of pixel (x, y), row 0 at the top.
    fn ray(&self, x: u32, y: u32) -> (DVec3, DVec3) {
        let (right, up, back) = self.basis();
        let (hw, hh) = self.half_extent();
        let sx = ((x as f64 + 0.5) / self.w as f64 * 2.0 - 1.0) * hw;
        let sy = (1.0 - (y as f64 + 0.5) / self.h as f64 * 2.0) * hh;
        match self.proj {
            Proj::Perspective(_) => (self.eye, (-back + sx * right + sy * up).normalize()),
            Proj::Orthographic(_) => (self.eye + sx * right + sy * up, -back),
        }
    }

    /// Continuous image coordinates (x right, y down; pixel centres at i + 0.5).
    fn project(&self, p: DVec3) -> (f64, f64) {
        let (right, up, back) = self.basis();
        let d = p - self.eye;
        let (lx, ly, lz) = (d.dot(right), d.dot(up), d.dot(back));
        let (sx, sy) = match self.proj {
            Proj::Perspective(_) => {
                assert!(lz < 0.0, "test point must be in front of the camera");
                (lx / -lz, ly / -lz)
            }
            Proj::Orthographic(_) => (lx, ly),
        };
        let (hw, hh) = self.half_extent();
        (
            (sx / hw + 1.0) * 0.5 * self.w as f64,
            (1.0 - sy / hh) * 0.5 * self.h as f64,
        )
    }

    fn json(&self) -> String {
        let v = |v: DVec3| format!("[{}, {}, {}]", v.x, v.y, v.z);
        let aim = match self.aim {
            Aim::LookAt { target, up } => format!("\"look_at\": {}, \"up\": {}", v(target), v(up)),
            Aim::Euler { yaw, pitch, roll } => {
                format!("\"yaw\": {yaw}, \"pitch\": {pitch}, \"roll\": {roll}")
            }
        };
        let proj = match self.proj {
            Proj::Perspective(fov) => format!("\"fov\": {fov}"),
            Proj::Orthographic(h) => {
                format!("\"projection\": \"orthographic\", \"half_height\": {h}")
            }
        };
        format!(
            "{{ \"position\": {}, {aim}, {proj}, \"width\": {}, \"height\": {} }}",
            v(self.eye),
            self.w,
            self.h
        )
    }
}

/// A black scene with one sphere shaded pure white (ambient only: k_a = 1,
/// I_a = 1, no diffuse or specular), so every sphere pixel is exactly 1.
fn sphere_scene(cam: &Cam, center: DVec3, radius: f64) -> Scene {
    let json = format!(
        r#"{{
  "camera": {},
  "background": [0, 0, 0],
  "shaders": {{ "white": {{ "type": "phong", "ambient": [1, 1, 1], "diffuse": [0, 0, 0] }} }},
  "objects": [ {{ "type": "sphere", "center": [{}, {}, {}], "radius": {radius}, "shader": "white" }} ],
  "lights": [ {{ "type": "directional", "direction": [0, -1, 0],
                 "ambient": [1, 1, 1], "diffuse": [0, 0, 0], "specular": [0, 0, 0] }} ]
}}"#,
        cam.json(),
        center.x,
        center.y,
        center.z
    );
    support::load_json(&json)
}

/// Renders the sphere and checks, against the test's own camera model:
/// the library's camera equals ours; `Camera::project` agrees with our
/// projection; the pixel under the projected centre is lit; every pixel whose
/// ray clearly hits (misses) the sphere is lit (background); the lit pixels
/// are centred on the projection. Returns the projected position.
fn check_sphere(cam: &Cam, center: DVec3, radius: f64) -> (f64, f64) {
    let scene = sphere_scene(cam, center, radius);
    let (right, up, back) = cam.basis();
    let lib = scene.camera.orientation;
    for (ours, theirs, name) in [
        (right, lib.x_axis, "right"),
        (up, lib.y_axis, "up"),
        (back, lib.z_axis, "back"),
    ] {
        assert!(
            (ours - theirs).length() < 1e-12,
            "{name}: ours {ours}, library {theirs} ({cam:?})"
        );
    }

    let (px, py) = cam.project(center);
    let (lx, ly) = scene
        .camera
        .project(center)
        .expect("in front of the camera");
    assert!(
        (px - lx).abs() < 1e-9 && (py - ly).abs() < 1e-9,
        "project: ours ({px}, {py}), library ({lx}, {ly})"
    );
    assert!(
        px > 2.0 && py > 2.0 && px < cam.w as f64 - 2.0 && py < cam.h as f64 - 2.0,
        "test setup: ({px}, {py}) off-image"
    );

    let frame = support::render(&scene);
    let img = &frame.image;
    assert_eq!((img.width, img.height), (cam.w, cam.h));
    let centre_px = img.at(px.floor() as u32, py.floor() as u32);
    assert_eq!(
        centre_px,
        [1.0, 1.0, 1.0, 1.0],
        "pixel under the projected centre ({px:.2}, {py:.2})"
    );

    let (mut lit, mut sx, mut sy, mut checked) = (0u32, 0.0, 0.0, 0u32);
    for y in 0..cam.h {
        for x in 0..cam.w {
            let got = img.at(x, y);
            let (o, d) = cam.ray(x, y);
            // Distance of the centre from the ray line, and whether the
            // intersection is in front of the ray origin.
            let f = center - o;
            let along = f.dot(d);
            let dist = (f - along * d).length();
            let in_front = along > 0.0;
            if got[3] == 1.0 {
                lit += 1;
                sx += x as f64 + 0.5;
                sy += y as f64 + 0.5;
            }
            // Rays grazing the silhouette may go either way in f32.
            if (dist - radius).abs() < 1e-3 * radius {
                continue;
            }
            checked += 1;
            let want = if dist < radius && in_front {
                [1.0, 1.0, 1.0, 1.0]
            } else {
                [0.0, 0.0, 0.0, 0.0]
            };
            assert_eq!(got, want, "pixel ({x}, {y}): ray at distance {dist} from the centre, radius {radius}; sphere projects to ({px:.2}, {py:.2})");
        }
    }
    assert!(checked > cam.w * cam.h * 9 / 10, "too many pixels skipped");
    assert!(lit >= 9, "sphere too small to check: {lit} pixels");
    let (cx, cy) = (sx / lit as f64, sy / lit as f64);
    assert!(
        (cx - px).abs() < 0.75 && (cy - py).abs() < 0.75,
        "lit pixels centred at ({cx:.2}, {cy:.2}), projection ({px:.2}, {py:.2})"
    );
    (px, py)
}

fn persp(eye: DVec3, aim: Aim) -> Cam {
    Cam {
        eye,
        aim,
        proj: Proj::Perspective(40.0),
        w: 96,
        h: 72,
    }
}

const FORWARD: Aim = Aim::Euler {
    yaw: 0.0,
    pitch: 0.0,
    roll: 0.0,
};

#[test]
fn sphere_lands_on_projected_pixel_and_follows_camera_translation() {
    let p = DVec3::new(0.7, -0.45, -5.0);
    let cam = persp(DVec3::ZERO, FORWARD);
    let (x0, y0) = check_sphere(&cam, p, 0.12);
    // The known answer, from the definition: local (0.7, -0.45, -5), vfov 40°.
    let t = 20f64.to_radians().tan();
    let want = (
        (0.7 / 5.0 / (t * 96.0 / 72.0) + 1.0) * 48.0,
        (1.0 + 0.45 / 5.0 / t) * 36.0,
    );
    assert!((x0 - want.0).abs() < 1e-9 && (y0 - want.1).abs() < 1e-9);

    // Moving the camera right and up moves the sphere left and down.
    let moved = persp(DVec3::new(0.5, 0.3, 1.0), FORWARD);
    let (x1, y1) = check_sphere(&moved, p, 0.12);
    assert!(
        x1 < x0 - 3.0 && y1 > y0 + 3.0,
        "({x0}, {y0}) -> ({x1}, {y1})"
    );
    // And a camera far from the origin with the scene moved along.
    let off = DVec3::new(2.5e4, -1.0e4, 3.0e4);
    let (x2, y2) = check_sphere(&persp(off, FORWARD), p + off, 0.12);
    assert!((x2 - x0).abs() < 1e-6 && (y2 - y0).abs() < 1e-6);
}

#[test]
fn yaw_then_pitch_then_roll() {
    let eye = DVec3::new(1.0, 0.5, -2.0);
    // Known answers: yaw 90° turns left to look along −X; pitch 90° looks
    // straight up. A point on the view axis lands in the image centre.
    let cam = persp(
        eye,
        Aim::Euler {
            yaw: 90.0,
            pitch: 0.0,
            roll: 0.0,
        },
    );
    let (x, y) = check_sphere(&cam, eye + DVec3::new(-5.0, 0.0, 0.0), 0.15);
    assert!((x - 48.0).abs() < 1e-9 && (y - 36.0).abs() < 1e-9);
    let cam = persp(
        eye,
        Aim::Euler {
            yaw: 0.0,
            pitch: 30.0,
            roll: 0.0,
        },
    );
    let (x, y) = check_sphere(&cam, eye + DVec3::new(0.0, 2.5, -2.5 * 3f64.sqrt()), 0.15);
    assert!((x - 48.0).abs() < 1e-9 && (y - 36.0).abs() < 1e-9);
    // Roll 90° (counter-clockwise) turns the image's up to world −X: a point
    // to the world's left lands in the upper half, centred horizontally.
    let cam = persp(
        eye,
        Aim::Euler {
            yaw: 0.0,
            pitch: 0.0,
            roll: 90.0,
        },
    );
    let (x, y) = check_sphere(&cam, eye + DVec3::new(-1.0, 0.0, -5.0), 0.15);
    assert!((x - 48.0).abs() < 1e-9 && y < 20.0, "({x}, {y})");

    // Combined rotations: each point is placed at known camera-local
    // coordinates (through the test's own R = Ry·Rx·Rz), so a library
    // rotation that differs from the spec moves it off the predicted pixel.
    for (yaw, pitch, roll, local) in [
        (35.0, 0.0, 0.0, DVec3::new(-0.9, 0.3, -5.0)),
        (35.0, 12.0, 0.0, DVec3::new(0.8, -0.6, -4.5)),
        (35.0, 12.0, -20.0, DVec3::new(1.1, 0.5, -5.5)),
        (-150.0, -8.0, 33.0, DVec3::new(0.6, -0.4, -5.0)),
    ] {
        let cam = persp(eye, Aim::Euler { yaw, pitch, roll });
        let (r, u, b) = cam.basis();
        check_sphere(&cam, eye + local.x * r + local.y * u + local.z * b, 0.15);
    }
}

#[test]
fn look_at_with_tilted_up_rolls_the_image() {
    let eye = DVec3::new(0.3, 1.0, 4.0);
    let target = DVec3::new(-0.5, 0.2, -1.0);
    let p = DVec3::new(0.6, 0.9, -1.5);
    let upright = persp(
        eye,
        Aim::LookAt {
            target,
            up: DVec3::Y,
        },
    );
    let (x0, y0) = check_sphere(&upright, p, 0.12);
    let (r, u, b) = upright.basis();
    let tilt = 25f64.to_radians();
    // Tilting up towards the camera's right rolls the camera clockwise, so the
    // image content turns counter-clockwise about the target.
    let tilted_up = DVec3::Y * tilt.cos() + r * tilt.sin();
    let rolled = persp(
        eye,
        Aim::LookAt {
            target,
            up: tilted_up,
        },
    );
    let (x1, y1) = check_sphere(&rolled, p, 0.12);
    // Same distance from the image centre (the target), angle turned by 25°.
    let (ax, ay) = (x0 - 48.0, 36.0 - y0);
    let (bx, by) = (x1 - 48.0, 36.0 - y1);
    let turned = by.atan2(bx) - ay.atan2(ax);
    // The new up is the tilted vector made perpendicular to the view axis:
    // cos·(Y·u)·u + sin·r, so the roll angle is atan2(sin, cos·(Y·u)).
    let roll = tilt.sin().atan2(tilt.cos() * u.dot(DVec3::Y));
    assert!(roll > 0.3, "test setup: roll {roll}");
    assert!(((ax * ax + ay * ay).sqrt() - (bx * bx + by * by).sqrt()).abs() < 1e-6);
    assert!(
        (turned - roll).abs() < 1e-9,
        "image turned by {} degrees, want {}",
        turned.to_degrees(),
        roll.to_degrees()
    );
    assert!(b.dot(DVec3::Y).abs() < 0.9);
}

#[test]
fn row_zero_is_the_top_and_column_zero_the_left() {
    let cam = persp(DVec3::ZERO, FORWARD);
    for (p, upper, right) in [
        (DVec3::new(0.0, 1.0, -5.0), Some(true), None),
        (DVec3::new(0.0, -1.0, -5.0), Some(false), None),
        (DVec3::new(1.2, 0.0, -5.0), None, Some(true)),
        (DVec3::new(-1.2, 0.0, -5.0), None, Some(false)),
    ] {
        let img = support::render(&sphere_scene(&cam, p, 0.2)).image;
        let mut lit = 0;
        for y in 0..img.height {
            for x in 0..img.width {
                if img.at(x, y)[3] == 1.0 {
                    lit += 1;
                    if let Some(upper) = upper {
                        assert_eq!(y < img.height / 2, upper, "{p}: lit pixel ({x}, {y})");
                    }
                    if let Some(right) = right {
                        assert_eq!(x >= img.width / 2, right, "{p}: lit pixel ({x}, {y})");
                    }
                }
            }
        }
        assert!(lit > 10, "{p}: only {lit} lit pixels");
    }
}

#[test]
fn orthographic_projection() {
    let eye = DVec3::new(0.4, 2.0, 3.0);
    let cam = Cam {
        eye,
        aim: Aim::LookAt {
            target: DVec3::new(0.0, 0.0, -1.0),
            up: DVec3::Y,
        },
        proj: Proj::Orthographic(1.5),
        w: 80,
        h: 64,
    };
    let p = DVec3::new(0.9, -0.2, -0.5);
    let (x0, y0) = check_sphere(&cam, p, 0.1);
    // Parallel rays: moving the point along the view axis does not move it
    // in the image, and sliding the camera along its right axis moves it by
    // exactly the pixel equivalent.
    let (r, _, b) = cam.basis();
    let (x1, y1) = check_sphere(&cam, p - 2.0 * b, 0.1);
    assert!((x1 - x0).abs() < 1e-9 && (y1 - y0).abs() < 1e-9);
    let slid = Cam {
        eye: eye + 0.3 * r,
        aim: Aim::LookAt {
            target: DVec3::new(0.0, 0.0, -1.0) + 0.3 * r,
            up: DVec3::Y,
        },
        ..cam
    };
    let (x2, y2) = check_sphere(&slid, p, 0.1);
    let px_per_unit = 64.0 / 3.0;
    assert!((x2 - (x0 - 0.3 * px_per_unit)).abs() < 1e-9 && (y2 - y0).abs() < 1e-9);
}

#[test]
fn non_square_images() {
    for (w, h) in [(160u32, 90u32), (60, 100)] {
        let aim = Aim::Euler {
            yaw: 10.0,
            pitch: -5.0,
            roll: 0.0,
        };
        let cam = Cam {
            eye: DVec3::new(0.0, 0.0, 1.0),
            aim,
            proj: Proj::Perspective(50.0),
            w,
            h,
        };
        let (r, u, b) = cam.basis();
        // Near the left and right edges of the wide image: the vertical fov is
        // fixed, so the horizontal extent follows the aspect ratio.
        let (hw, hh) = cam.half_extent();
        for (fx, fy) in [(-0.8, 0.5), (0.85, -0.7), (0.1, 0.1)] {
            let p = cam.eye + 6.0 * (-b + fx * hw * r + fy * hh * u);
            let (x, y) = check_sphere(&cam, p, 0.15);
            assert!((x - (fx + 1.0) * 0.5 * w as f64).abs() < 1e-9);
            assert!((y - (1.0 - fy) * 0.5 * h as f64).abs() < 1e-9);
        }
        let ortho = Cam {
            proj: Proj::Orthographic(2.0),
            ..cam
        };
        check_sphere(
            &ortho,
            cam.eye - 3.0 * b + 2.5 * r * (w as f64 / h as f64) * 0.5,
            0.15,
        );
    }
}

#[test]
fn one_primary_ray_per_pixel() {
    // Sizes that are and are not multiples of the 8x8 workgroup.
    for (w, h) in [(64u32, 48u32), (61, 47), (1, 1), (9, 130)] {
        let cam = Cam {
            eye: DVec3::ZERO,
            aim: FORWARD,
            proj: Proj::Perspective(40.0),
            w,
            h,
        };
        let frame = support::render(&sphere_scene(&cam, DVec3::new(0.0, 0.0, -5.0), 1.0));
        assert_eq!(frame.stats.primary_rays, w as u64 * h as u64, "{w}x{h}");
        assert_eq!(frame.image.pixels.len(), (w * h) as usize);
    }
}
