//! A JSON scene with textures, loaded from files and rendered on the GPU
//! (issue 14), checked pixel by pixel against values computed here from the
//! PNG texels and the conventions of `penumbra::scene::texture` (planar
//! coordinates of planes, latitude-longitude ones of spheres, sRGB decoding,
//! the JSON's filter, wrap and scale), never against an earlier render.
//!
//! An orthographic camera looks straight down at the ground plane y = 0 with
//! −Z up the image, under a unit directional light along −Y: the plane's
//! Phong shader (textured diffuse, no ambient or specular) gives exactly
//! the texture's linear RGB, and a sphere above it with a user shader
//! returns its texture parameter's sample times a tint. The light falls
//! along the view, so the sphere's shadow is hidden behind it.

use std::io::Cursor;

use glam::DVec2;
use penumbra::scene::texture::srgb_to_linear;
use penumbra::scene::Wrap;

use crate::support;

const N: u32 = 48;
const HALF: f64 = 1.5;
const RADIUS: f64 = 0.8;
/// f32 filtering of 8-bit texels: a few ulps (as tests/gpu/textures.rs).
const TOL: f64 = 2e-4;
const TINT: [f64; 3] = [1.0, 0.5, 0.25];

/// A `w`×`h` image whose texels all differ (RGB), opaque.
fn texels(w: u32, h: u32, seed: u32) -> image::RgbaImage {
    image::RgbaImage::from_fn(w, h, |x, y| {
        let i = y * w + x;
        image::Rgba([
            (15 + 230 * x / (w - 1)) as u8,
            (25 + 220 * y / (h - 1)) as u8,
            ((seed + 37 * i) % 251) as u8,
            255,
        ])
    })
}

fn png(img: &image::RgbaImage) -> Vec<u8> {
    let mut out = Vec::new();
    img.write_to(&mut Cursor::new(&mut out), image::ImageFormat::Png)
        .unwrap();
    out
}

/// Texel (x, y) of `img`, wrapped, as linear RGB (the file is sRGB).
fn texel(img: &image::RgbaImage, x: i64, y: i64, wrap: (Wrap, Wrap)) -> [f64; 3] {
    let xi = wrap.0.apply(x, img.width());
    let yi = wrap.1.apply(y, img.height());
    let p = img.get_pixel(xi, yi).0;
    std::array::from_fn(|c| srgb_to_linear(p[c]))
}

/// Bilinear sample of level 0 at `uv` (OpenGL's rules: `x = u·w − ½`).
fn bilinear(img: &image::RgbaImage, uv: DVec2, wrap: (Wrap, Wrap)) -> [f64; 3] {
    let p = uv * DVec2::new(img.width().into(), img.height().into()) - 0.5;
    let f = p.floor();
    let w = p - f;
    let (x, y) = (f.x as i64, f.y as i64);
    let a = texel(img, x, y, wrap);
    let b = texel(img, x + 1, y, wrap);
    let c = texel(img, x, y + 1, wrap);
    let d = texel(img, x + 1, y + 1, wrap);
    std::array::from_fn(|k| {
        let top = a[k] + (b[k] - a[k]) * w.x;
        let bottom = c[k] + (d[k] - c[k]) * w.x;
        top + (bottom - top) * w.y
    })
}

/// The shader of the sphere: its texture parameter at the point, tinted.
const PAINTED: &str = "struct Params { tint: vec3<f32>, t: u32, }
fn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32> {
    return texture_at(p.t, s).rgb * p.tint;
}
";

#[test]
fn a_textured_plane_from_above_and_a_user_shader_with_a_texture_match_the_conventions() {
    let ground = texels(4, 4, 3);
    let globe = texels(8, 4, 11);
    let json = format!(
        r#"{{
  "camera": {{ "position": [0, 5, 0], "look_at": [0, 0, 0], "up": [0, 0, -1],
              "projection": "orthographic", "half_height": {HALF}, "width": {N}, "height": {N} }},
  "shaders": {{
    "ground": {{ "type": "phong", "diffuse": {{ "texture": "ground.png", "filter": "bilinear",
                                              "wrap": ["mirrored_repeat", "clamp"], "scale": [0.75, 0.5] }} }},
    "globe": {{ "type": "wgsl", "file": "painted.wgsl",
                "params": {{ "tint": {TINT:?}, "t": {{ "texture": "textures/globe.png", "filter": "nearest" }} }} }}
  }},
  "objects": [
    {{ "type": "plane", "point": [0, 0, 0], "normal": [0, 1, 0], "shader": "ground" }},
    {{ "type": "sphere", "center": [0, 1, 0], "radius": {RADIUS}, "shader": "globe" }}
  ],
  "lights": [ {{ "type": "directional", "direction": [0, -1, 0], "ambient": [0, 0, 0],
                 "diffuse": [1, 1, 1], "specular": [0, 0, 0] }} ]
}}"#
    );
    let (dir, path) = support::write_scene(&json);
    std::fs::write(dir.path().join("ground.png"), png(&ground)).unwrap();
    std::fs::create_dir(dir.path().join("textures")).unwrap();
    std::fs::write(dir.path().join("textures/globe.png"), png(&globe)).unwrap();
    std::fs::write(dir.path().join("painted.wgsl"), PAINTED).unwrap();
    let scene = support::load(&path);
    assert_eq!(scene.textures.len(), 2);
    let frame = support::render(&scene);

    let px = 2.0 * HALF / f64::from(N);
    let (mut plane_px, mut sphere_px, mut skipped) = (0, 0, 0);
    for py in 0..N {
        for pxi in 0..N {
            // Ray (x, z) of the pixel centre: +X to the right, −Z at the top.
            let x = (f64::from(pxi) + 0.5) * px - HALF;
            let z = (f64::from(py) + 0.5) * px - HALF;
            let got = frame.image.pixels[(py * N + pxi) as usize];
            let r = x.hypot(z);
            if (r - RADIUS).abs() < px {
                skipped += 1; // the silhouette: either surface
                continue;
            }
            let want = if r > RADIUS {
                // The ground: u = x, v = z (e_u = +X, e_v = +Z for n = +Y),
                // scaled, mirrored along u and clamped along v; bilinear
                // in level 0 (magnified: λ = log2(W) + 1 + log2(0.75·0.5)/2 < 0).
                plane_px += 1;
                let uv = DVec2::new(0.75 * x, 0.5 * z);
                bilinear(&ground, uv, (Wrap::MirroredRepeat, Wrap::ClampToEdge))
            } else {
                // The sphere's top: d from the centre, u = ½ − atan2(d_z,
                // d_x)/2π, v = acos(d_y)/π; nearest in level 0 (no mip-maps).
                let y = (RADIUS * RADIUS - r * r).sqrt();
                let d = glam::DVec3::new(x, y, z) / RADIUS;
                let u = 0.5 - d.z.atan2(d.x) / std::f64::consts::TAU;
                let v = d.y.clamp(-1.0, 1.0).acos() / std::f64::consts::PI;
                let (tx, ty) = (u * 8.0, v * 4.0);
                // A point on a texel edge may go either way in f32.
                let edge = |t: f64| (t - t.round()).abs() < 0.02;
                if edge(tx) || edge(ty) || r < 0.05 {
                    skipped += 1;
                    continue;
                }
                sphere_px += 1;
                let t = texel(
                    &globe,
                    tx.floor() as i64,
                    ty.floor() as i64,
                    (Wrap::Repeat, Wrap::Repeat),
                );
                std::array::from_fn(|c| t[c] * TINT[c])
            };
            for c in 0..3 {
                assert!(
                    (f64::from(got[c]) - want[c]).abs() <= TOL,
                    "pixel ({pxi}, {py}) at x {x:.3}, z {z:.3} channel {c}: got {:?}, want {want:?}",
                    &got[..3]
                );
            }
        }
    }
    // Most pixels are checked, on both surfaces.
    assert!(
        plane_px > 1400 && sphere_px > 250,
        "plane {plane_px}, sphere {sphere_px}, skipped {skipped}"
    );
}

/// The ground's shader for the linear test: its texture parameter's RGB.
const RAW: &str = "struct Params { t: u32, }
fn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32> {
    return texture_at(p.t, s).rgb;
}
";

/// `"encoding": "linear"` hands a shader the file's values undecoded: the
/// ground seen from above, its user shader returning its texture parameter
/// (nearest, level 0), shows texel `(⌊4u⌋ mod 4, ⌊4v⌋ mod 4)` at `u = x`,
/// `v = z` as the 8-bit values over 255, where the sRGB default would give
/// their decoded (darker) values.
#[test]
fn a_linear_texture_parameter_reads_the_files_values() {
    let data = texels(4, 4, 5);
    let json = format!(
        r#"{{
  "camera": {{ "position": [0, 5, 0], "look_at": [0, 0, 0], "up": [0, 0, -1],
              "projection": "orthographic", "half_height": {HALF}, "width": {N}, "height": {N} }},
  "shaders": {{
    "ground": {{ "type": "wgsl", "file": "raw.wgsl",
                "params": {{ "t": {{ "texture": "data.png", "filter": "nearest", "encoding": "linear" }} }} }}
  }},
  "objects": [ {{ "type": "plane", "point": [0, 0, 0], "normal": [0, 1, 0], "shader": "ground" }} ],
  "lights": [ {{ "type": "directional", "direction": [0, -1, 0] }} ]
}}"#
    );
    let (dir, path) = support::write_scene(&json);
    std::fs::write(dir.path().join("data.png"), png(&data)).unwrap();
    std::fs::write(dir.path().join("raw.wgsl"), RAW).unwrap();
    let scene = support::load(&path);
    assert!(!scene.textures[0].srgb);
    let frame = support::render(&scene);
    let px = 2.0 * HALF / f64::from(N);
    let mut checked = 0;
    for py in 0..N {
        for pxi in 0..N {
            let x = (f64::from(pxi) + 0.5) * px - HALF;
            let z = (f64::from(py) + 0.5) * px - HALF;
            let (tx, tz) = (4.0 * x, 4.0 * z);
            // A point on a texel edge may go either way in f32.
            if (tx - tx.round()).abs() < 0.02 || (tz - tz.round()).abs() < 0.02 {
                continue;
            }
            let t = data.get_pixel(
                (tx.floor() as i64).rem_euclid(4) as u32,
                (tz.floor() as i64).rem_euclid(4) as u32,
            );
            let got = frame.image.pixels[(py * N + pxi) as usize];
            for c in 0..3 {
                let want = f64::from(t[c]) / 255.0;
                assert!(
                    (f64::from(got[c]) - want).abs() <= TOL,
                    "pixel ({pxi}, {py}) channel {c}: got {:?}, want texel {:?} / 255",
                    &got[..3],
                    t.0
                );
            }
            checked += 1;
        }
    }
    assert!(checked > 2000, "{checked} pixels checked");
}

// ------------------------------------------------------------ watching

/// The watch scene: the ground from above (orthographic, 4 units across,
/// −Z up), its diffuse the texture `tex.png` with the nearest filter (level
/// 0 only), lit head-on: pixel (x, y) of the output is texel
/// `(⌊u·w⌋ mod w, ⌊v·h⌋ mod h)`'s colour for `u = x`, `v = z` at its centre.
fn watch_scene() -> String {
    r#"{
  "camera": { "position": [0, 5, 0], "look_at": [0, 0, 0], "up": [0, 0, -1],
              "projection": "orthographic", "half_height": 2, "width": 32, "height": 32 },
  "shaders": { "ground": { "type": "phong", "diffuse": { "texture": "tex.png", "filter": "nearest" } } },
  "objects": [ { "type": "plane", "point": [0, 0, 0], "normal": [0, 1, 0], "shader": "ground" } ],
  "lights": [ { "type": "directional", "direction": [0, -1, 0], "ambient": [0, 0, 0],
                "diffuse": [1, 1, 1], "specular": [0, 0, 0] } ]
}"#
    .to_string()
}

/// Checks every even pixel of the output (whose centres lie a quarter
/// texel from the texel edges) against `img`: the PNG holds the linear
/// texel re-encoded to sRGB, the file's byte within one.
#[track_caller]
fn assert_output_shows(out: &std::path::Path, img: &image::RgbaImage) {
    let got = image::open(out).unwrap().to_rgb8();
    assert_eq!(got.dimensions(), (32, 32));
    for py in (0..32).step_by(2) {
        for px in (0..32).step_by(2) {
            // u = x = (px + ½)/8 − 2 and v = z likewise; the texel is
            // ⌊u·w⌋, ⌊v·h⌋ wrapped (never on an edge for w, h of 4 or 8).
            let x = (f64::from(px) + 0.5) / 8.0 - 2.0;
            let z = (f64::from(py) + 0.5) / 8.0 - 2.0;
            let tx = (x * f64::from(img.width())).floor() as i64;
            let ty = (z * f64::from(img.height())).floor() as i64;
            let xi = Wrap::Repeat.apply(tx, img.width());
            let yi = Wrap::Repeat.apply(ty, img.height());
            let want = img.get_pixel(xi, yi).0;
            let g = got.get_pixel(px, py).0;
            for c in 0..3 {
                assert!(
                    g[c].abs_diff(want[c]) <= 1,
                    "pixel ({px}, {py}): got {g:?}, want texel ({xi}, {yi}) {want:?}"
                );
            }
        }
    }
}

#[test]
fn watch_replaces_an_edited_texture_without_reloading_the_scene() {
    use crate::watch_support::{Fixture, Running};
    use penumbra::watch::files::normalise;
    let fx = Fixture::new();
    std::fs::write(&fx.scene, watch_scene()).unwrap();
    let tex = fx.dir.path().join("tex.png");
    let first = texels(4, 4, 3);
    std::fs::write(&tex, png(&first)).unwrap();
    let mut w = Running::start(fx.options());
    assert!(w.reloads[0].errors.is_empty(), "{:?}", w.reloads[0].errors);
    assert_output_shows(&fx.out, &first);

    // An edit of the texture (same size): only that texture is replaced.
    let second = texels(4, 4, 100);
    let second = image::RgbaImage::from_fn(4, 4, |x, y| {
        let p = second.get_pixel(3 - x, y).0;
        image::Rgba([p[2], p[0], p[1], 255])
    });
    std::fs::write(&tex, png(&second)).unwrap();
    let r = w.next_reload();
    assert!(r.errors.is_empty(), "{:?}", r.errors);
    assert!(!r.changes.scene && !r.changes.shaders, "{}", r.line);
    assert_eq!(r.textures, [normalise(&tex)], "{}", r.line);
    assert!(r.upload.is_none(), "no scene reload: {}", r.line);
    assert!(r.texture_replace.is_some(), "{}", r.line);
    assert!(r.compile.is_none(), "nothing recompiled: {}", r.line);
    assert!(r.line.contains("textures (tex.png)"), "{}", r.line);
    assert_eq!(r.stages.len(), 2, "{r:#?}");
    assert_output_shows(&fx.out, &second);
    let good = std::fs::read(&fx.out).unwrap();

    // A corrupt texture: one error naming the file; the image stays.
    let mut cut = png(&first);
    cut.truncate(cut.len() - 20);
    std::fs::write(&tex, &cut).unwrap();
    let r = w.next_reload();
    assert_eq!(r.errors.len(), 1, "{r:#?}");
    assert!(
        r.errors[0].contains("tex.png") && r.errors[0].contains("corrupt"),
        "{}",
        r.errors[0]
    );
    assert!(r.upload.is_none(), "{}", r.line);
    assert!(r.stages.is_empty(), "{r:#?}");
    assert!(r.line.contains("ERROR"), "{}", r.line);
    assert_eq!(
        std::fs::read(&fx.out).unwrap(),
        good,
        "the last image stays"
    );

    // Fixed, saved by rename: replaced again, still without a reload.
    let third = texels(4, 4, 200);
    let tmp = fx.dir.path().join("tex.png.tmp");
    std::fs::write(&tmp, png(&third)).unwrap();
    std::fs::rename(&tmp, &tex).unwrap();
    let r = w.reload_until("the fixed texture", |r| r.stages.len() == 2);
    assert!(r.errors.is_empty(), "{:?}", r.errors);
    assert!(
        r.upload.is_none() && r.texture_replace.is_some(),
        "{}",
        r.line
    );
    assert_output_shows(&fx.out, &third);

    // Another size cannot be replaced in place: the scene is reloaded.
    let bigger = texels(8, 4, 50);
    std::fs::write(&tex, png(&bigger)).unwrap();
    let r = w.next_reload();
    assert!(r.errors.is_empty(), "{:?}", r.errors);
    assert!(
        r.upload.is_some(),
        "a new size reloads the scene: {}",
        r.line
    );
    assert_output_shows(&fx.out, &bigger);

    // And the scene still watches it after that reload.
    let last = texels(8, 4, 7);
    std::fs::write(&tex, png(&last)).unwrap();
    let r = w.next_reload();
    assert!(r.errors.is_empty(), "{:?}", r.errors);
    assert!(
        r.upload.is_none() && r.texture_replace.is_some(),
        "{}",
        r.line
    );
    assert_output_shows(&fx.out, &last);
}

/// A user's texture index out of range (issue 36: user code touches only
/// what the interface gives it): the shade stage's texel loads are
/// bounds-checked, so indices past the texture table read a zero record and
/// the render completes with finite colours.
#[test]
fn a_texture_index_out_of_range_reads_nothing_out_of_range() {
    const WILD: &str = "struct Params { t: u32, }
fn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32> {
    let far = texture_at(p.t + 123456789u, s).rgb + texture_at(0xfffffffeu, s).rgb;
    return texture_at(p.t, s).rgb + 1e-3 * far;
}
";
    let json = format!(
        r#"{{
  "camera": {{ "position": [0, 5, 0], "look_at": [0, 0, 0], "up": [0, 0, -1],
              "projection": "orthographic", "half_height": {HALF}, "width": {N}, "height": {N} }},
  "shaders": {{
    "ground": {{ "type": "wgsl", "file": "wild.wgsl",
                "params": {{ "t": {{ "texture": "data.png", "filter": "nearest" }} }} }}
  }},
  "objects": [ {{ "type": "plane", "point": [0, 0, 0], "normal": [0, 1, 0], "shader": "ground" }} ],
  "lights": [ {{ "type": "directional", "direction": [0, -1, 0] }} ]
}}"#
    );
    let (dir, path) = support::write_scene(&json);
    std::fs::write(dir.path().join("data.png"), png(&texels(4, 4, 5))).unwrap();
    std::fs::write(dir.path().join("wild.wgsl"), WILD).unwrap();
    let frame = support::render(&support::load(&path));
    assert!(frame
        .image
        .pixels
        .iter()
        .all(|p| p.iter().all(|c| c.is_finite() && *c >= 0.0)));
    assert!(frame.image.pixels.iter().any(|p| p[0] > 0.0));
}
