//! Textures on the GPU against values computed here from the definitions of
//! `penumbra::scene::texture` (sRGB decoding, nearest and bilinear filters,
//! wrap modes, KHR_texture_transform, mip selection by ray cones), never
//! against earlier renders.
//!
//! The scenes are built so that the colour of a pixel is exactly the texture
//! sample: an orthographic camera looks head-on at a unit-less quad lit by a
//! directional light along the view (n·l = 1), with a Phong shader of
//! diffuse 1, no ambient and no specular. The GPU filters in f32 on 8-bit
//! texels, so a sample carries errors of a few ulps of values ≤ 1; the
//! tolerance 2e-4 covers them with a wide margin, while a wrong texel, a
//! missing sRGB decode (which moves mid-greys by > 0.1) or a half-texel shift
//! of the bilinear weights (≥ 0.02 with these texels) fails it.

use crate::support;

use glam::{DMat3, DVec2, DVec3, Vec3};
use penumbra::scene::texture::srgb_to_linear;
use penumbra::scene::{
    AlphaMode, Camera, Filter, Light, LightKind, Mesh, Object, Phong, PhongTextures, Projection,
    Sampler, Scene, Shader, Shape, SurfaceMaps, Texture, TextureRef, UvTransform, Wrap,
};

const TOL: f64 = 2e-4;

/// A 4×4 texture whose texels all differ.
fn texture(srgb: bool) -> Texture {
    let texels = (0..16u32)
        .map(|i| {
            let (x, y) = (i % 4, i / 4);
            [
                (20 + 60 * x) as u8,
                (30 + 55 * y) as u8,
                (7 * i + 3) as u8,
                (255 - 10 * i) as u8,
            ]
        })
        .collect();
    Texture {
        label: "test texture".into(),
        file: None,
        width: 4,
        height: 4,
        texels,
        srgb,
    }
}

/// The texel (x, y) of `t` as linear RGBA, wrapped by `wrap`.
fn texel(t: &Texture, x: i64, y: i64, wrap: (Wrap, Wrap)) -> [f64; 4] {
    let xi = wrap.0.apply(x, t.width);
    let yi = wrap.1.apply(y, t.height);
    let p = t.texels[(yi * t.width + xi) as usize];
    std::array::from_fn(|c| {
        if t.srgb && c < 3 {
            srgb_to_linear(p[c])
        } else {
            f64::from(p[c]) / 255.0
        }
    })
}

/// Level 0 of `t` at `uv`, magnified with `filter` (OpenGL's rules).
fn expected(t: &Texture, uv: DVec2, filter: Filter, wrap: (Wrap, Wrap)) -> [f64; 4] {
    let p = uv * DVec2::new(f64::from(t.width), f64::from(t.height));
    match filter {
        Filter::Nearest => texel(t, p.x.floor() as i64, p.y.floor() as i64, wrap),
        Filter::Linear => {
            let q = p - 0.5;
            let f = q.floor();
            let w = q - f;
            let (x, y) = (f.x as i64, f.y as i64);
            let a = texel(t, x, y, wrap);
            let b = texel(t, x + 1, y, wrap);
            let c = texel(t, x, y + 1, wrap);
            let d = texel(t, x + 1, y + 1, wrap);
            std::array::from_fn(|k| {
                let top = a[k] + (b[k] - a[k]) * w.x;
                let bottom = c[k] + (d[k] - c[k]) * w.x;
                top + (bottom - top) * w.y
            })
        }
    }
}

/// A quad in the z = 0 plane from (−1, −1) to (1, 1), facing +Z, whose
/// top-left corner has uv (0, 0) and bottom-right `uv_max`.
fn quad(uv_max: DVec2) -> Mesh {
    Mesh {
        positions: vec![
            DVec3::new(-1.0, 1.0, 0.0),
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(1.0, -1.0, 0.0),
            DVec3::new(-1.0, -1.0, 0.0),
        ],
        normals: None,
        indices: vec![[0, 3, 2], [0, 2, 1]],
        uvs: vec![vec![
            DVec2::ZERO,
            DVec2::new(uv_max.x, 0.0),
            uv_max,
            DVec2::new(0.0, uv_max.y),
        ]],
        colours: None,
        tangents: None,
    }
}

/// An `n`×`n` image of `mesh` seen head-on by an orthographic camera whose
/// window is exactly the quad, under a unit directional light along the
/// view, shaded by Phong with diffuse 1 scaled by `diffuse`.
fn scene(mesh: Mesh, n: u32, diffuse: TextureRef, textures: Vec<Texture>) -> Scene {
    Scene {
        textures,
        camera: Camera {
            position: DVec3::new(0.0, 0.0, 5.0),
            orientation: DMat3::IDENTITY,
            projection: Projection::Orthographic { half_height: 1.0 },
            width: n,
            height: n,
        },
        background: Vec3::ZERO,
        shaders: vec![Shader::Phong(Phong {
            ambient: Vec3::ZERO,
            diffuse: Vec3::ONE,
            specular: Vec3::ZERO,
            shininess: 1.0,
            textures: PhongTextures {
                diffuse: Some(diffuse),
                ..Default::default()
            },
        })],
        objects: vec![Object {
            shape: Shape::Mesh(mesh),
            shader: 0,
            maps: SurfaceMaps::default(),
        }],
        lights: vec![Light {
            kind: LightKind::Directional {
                direction: DVec3::new(0.0, 0.0, -1.0),
            },
            intensity: 1.0,
            ambient: Vec3::ZERO,
            diffuse: Vec3::ONE,
            specular: Vec3::ZERO,
        }],
    }
}

/// The uv at the centre of pixel (x, y) of an `n`×`n` image of `quad(uv_max)`.
fn pixel_uv(x: u32, y: u32, n: u32, uv_max: DVec2) -> DVec2 {
    DVec2::new(
        (f64::from(x) + 0.5) / f64::from(n),
        (f64::from(y) + 0.5) / f64::from(n),
    ) * uv_max
}

fn sampler(filter: Filter, wrap_u: Wrap, wrap_v: Wrap) -> Sampler {
    Sampler {
        mag: filter,
        min: filter,
        mip: None,
        wrap_u,
        wrap_v,
    }
}

/// Renders `quad(uv_max)` with `use_` and checks every pixel against the
/// magnified sample of the formula.
fn check_magnified(use_: TextureRef, uv_max: DVec2, n: u32, srgb: bool) {
    let t = texture(srgb);
    let frame = support::render(&scene(quad(uv_max), n, use_, vec![t.clone()]));
    let wrap = (use_.sampler.wrap_u, use_.sampler.wrap_v);
    for y in 0..n {
        for x in 0..n {
            let uv = use_.transform.apply(pixel_uv(x, y, n, uv_max));
            let want = expected(&t, uv, use_.sampler.mag, wrap);
            let got = frame.image.pixels[(y * n + x) as usize];
            for c in 0..3 {
                assert!(
                    (f64::from(got[c]) - want[c]).abs() <= TOL,
                    "pixel ({x}, {y}) channel {c}: got {:?}, want {:?}",
                    &got[..3],
                    &want[..3]
                );
            }
        }
    }
}

#[test]
fn nearest_and_linear_magnification_decode_srgb() {
    for filter in [Filter::Nearest, Filter::Linear] {
        for srgb in [true, false] {
            let use_ = TextureRef {
                sampler: sampler(filter, Wrap::Repeat, Wrap::Repeat),
                ..TextureRef::new(0)
            };
            check_magnified(use_, DVec2::ONE, 16, srgb);
        }
    }
}

#[test]
fn each_wrap_mode() {
    for wrap in [Wrap::Repeat, Wrap::MirroredRepeat, Wrap::ClampToEdge] {
        for filter in [Filter::Nearest, Filter::Linear] {
            let use_ = TextureRef {
                sampler: sampler(filter, wrap, Wrap::ClampToEdge),
                ..TextureRef::new(0)
            };
            // uv runs to 2.5 and 1.5: outside the image, where wraps differ.
            check_magnified(use_, DVec2::new(2.5, 1.5), 24, true);
        }
    }
}

#[test]
fn khr_texture_transform() {
    let use_ = TextureRef {
        sampler: sampler(Filter::Linear, Wrap::Repeat, Wrap::MirroredRepeat),
        transform: UvTransform {
            offset: DVec2::new(0.3, -0.2),
            rotation: 0.4,
            scale: DVec2::new(0.7, 0.9),
        },
        ..TextureRef::new(0)
    };
    check_magnified(use_, DVec2::ONE, 20, true);
}

/// With the texture's alpha as a mask, pixels whose alpha is below the cutoff
/// show the background, and the others the texture.
#[test]
fn a_mask_cuts_out() {
    let t = texture(true);
    let use_ = TextureRef {
        sampler: sampler(Filter::Nearest, Wrap::Repeat, Wrap::Repeat),
        ..TextureRef::new(0)
    };
    let mut s = scene(quad(DVec2::ONE), 16, use_, vec![t.clone()]);
    s.background = Vec3::new(0.0, 0.0, 1.0);
    s.objects[0].maps = SurfaceMaps {
        alpha_mode: AlphaMode::Mask { cutoff: 0.6 },
        opacity: 1.0,
        opacity_texture: Some(use_),
        ..SurfaceMaps::default()
    };
    let frame = support::render(&s);
    let (mut cut, mut kept) = (0, 0);
    for y in 0..16 {
        for x in 0..16 {
            let uv = pixel_uv(x, y, 16, DVec2::ONE);
            let want = expected(&t, uv, Filter::Nearest, (Wrap::Repeat, Wrap::Repeat));
            let got = frame.image.pixels[(y * 16 + x) as usize];
            if want[3] >= 0.6 {
                kept += 1;
                support::assert_rgb(got, [want[0], want[1], want[2]], TOL);
            } else {
                cut += 1;
                support::assert_rgb(got, [0.0, 0.0, 1.0], 0.0);
            }
        }
    }
    // Alpha falls from 1 to 0.41 over the texels: both kinds are tested.
    assert!(cut > 0 && kept > 0, "cut {cut}, kept {kept}");
}
