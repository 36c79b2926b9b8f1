//! User shaders (WGSL files, issue 13) rendered end to end: scenes are
//! written as JSON with their shader files into a temporary folder and go
//! through the real loader, then through the GPU renderer. Every expected
//! colour is computed here on the host, in f64, from the shader's formula and
//! the exact primary ray of the pixel, never from an earlier render.
//!
//! Tolerances (checked per channel):
//! - Colours that are products and sums of parameters and light colours
//!   only (ambient terms, constants, encoded parameters) are exact or
//!   within a few f32 roundings: `EXACT` = 0 or `SUM_TOL` = 1e-6 for values
//!   below 2.
//! - Colours that depend on the hit point (a point light's direction and
//!   1/d² falloff, `to_eye`, `position`) carry the GPU's f32 error of the
//!   primary ray and of the plane intersection: the ray direction is good to
//!   a few 1e-7 (relative), which moves the hit point by about
//!   t·1e-7/cos θ ≈ 1e-6 at the distances (t < 6) and view angles (cos θ >
//!   0.5) of these scenes; 1/d² doubles the relative error. `F32_TOL` =
//!   2e-5 is about 10× that estimate (~160 ulps at 1.0), and the maximum
//!   error measured on lavapipe is reported in the failure messages. A
//!   formula error (a missing factor, a wrong vector, a camera-absolute
//!   position) changes colours by far more.

use crate::support;

use std::path::Path;

use glam::DVec3;
use penumbra::loaders::{load_scene, LoadOptions};
use penumbra::render::Image;
use serde_json::{json, Value};

/// Exact: a value copied or multiplied by 1.0 in f32.
const EXACT: f64 = 0.0;
/// Sums of a few f32 products of magnitude < 2.
const SUM_TOL: f64 = 1e-6;
/// Values computed from the f32 hit point (see the module comment).
const F32_TOL: f64 = 2e-5;

/// A perspective look-at camera, as `scenes/README.md` defines it.
#[derive(Clone, Copy)]
struct Cam {
    eye: DVec3,
    look_at: DVec3,
    fov: f64,
    w: u32,
    h: u32,
}

impl Cam {
    /// The primary ray through the centre of pixel (x, y): origin and unit
    /// direction (up is +Y).
    fn ray(&self, x: u32, y: u32) -> (DVec3, DVec3) {
        let back = (self.eye - self.look_at).normalize();
        let right = DVec3::Y.cross(back).normalize();
        let up = back.cross(right);
        let half_h = (self.fov.to_radians() / 2.0).tan();
        let half_w = half_h * self.w as f64 / self.h as f64;
        let sx = ((x as f64 + 0.5) / self.w as f64 * 2.0 - 1.0) * half_w;
        let sy = (1.0 - (y as f64 + 0.5) / self.h as f64 * 2.0) * half_h;
        (self.eye, (-back + sx * right + sy * up).normalize())
    }

    fn json(&self) -> Value {
        json!({
            "position": self.eye.to_array(),
            "look_at": self.look_at.to_array(),
            "up": [0, 1, 0],
            "fov": self.fov,
            "width": self.w,
            "height": self.h
        })
    }

    /// Where the ray of pixel (x, y) meets the plane y = 0 (world space).
    fn on_ground(&self, x: u32, y: u32) -> DVec3 {
        let (o, d) = self.ray(x, y);
        assert!(d.y < -0.1, "pixel ({x}, {y}) must look down at the ground");
        o + (-o.y / d.y) * d
    }

    fn pixels(&self) -> impl Iterator<Item = (u32, u32)> + '_ {
        (0..self.h).flat_map(move |y| (0..self.w).map(move |x| (x, y)))
    }
}

/// Looking down at the ground plane y = 0 steeply enough that every pixel
/// sees it (the top row looks about 30° below the horizon).
const GROUND_CAM: Cam = Cam {
    eye: DVec3::new(0.3, 4.0, 2.0),
    look_at: DVec3::new(0.0, 0.0, -0.5),
    fov: 50.0,
    w: 48,
    h: 36,
};

const BACKGROUND: [f64; 3] = [0.1, 0.2, 0.3];

/// A scene of the ground plane with `shader`, seen by `cam`.
fn ground_scene(cam: &Cam, shaders: Value, shader: &str, lights: Value) -> Value {
    json!({
        "camera": cam.json(),
        "background": BACKGROUND,
        "shaders": shaders,
        "objects": [{"type": "plane", "point": [0, 0, 0], "normal": [0, 1, 0], "shader": shader}],
        "lights": lights
    })
}

/// Writes `scene` and the shader `files` (name, text) to a fresh folder,
/// loads it with the JSON loader and renders it.
fn render(scene: &Value, files: &[(&str, &str)]) -> Image {
    let dir = tempfile::tempdir().expect("tempdir");
    for (name, text) in files {
        std::fs::write(dir.path().join(name), text).expect("write shader");
    }
    let path = dir.path().join("scene.json");
    std::fs::write(&path, serde_json::to_string_pretty(scene).unwrap()).unwrap();
    let loaded = load_scene(&path, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    support::render(&loaded.scene).image
}

/// Checks `want` at every pixel where it gives a colour; all are hits.
/// Returns the largest error seen.
#[track_caller]
fn check(img: &Image, cam: &Cam, tol: f64, mut want: impl FnMut(u32, u32) -> Option<DVec3>) -> f64 {
    let mut worst = 0.0f64;
    let mut judged = 0;
    for (x, y) in cam.pixels() {
        let Some(c) = want(x, y) else { continue };
        let got = img.at(x, y);
        assert_eq!(got[3], 1.0, "pixel ({x}, {y}) should be a hit");
        for k in 0..3 {
            let err = (got[k] as f64 - c[k]).abs();
            worst = worst.max(err);
            assert!(
                err <= tol,
                "pixel ({x}, {y}) channel {k}: got {:?}, want {c:?} (tol {tol})",
                &got[..3]
            );
        }
        judged += 1;
    }
    assert!(judged > 100, "only {judged} pixels judged");
    worst
}

/// `p.base * l.intensity * dot(l.to_light, s.normal)`: the example.
const LAMBERT: &str = "\
// The seminar's diffuse term with the light's colour left out.
struct Params {
    base: vec3<f32>,
}

fn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32> {
    return p.base * l.intensity * dot(l.to_light, s.normal);
}
";

const BASE: [f64; 3] = [0.9, 0.3, 0.2];

fn lambert_scene(light: Value) -> Value {
    ground_scene(
        &GROUND_CAM,
        json!({"lambert": {"type": "wgsl", "file": "lambert.wgsl", "params": {"base": BASE}}}),
        "lambert",
        json!([light]),
    )
}

#[test]
fn a_user_shader_renders_its_formula_under_a_directional_light() {
    // The light travels along `dir`: to_light is at 60° from the normal.
    let theta = 60f64.to_radians();
    let dir = DVec3::new(-theta.sin() * 0.6, -theta.cos(), -theta.sin() * 0.8);
    let intensity = 0.75;
    let light = json!({"type": "directional", "direction": dir.to_array(), "intensity": intensity,
                       "ambient": [0.2, 0.2, 0.2], "diffuse": [0.1, 0.5, 1.0]});
    let img = render(&lambert_scene(light), &[("lambert.wgsl", LAMBERT)]);
    // cos 60° = 0.5 everywhere on the plane; the light's colours and
    // ambient do not enter this shader, and there is no `ambient`.
    let want = DVec3::from_array(BASE) * intensity * 0.5;
    check(&img, &GROUND_CAM, SUM_TOL, |_, _| Some(want));
}

#[test]
fn a_user_shader_renders_its_formula_under_a_point_light() {
    let q = DVec3::new(0.7, 1.5, -0.8);
    let intensity = 5.0;
    let light = json!({"type": "point", "position": q.to_array(), "intensity": intensity,
                       "ambient": [0.2, 0.2, 0.2]});
    let img = render(&lambert_scene(light), &[("lambert.wgsl", LAMBERT)]);
    let worst = check(&img, &GROUND_CAM, F32_TOL, |x, y| {
        let p = GROUND_CAM.on_ground(x, y);
        let to_light = q - p;
        let falloff = 1.0 / to_light.length_squared();
        let cos = to_light.normalize().dot(DVec3::Y);
        Some(DVec3::from_array(BASE) * (intensity * falloff * cos))
    });
    eprintln!("point light: largest error {worst:e}");
    // The pixels differ: the falloff and angle vary over the plane.
    assert_ne!(img.at(0, 0), img.at(GROUND_CAM.w - 1, GROUND_CAM.h - 1));
}

/// Shows `to_eye` (mode 0) or `position` (mode 1) as the colour.
const PROBE: &str = "\
struct Params {
    mode: u32,
}

fn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32> {
    if p.mode == 0u {
        return s.to_eye;
    }
    return s.position;
}
";

#[test]
fn to_eye_and_position_reach_the_shader() {
    let cam = Cam {
        eye: DVec3::new(1.5, 3.0, 4.0),
        look_at: DVec3::new(0.5, 0.0, 0.0),
        ..GROUND_CAM
    };
    // One sample straight down: `shade` runs once per pixel.
    let lights = json!([{"type": "directional", "direction": [0, -1, 0], "intensity": 1}]);
    let probe = |mode: u32| {
        let shaders =
            json!({"probe": {"type": "wgsl", "file": "probe.wgsl", "params": {"mode": mode}}});
        render(
            &ground_scene(&cam, shaders, "probe", lights.clone()),
            &[("probe.wgsl", PROBE)],
        )
    };
    // to_eye is the unit vector from the point back to the camera.
    let worst = check(&probe(0), &cam, F32_TOL, |x, y| Some(-cam.ray(x, y).1));
    eprintln!("to_eye: largest error {worst:e}");
    // The position is camera-relative: the camera sits at the origin.
    let img = probe(1);
    let worst = check(&img, &cam, F32_TOL, |x, y| {
        Some(cam.on_ground(x, y) - cam.eye)
    });
    eprintln!("position: largest error {worst:e}");
    // On the plane y = 0 every point is at height −eye.y relative to the camera.
    for (x, y) in [(0, 0), (cam.w / 2, cam.h / 2), (cam.w - 1, cam.h - 1)] {
        assert!((img.at(x, y)[1] as f64 + cam.eye.y).abs() <= F32_TOL);
    }
}

/// Shows one more input per mode: the light's colours, both normals, the
/// texture coordinates, the direction to the light and the intensity.
const INPUTS: &str = "\
struct Params {
    mode: u32,
}

fn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32> {
    switch p.mode {
        case 0u: { return l.diffuse; }
        case 1u: { return l.specular; }
        case 2u: { return s.normal; }
        case 3u: { return s.geometric_normal; }
        case 4u: { return vec3<f32>(s.uv, 1.0); }
        case 5u: { return l.to_light; }
        default: { return vec3<f32>(l.intensity); }
    }
}
";

#[test]
fn the_light_colours_normals_and_uv_reach_the_shader() {
    // The plane's normal points down, away from the camera above it: both
    // normals reach the shader facing the viewer, (0, 1, 0), and the light
    // from above lights it.
    let (diffuse, specular) = ([0.25, 0.5, 1.0], [1.0, 0.75, 0.125]);
    let dir = DVec3::new(0.3, -1.0, 0.2);
    let intensity = 0.625;
    let lights = json!([{"type": "directional", "direction": dir.to_array(), "intensity": intensity,
                         "diffuse": diffuse, "specular": specular, "ambient": [0.5, 0.5, 0.5]}]);
    let to_light = -dir.normalize();
    let expect = [
        (DVec3::from_array(diffuse), EXACT),
        (DVec3::from_array(specular), EXACT),
        (DVec3::Y, EXACT),
        (DVec3::Y, EXACT),
        // A plane's planar coordinates (checked per pixel below).
        (DVec3::Z, F32_TOL),
        (to_light, SUM_TOL),
        (DVec3::splat(intensity), EXACT),
    ];
    for (mode, (want, tol)) in expect.into_iter().enumerate() {
        let scene = json!({
            "camera": GROUND_CAM.json(),
            "background": BACKGROUND,
            "shaders": {"probe": {"type": "wgsl", "file": "inputs.wgsl", "params": {"mode": mode}}},
            "objects": [{"type": "plane", "point": [0, 0, 0], "normal": [0, -1, 0], "shader": "probe"}],
            "lights": lights
        });
        let img = render(&scene, &[("inputs.wgsl", INPUTS)]);
        if mode == 4 {
            // The normal (0, −1, 0) has the axes e_u = (−1, 0, 0) and
            // e_v = (0, 0, 1) (penumbra::scene::texture): uv = (−x, z).
            check(&img, &GROUND_CAM, tol, |x, y| {
                let p = GROUND_CAM.on_ground(x, y);
                Some(DVec3::new(-p.x, p.z, 1.0))
            });
            continue;
        }
        check(&img, &GROUND_CAM, tol, |_, _| Some(want));
    }
}

/// An `ambient` term (k · light ambient) and a `shade` that adds nothing.
const AMBIENT: &str = "\
struct Params {
    k: vec3<f32>,
}

fn ambient(s: Surface, light_ambient: vec3<f32>, p: Params) -> vec3<f32> {
    return p.k * light_ambient;
}

fn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32> {
    return vec3<f32>(0.0);
}
";

/// No `ambient`: only `shade`, which adds nothing either.
const NO_AMBIENT: &str = "\
fn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32> {
    return vec3<f32>(0.0);
}
";

#[test]
fn ambient_is_added_once_per_light_and_a_file_without_it_adds_nothing() {
    // A directional light from above, a point light below the ground (it
    // reaches no point, yet its ambient counts), a rectangle of 100 samples
    // (two chunks of tiles::MAX_CHUNK: ambient must still count once) and a
    // sphere light of 16 samples.
    let ambients = [
        [0.05, 0.1, 0.15],
        [0.2, 0.01, 0.03],
        [0.125, 0.25, 0.0625],
        [0.07, 0.02, 0.3],
    ];
    let lights = json!([
        {"type": "directional", "direction": [0.2, -1, 0.1], "ambient": ambients[0]},
        {"type": "point", "position": [0, -2, 0], "intensity": 3, "ambient": ambients[1]},
        {"type": "rect", "corner": [-1, 3, -1], "edge1": [0, 0, 2], "edge2": [2, 0, 0],
         "intensity": 4, "samples": 100, "ambient": ambients[2]},
        {"type": "sphere", "center": [1, 2, 0], "radius": 0.3, "intensity": 2, "samples": 16,
         "ambient": ambients[3]}
    ]);
    let k = [0.5, 1.5, 0.75];
    let shaders = json!({"amb": {"type": "wgsl", "file": "ambient.wgsl", "params": {"k": k}}});
    let img = render(
        &ground_scene(&GROUND_CAM, shaders, "amb", lights.clone()),
        &[("ambient.wgsl", AMBIENT)],
    );
    let sum = ambients
        .iter()
        .fold(DVec3::ZERO, |acc, a| acc + DVec3::from_array(*a));
    let want = DVec3::from_array(k) * sum;
    check(&img, &GROUND_CAM, SUM_TOL, |_, _| Some(want));

    let shaders = json!({"none": {"type": "wgsl", "file": "none.wgsl"}});
    let img = render(
        &ground_scene(&GROUND_CAM, shaders, "none", lights),
        &[("none.wgsl", NO_AMBIENT)],
    );
    check(&img, &GROUND_CAM, EXACT, |_, _| Some(DVec3::ZERO));
}

/// A flat colour through `ambient` (light ambient 1, so exact and the same
/// lit or in shadow).
const FLAT: &str = "\
struct Params {
    base: vec3<f32>,
}

fn ambient(s: Surface, light_ambient: vec3<f32>, p: Params) -> vec3<f32> {
    return p.base * light_ambient;
}

fn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32> {
    return vec3<f32>(0.0);
}
";

/// Another flat colour, from two parameters of another file.
const TINTED: &str = "\
struct Params {
    tint: vec3<f32>,
    gain: f32,
}

fn ambient(s: Surface, light_ambient: vec3<f32>, p: Params) -> vec3<f32> {
    return p.tint * p.gain * light_ambient;
}

fn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32> {
    return vec3<f32>(0.0);
}
";

#[test]
fn materials_share_a_file_and_a_checker_selects_user_shaders() {
    let cam = GROUND_CAM;
    let (warm, cold, tint, gain) = ([1.0, 0.5, 0.25], [0.0, 0.5, 1.0], [0.5, 0.25, 0.75], 2.0);
    let center = DVec3::new(0.3, 0.6, -0.6);
    let radius = 0.6;
    let scene = json!({
        "camera": cam.json(),
        "background": BACKGROUND,
        "shaders": {
            "warm": {"type": "wgsl", "file": "flat.wgsl", "params": {"base": warm}},
            "cold": {"type": "wgsl", "file": "flat.wgsl", "params": {"base": cold}},
            "tinted": {"type": "wgsl", "file": "tinted.wgsl", "params": {"tint": tint, "gain": gain}},
            "board": {"type": "checker", "size": 1.0, "even": "warm", "odd": "tinted"}
        },
        "objects": [
            {"type": "plane", "point": [0, 0, 0], "normal": [0, 1, 0], "shader": "board"},
            {"type": "sphere", "center": center.to_array(), "radius": radius, "shader": "cold"}
        ],
        "lights": [{"type": "directional", "direction": [0.3, -1, -0.2], "ambient": [1, 1, 1]}]
    });
    let img = render(&scene, &[("flat.wgsl", FLAT), ("tinted.wgsl", TINTED)]);
    let odd = DVec3::from_array(tint) * gain;
    let mut seen = [0; 3];
    check(&img, &cam, EXACT, |x, y| {
        let (o, d) = cam.ray(x, y);
        // The sphere first, off its silhouette.
        let f = center - o;
        let along = f.dot(d);
        let miss = (f - along * d).length() - radius;
        if miss.abs() < 1e-3 {
            return None;
        }
        if miss < 0.0 {
            seen[2] += 1;
            return Some(DVec3::from_array(cold));
        }
        // The ground, off the cell boundaries; looked up just below the
        // surface (y < 0, so floor(y) = −1).
        let p = cam.on_ground(x, y);
        let near = |v: f64| (v - v.round()).abs() < 1e-3;
        if near(p.x) || near(p.z) {
            return None;
        }
        let cell = p.x.floor() as i64 - 1 + p.z.floor() as i64;
        if cell.rem_euclid(2) == 0 {
            seen[0] += 1;
            Some(DVec3::from_array(warm))
        } else {
            seen[1] += 1;
            Some(odd)
        }
    });
    assert!(
        seen.iter().all(|&n| n > 50),
        "pixels per colour (even, odd, sphere): {seen:?}"
    );
}

/// Encodes every kind of parameter into the colour (through `ambient`,
/// with light ambient 1): `show` picks which.
const ENCODE: &str = "\
struct Params {
    i: i32,
    u: u32,
    f: f32,
    v2: vec2<f32>,
    v4: vec4<f32>,
    show: u32,
}

fn ambient(s: Surface, light_ambient: vec3<f32>, p: Params) -> vec3<f32> {
    var c: vec3<f32>;
    switch p.show {
        case 0u: { c = vec3<f32>(f32(p.i), f32(p.u), p.f); }
        case 1u: { c = vec3<f32>(p.v2, select(0.0, 1.0, p.i < 0)); }
        case 2u: { c = p.v4.xyz; }
        default: { c = vec3<f32>(p.v4.w, select(0.0, 1.0, p.u > 3000000000u), f32(p.show)); }
    }
    return c * light_ambient;
}

fn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32> {
    return vec3<f32>(0.0);
}
";

#[test]
fn i32_u32_vec2_and_vec4_params_reach_the_shader() {
    // Values that f32 holds exactly: -2e9 = -1953125·2^10, 4e9 =
    // 15625000·2^8 (above i32::MAX, so a u32 read as i32 would show).
    let (i, u, f) = (-2_000_000_000i64, 4_000_000_000u64, 0.375);
    let (v2, v4) = ([0.25, -1.5], [1.0, 2.0, -3.0, 0.125]);
    let lights = json!([{"type": "directional", "direction": [0, -1, 0], "ambient": [1, 1, 1]}]);
    let expect = [
        [i as f64, u as f64, f],
        [v2[0], v2[1], 1.0],
        [v4[0], v4[1], v4[2]],
        [v4[3], 1.0, 3.0],
    ];
    for (show, want) in expect.iter().enumerate() {
        let shaders = json!({"enc": {"type": "wgsl", "file": "encode.wgsl", "params": {
            "i": i, "u": u, "f": f, "v2": v2, "v4": v4, "show": show
        }}});
        let img = render(
            &ground_scene(&GROUND_CAM, shaders, "enc", lights.clone()),
            &[("encode.wgsl", ENCODE)],
        );
        check(&img, &GROUND_CAM, EXACT, |_, _| {
            Some(DVec3::from_array(*want))
        });
    }
}

#[test]
fn the_example_scene_loads_and_renders() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/shaders.json");
    let opts = LoadOptions {
        width: Some(96),
        height: Some(54),
        ..LoadOptions::default()
    };
    let loaded = load_scene(&path, &opts).unwrap_or_else(|e| panic!("{e}"));
    // Two example user shaders, the first shared by two materials.
    let dir = path.parent().unwrap();
    for f in ["shaders/toon.wgsl", "shaders/normals.wgsl"] {
        assert!(
            loaded.files.contains(&dir.join(f)),
            "{f}: {:?}",
            loaded.files
        );
    }
    let img = support::render(&loaded.scene).image;
    assert_eq!((img.width, img.height), (96, 54));
    assert!(img.pixels.iter().all(|p| p.iter().all(|c| c.is_finite())));
    // Most of the picture is objects, and it is not one flat colour.
    let hits = img.pixels.iter().filter(|p| p[3] == 1.0).count();
    assert!(hits > img.pixels.len() / 2, "{hits} hits");
    let first = img.pixels[img.pixels.len() / 2];
    assert!(img.pixels.iter().any(|p| p != &first));
}

/// Reproducer of a renderer bug (issue 13, reported to the lead, not fixed
/// here): `Renderer::upload` reads a `wgsl` shader's file from disk again
/// (src/render/mod.rs, `upload_inner` passes `shade::read_program` to
/// `Materials::new`) instead of rendering `WgslShader::source`, the text
/// that was loaded and checked. A scene whose file changed (or was removed)
/// after loading renders other code (or fails), and a `Scene` built in
/// memory cannot be rendered without a file.
#[test]
fn a_loaded_scene_renders_the_source_it_loaded() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("flat.wgsl"), FLAT).unwrap();
    let base = [0.25, 0.5, 0.75];
    let scene = ground_scene(
        &GROUND_CAM,
        json!({"flat": {"type": "wgsl", "file": "flat.wgsl", "params": {"base": base}}}),
        "flat",
        json!([{"type": "directional", "direction": [0, -1, 0], "ambient": [1, 1, 1]}]),
    );
    let path = dir.path().join("scene.json");
    std::fs::write(&path, scene.to_string()).unwrap();
    let loaded = load_scene(&path, &LoadOptions::default()).unwrap();
    // The same Params, other code: twice the colour.
    std::fs::write(
        dir.path().join("flat.wgsl"),
        FLAT.replace("p.base * light_ambient", "2.0 * p.base * light_ambient"),
    )
    .unwrap();
    let img = support::render(&loaded.scene).image;
    check(&img, &GROUND_CAM, EXACT, |_, _| {
        Some(DVec3::from_array(base))
    });
    // Without the file at all.
    std::fs::remove_file(dir.path().join("flat.wgsl")).unwrap();
    let img = support::render(&loaded.scene).image;
    check(&img, &GROUND_CAM, EXACT, |_, _| {
        Some(DVec3::from_array(base))
    });
}

/// The built-in Phong and Blinn-Phong files, read by the scene as user
/// files: one mechanism for both, so the images agree bit for bit, with
/// checkers, shadows, a spot light and an area light of two sample chunks.
#[test]
fn copies_of_the_builtin_files_render_the_builtin_images() {
    let builtins = Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders/shading");
    let phong = std::fs::read_to_string(builtins.join("phong.wgsl")).unwrap();
    let blinn = std::fs::read_to_string(builtins.join("blinn_phong.wgsl")).unwrap();
    let coefficients = |ka: [f64; 3], kd: [f64; 3], ks: [f64; 3], ns: f64| json!({"ambient": ka, "diffuse": kd, "specular": ks, "shininess": ns});
    let materials = [
        (
            "red",
            "phong",
            coefficients([0.8, 0.1, 0.1], [0.8, 0.1, 0.1], [0.6, 0.6, 0.6], 20.0),
        ),
        (
            "blue",
            "blinn_phong",
            coefficients([0.1, 0.2, 0.8], [0.1, 0.2, 0.8], [0.5, 0.5, 0.5], 8.0),
        ),
        (
            "ivory",
            "phong",
            coefficients([0.9, 0.9, 0.8], [0.85, 0.8, 0.75], [0.1, 0.1, 0.1], 1.0),
        ),
        (
            "slate",
            "blinn_phong",
            coefficients([0.2, 0.2, 0.25], [0.2, 0.2, 0.25], [0.2, 0.2, 0.2], 0.0),
        ),
    ];
    let scene = |user: bool| {
        let mut shaders = serde_json::Map::new();
        for (name, kind, c) in &materials {
            let mut s = json!({"type": kind});
            if user {
                // The built-ins' texture fields, untextured (no texture use).
                let mut params = c.as_object().unwrap().clone();
                for field in ["ambient_texture", "diffuse_texture", "specular_texture"] {
                    params.insert(field.into(), json!(u32::MAX));
                }
                s = json!({"type": "wgsl", "file": format!("{kind}.wgsl"), "params": params});
            } else {
                s.as_object_mut()
                    .unwrap()
                    .extend(c.as_object().unwrap().clone());
            }
            shaders.insert(name.to_string(), s);
        }
        shaders.insert(
            "floor".into(),
            json!({"type": "checker", "size": 0.75, "even": "ivory", "odd": "slate"}),
        );
        json!({
            "camera": {"position": [0.5, 2.0, 5.0], "look_at": [0, 0.5, 0], "fov": 45, "width": 96, "height": 64},
            "background": BACKGROUND,
            "shaders": shaders,
            "objects": [
                {"type": "plane", "point": [0, 0, 0], "normal": [0, 1, 0], "shader": "floor"},
                {"type": "sphere", "center": [-0.8, 0.7, 0], "radius": 0.7, "shader": "red"},
                {"type": "sphere", "center": [0.9, 0.5, 0.4], "radius": 0.5, "shader": "blue"}
            ],
            "lights": [
                {"type": "point", "position": [2, 3, 2], "intensity": 8, "ambient": [0.05, 0.05, 0.05],
                 "diffuse": [1, 0.9, 0.8], "specular": [1, 1, 1]},
                {"type": "spot", "position": [-2, 3, 1], "direction": [0.5, -1, -0.2], "inner_angle": 15,
                 "outer_angle": 30, "intensity": 10, "diffuse": [0.5, 0.6, 1], "specular": [0.5, 0.6, 1]},
                {"type": "rect", "corner": [-1, 3, -2], "edge1": [1.5, 0, 0], "edge2": [0, 0, 1.5],
                 "intensity": 6, "samples": 100, "ambient": [0.02, 0.03, 0.04]}
            ]
        })
    };
    let files = [
        ("phong.wgsl", phong.as_str()),
        ("blinn_phong.wgsl", blinn.as_str()),
    ];
    let want = render(&scene(false), &[]);
    let got = render(&scene(true), &files);
    let bits =
        |img: &Image| -> Vec<[u32; 4]> { img.pixels.iter().map(|p| p.map(f32::to_bits)).collect() };
    let differ = bits(&got)
        .iter()
        .zip(&bits(&want))
        .filter(|(a, b)| a != b)
        .count();
    assert_eq!(
        differ, 0,
        "{differ} pixels differ from the built-in shaders"
    );
    // Lit, shadowed and highlight pixels: the image is not trivial.
    let mut reds: Vec<u32> = bits(&want).iter().map(|p| p[0]).collect();
    reds.sort_unstable();
    reds.dedup();
    assert!(reds.len() > 500, "{} distinct reds", reds.len());
}

/// `shade` and `ambient` together: a Lambert term and k · light ambient.
const LAMBERT_AMBIENT: &str = "\
struct Params {
    base: vec3<f32>,
    k: vec3<f32>,
}

fn ambient(s: Surface, light_ambient: vec3<f32>, p: Params) -> vec3<f32> {
    return p.k * light_ambient;
}

fn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32> {
    return p.base * l.diffuse * l.intensity * dot(l.to_light, s.normal);
}
";

/// Whether the segment from `p` to `q` passes through the sphere, and
/// whether it passes so close to its silhouette that f32 may decide either
/// way.
fn blocked(p: DVec3, q: DVec3, center: DVec3, radius: f64) -> (bool, bool) {
    let d = q - p;
    let len = d.length();
    let d = d / len;
    let along = (center - p).dot(d).clamp(0.0, len);
    let gap = (p + along * d - center).length() - radius;
    (gap < 0.0, gap.abs() < 1e-3)
}

#[test]
fn many_point_lights_in_three_sample_chunks_match_the_formula() {
    // 150 point lights, one sample each: chunks of 64, 64 and 22 samples,
    // with no sampling pattern, so every pixel is computed here exactly.
    // Lights below the ground reach no point but add their ambient; a
    // sphere casts their shadows.
    let (base, k) = ([0.9, 0.6, 0.3], [0.5, 0.25, 1.0]);
    let (center, radius) = (DVec3::new(0.0, 0.5, -0.5), 0.5);
    struct Lamp {
        q: DVec3,
        intensity: f64,
        diffuse: DVec3,
        ambient: DVec3,
    }
    let lamps: Vec<Lamp> = (0..150)
        .map(|i| {
            let f = i as f64;
            let angle = f * 2.399_963; // the golden angle spreads them out
            let r = 1.0 + (f % 7.0) * 0.4;
            let height = if i % 10 == 9 {
                -1.0
            } else {
                1.5 + (f % 5.0) * 0.5
            };
            Lamp {
                q: DVec3::new(r * angle.cos(), height, r * angle.sin() - 0.5),
                intensity: 0.05 + (f % 3.0) * 0.02,
                diffuse: DVec3::new(1.0, 0.5 + (f % 2.0) * 0.5, 0.25 + (f % 4.0) * 0.25),
                ambient: DVec3::splat(0.001 * (f % 4.0)),
            }
        })
        .collect();
    let lights: Vec<Value> = lamps
        .iter()
        .map(|l| {
            json!({"type": "point", "position": l.q.to_array(), "intensity": l.intensity,
                   "diffuse": l.diffuse.to_array(), "ambient": l.ambient.to_array()})
        })
        .collect();
    let scene = json!({
        "camera": GROUND_CAM.json(),
        "background": BACKGROUND,
        "shaders": {"m": {"type": "wgsl", "file": "lambert_ambient.wgsl",
                          "params": {"base": base, "k": k}}},
        "objects": [
            {"type": "plane", "point": [0, 0, 0], "normal": [0, 1, 0], "shader": "m"},
            {"type": "sphere", "center": center.to_array(), "radius": radius, "shader": "m"}
        ],
        "lights": lights
    });
    let img = render(&scene, &[("lambert_ambient.wgsl", LAMBERT_AMBIENT)]);
    let ambient = lamps.iter().fold(DVec3::ZERO, |a, l| a + l.ambient) * DVec3::from_array(k);
    let (mut shadowed, mut judged) = (0, 0);
    let worst = check(&img, &GROUND_CAM, F32_TOL, |x, y| {
        let (o, d) = GROUND_CAM.ray(x, y);
        let (on_sphere, near_silhouette) = blocked(o, o + 100.0 * d, center, radius);
        if on_sphere || near_silhouette {
            return None;
        }
        let p = GROUND_CAM.on_ground(x, y);
        let mut c = ambient;
        for l in &lamps {
            let to_light = l.q - p;
            if to_light.y <= 0.0 {
                continue;
            }
            let (hit, close) = blocked(p, l.q, center, radius);
            if close {
                return None;
            }
            if hit {
                shadowed += 1;
                continue;
            }
            let cos = to_light.normalize().y;
            c += DVec3::from_array(base)
                * l.diffuse
                * (l.intensity / to_light.length_squared() * cos);
        }
        judged += 1;
        Some(c)
    });
    eprintln!(
        "150 point lights: largest error {worst:e}, {judged} pixels, {shadowed} shadowed samples"
    );
    assert!(shadowed > 1000, "{shadowed} shadowed light samples");
}

/// Reproducer of a renderer bug (issue 13, reported to the lead, not fixed
/// here): a shade pipeline is cached by the shader file's path, and
/// `Renderer::render` (`frame_pipelines` with `reload = false`) compiles it
/// only when no pipeline for that path exists, so a scene loaded again after
/// its shader file was edited renders with the old code. `penumbra watch`
/// shows it: an edit of a user shader reloads the scene ("kernel kept") and
/// the image does not change.
#[test]
fn an_edited_shader_file_renders_its_new_code() {
    let dir = tempfile::tempdir().unwrap();
    let base = [0.25, 0.5, 0.75];
    let scene = ground_scene(
        &GROUND_CAM,
        json!({"flat": {"type": "wgsl", "file": "flat.wgsl", "params": {"base": base}}}),
        "flat",
        json!([{"type": "directional", "direction": [0, -1, 0], "ambient": [1, 1, 1]}]),
    );
    let path = dir.path().join("scene.json");
    std::fs::write(&path, scene.to_string()).unwrap();
    let render_with = |gain: f64| {
        let text = FLAT.replace(
            "p.base * light_ambient",
            &format!("{gain:?} * p.base * light_ambient"),
        );
        std::fs::write(dir.path().join("flat.wgsl"), text).unwrap();
        let loaded = load_scene(&path, &LoadOptions::default()).unwrap();
        let img = support::render(&loaded.scene).image;
        check(&img, &GROUND_CAM, EXACT, |_, _| {
            Some(DVec3::from_array(base) * gain)
        });
    };
    render_with(1.0);
    render_with(2.0);
}

/// The light's diffuse colour, once per light sample that the engine lets
/// through.
const SAMPLE_COLOUR: &str = "\
fn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32> {
    return l.diffuse;
}
";

#[test]
fn shade_runs_only_for_samples_above_the_surface_and_the_shading_normal() {
    // A quad facing the camera (+Z) whose vertex normals lean left and
    // right: light A, from the right and in front, is above the geometric
    // surface everywhere but below the interpolated normal on the left;
    // light B, from the right and behind, is below the geometric surface
    // everywhere although above the normal on the right.
    let cam = Cam {
        eye: DVec3::ZERO,
        look_at: DVec3::new(0.0, 0.0, -1.0),
        fov: 50.0,
        w: 64,
        h: 48,
    };
    let to_a = DVec3::new(1.0, 0.0, 0.3).normalize();
    let to_b = DVec3::new(1.0, 0.0, -0.3).normalize();
    let lights = json!([
        {"type": "directional", "direction": (-to_a).to_array(), "diffuse": [1, 0, 0], "ambient": [0, 0, 0]},
        {"type": "directional", "direction": (-to_b).to_array(), "diffuse": [0, 1, 0], "ambient": [0, 0, 0]}
    ]);
    let z = -4.0;
    let scene = json!({
        "camera": cam.json(),
        "background": BACKGROUND,
        "shaders": {"count": {"type": "wgsl", "file": "count.wgsl"}},
        "objects": [{"type": "triangle", "vertices": [[-1, -1, z], [1, -1, z], [0, 1, z]], "shader": "count"}],
        "lights": lights
    });
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("count.wgsl"), SAMPLE_COLOUR).unwrap();
    let path = dir.path().join("scene.json");
    std::fs::write(&path, scene.to_string()).unwrap();
    let mut scene = load_scene(&path, &LoadOptions::default()).unwrap().scene;
    // The triangle becomes a quad with vertex normals (the JSON format has
    // no such meshes inline).
    let corners = [
        DVec3::new(-3.0, -2.5, z),
        DVec3::new(3.0, -2.5, z),
        DVec3::new(3.0, 2.5, z),
        DVec3::new(-3.0, 2.5, z),
    ];
    let normals = [
        DVec3::new(-0.8, 0.0, 0.6),
        DVec3::new(0.8, 0.0, 0.6),
        DVec3::new(0.8, 0.0, 0.6),
        DVec3::new(-0.8, 0.0, 0.6),
    ];
    let tris = [[0usize, 1, 2], [0, 2, 3]];
    scene.objects[0].shape = penumbra::scene::Shape::Mesh(penumbra::scene::Mesh {
        uvs: vec![],
        colours: None,
        tangents: None,
        positions: corners.to_vec(),
        normals: Some(normals.to_vec()),
        indices: tris.iter().map(|t| t.map(|i| i as u32)).collect(),
    });
    let img = support::render(&scene).image;
    let (mut lit, mut unlit) = (0, 0);
    check(&img, &cam, EXACT, |x, y| {
        let (o, d) = cam.ray(x, y);
        let p = o + (z - o.z) / d.z * d;
        let t = tris
            .iter()
            .find_map(|t| {
                let (a, b, c) = (corners[t[0]], corners[t[1]], corners[t[2]]);
                let (e1, e2, q) = (b - a, c - a, p - a);
                let det = e1.x * e2.y - e1.y * e2.x;
                let u = (q.x * e2.y - q.y * e2.x) / det;
                let v = (e1.x * q.y - e1.y * q.x) / det;
                (u >= 0.0 && v >= 0.0 && u + v <= 1.0).then_some((t, u, v))
            })
            .expect("the quad fills the view");
        let (t, u, v) = t;
        let n = ((1.0 - u - v) * normals[t[0]] + u * normals[t[1]] + v * normals[t[2]]).normalize();
        let ln = to_a.dot(n);
        if ln.abs() < 1e-3 {
            return None;
        }
        if ln > 0.0 {
            lit += 1;
            Some(DVec3::X)
        } else {
            unlit += 1;
            Some(DVec3::ZERO)
        }
    });
    assert!(lit > 200 && unlit > 200, "{lit} lit, {unlit} unlit");
}
