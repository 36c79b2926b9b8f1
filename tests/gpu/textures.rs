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
        camera: support::front_on(1.0, n, n),
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

/// Checks every pixel of `frame` (an `n`×`n` image of the quad) against
/// `want(world x, world y)`.
#[track_caller]
fn check_quad(
    frame: &penumbra::render::Frame,
    n: u32,
    tol: f64,
    want: impl Fn(f64, f64) -> [f64; 3],
) {
    for y in 0..n {
        for x in 0..n {
            let wx = -1.0 + 2.0 * (f64::from(x) + 0.5) / f64::from(n);
            let wy = 1.0 - 2.0 * (f64::from(y) + 0.5) / f64::from(n);
            support::assert_rgb(frame.image.pixels[(y * n + x) as usize], want(wx, wy), tol);
        }
    }
}

/// Vertex colours that are an affine function of the position: every
/// triangulation interpolates them exactly, so the pixel's colour is known
/// in closed form. They multiply the textured diffuse colour.
#[test]
fn vertex_colours_multiply_the_diffuse_colour() {
    let colour = |x: f64, y: f64| [0.5 + 0.25 * x, 0.5 + 0.25 * y, 0.3 + 0.1 * x + 0.2 * y];
    let mut mesh = quad(DVec2::ONE);
    mesh.colours = Some(
        mesh.positions
            .iter()
            .map(|p| {
                let c = colour(p.x, p.y);
                glam::Vec4::new(c[0] as f32, c[1] as f32, c[2] as f32, 1.0)
            })
            .collect(),
    );
    let use_ = TextureRef {
        sampler: sampler(Filter::Nearest, Wrap::Repeat, Wrap::Repeat),
        ..TextureRef::new(0)
    };
    let t = texture(true);
    let frame = support::render(&scene(mesh, 16, use_, vec![t.clone()]));
    check_quad(&frame, 16, TOL, |x, y| {
        let uv = DVec2::new((x + 1.0) / 2.0, (1.0 - y) / 2.0);
        let tex = expected(&t, uv, Filter::Nearest, (Wrap::Repeat, Wrap::Repeat));
        let c = colour(x, y);
        [tex[0] * c[0], tex[1] * c[1], tex[2] * c[2]]
    });
}

/// Emission × its texture is added to the colour at the point; with no
/// diffuse colour it is the whole colour.
#[test]
fn emission_is_added() {
    let t = texture(true);
    let use_ = TextureRef {
        sampler: sampler(Filter::Nearest, Wrap::Repeat, Wrap::Repeat),
        ..TextureRef::new(0)
    };
    let mut s = scene(quad(DVec2::ONE), 16, use_, vec![t.clone()]);
    let Shader::Phong(p) = &mut s.shaders[0] else {
        unreachable!()
    };
    p.diffuse = Vec3::splat(0.5);
    p.textures.diffuse = None;
    let emission = [0.25, 0.5, 2.0];
    s.objects[0].maps = SurfaceMaps {
        emission: Vec3::new(0.25, 0.5, 2.0),
        emission_texture: Some(use_),
        ..SurfaceMaps::default()
    };
    let frame = support::render(&s);
    check_quad(&frame, 16, TOL, |x, y| {
        let uv = DVec2::new((x + 1.0) / 2.0, (1.0 - y) / 2.0);
        let tex = expected(&t, uv, Filter::Nearest, (Wrap::Repeat, Wrap::Repeat));
        std::array::from_fn(|c| 0.5 + emission[c] * tex[c])
    });
}

/// A constant normal map that tilts the normal by 30° towards the tangent,
/// with glTF's `scale`: the Lambert term of a light from (1, 0, 1) is the
/// tilted normal's dot product with it, computed here from the texel bytes.
#[test]
fn a_normal_map_tilts_the_normal_by_a_known_angle() {
    let theta = 30f64.to_radians();
    let byte = |c: f64| ((c + 1.0) / 2.0 * 255.0).round() as u8;
    let texel = [byte(theta.sin()), byte(0.0), byte(theta.cos()), 255];
    let map = Texture {
        label: "normal map".into(),
        file: None,
        width: 2,
        height: 2,
        texels: vec![texel; 4],
        srgb: false,
    };
    for (scale, tangent_w) in [(1.0f32, 1.0), (0.5, -1.0)] {
        let mut mesh = quad(DVec2::ONE);
        mesh.normals = Some(vec![DVec3::Z; 4]);
        mesh.tangents = Some(vec![glam::DVec4::new(1.0, 0.0, 0.0, tangent_w); 4]);
        let white = Texture {
            label: "white".into(),
            file: None,
            width: 1,
            height: 1,
            texels: vec![[255; 4]],
            srgb: true,
        };
        let mut s = scene(mesh, 8, TextureRef::new(0), vec![white, map.clone()]);
        let l = DVec3::new(1.0, 0.0, 1.0).normalize();
        s.lights[0].kind = LightKind::Directional { direction: -l };
        s.objects[0].maps = SurfaceMaps {
            normal: Some((TextureRef::new(1), scale)),
            ..SurfaceMaps::default()
        };
        let frame = support::render(&s);
        // The tangent-space normal from the bytes, with x and y scaled; the
        // tangent is +X, the normal +Z, the bitangent w·(Z × X) = w·Y.
        let t = DVec3::from_array(std::array::from_fn(|c| {
            2.0 * f64::from(texel[c]) / 255.0 - 1.0
        })) * DVec3::new(f64::from(scale), f64::from(scale), 1.0);
        let t = t.normalize();
        let n = DVec3::new(t.x, tangent_w * t.y, t.z);
        let want = n.dot(l);
        // Tilted towards the light: brighter than the untilted cos 45°.
        assert!(want > 0.8, "{want}");
        check_quad(&frame, 8, TOL, |_, _| [want; 3]);
    }
}

/// A ground plane with a fine checker texture (8-texel checks, 8 checks a
/// unit) seen at a grazing angle. Far away a pixel's footprint covers many
/// checks, so its correct (area-averaged) value is the texture's mean,
/// linear 0.5. With mip-maps and ray-cone level of detail the far pixels
/// stay within 0.06 of it; without mip-maps (level 0 only) the same pixels
/// alias to near black or white, which the test also asserts, so it fails if
/// level selection does nothing.
#[test]
fn mip_maps_keep_a_receding_plane_from_aliasing() {
    let side = 64u32;
    let texels = (0..side * side)
        .map(|i| {
            let (x, y) = (i % side, i / side);
            if ((x / 8) + (y / 8)) % 2 == 0 {
                [255, 255, 255, 255]
            } else {
                [0, 0, 0, 255]
            }
        })
        .collect();
    let checks = Texture {
        label: "checks".into(),
        file: None,
        width: side,
        height: side,
        texels,
        srgb: true,
    };
    let (w, h, fov) = (64u32, 48u32, 40.0f64);
    let eye = DVec3::new(0.0, 1.0, 0.0);
    let target = DVec3::new(0.0, 0.0, -20.0);
    let render = |mip: Option<Filter>| {
        let use_ = TextureRef {
            sampler: Sampler {
                mip,
                ..Sampler::default()
            },
            ..TextureRef::new(0)
        };
        let mut s = scene(quad(DVec2::ONE), 8, use_, vec![checks.clone()]);
        s.objects[0].shape = Shape::Plane(penumbra::scene::Plane {
            point: DVec3::ZERO,
            normal: DVec3::Y,
        });
        s.lights[0].kind = LightKind::Directional {
            direction: -DVec3::Y,
        };
        s.camera = Camera {
            position: eye,
            orientation: Camera::look_at(eye, target, DVec3::Y).unwrap(),
            projection: Projection::Perspective { vfov_deg: fov },
            width: w,
            height: h,
        };
        support::render(&s)
    };
    // Pixels whose ray meets the ground more than 12 units away.
    let back = (eye - target).normalize();
    let right = DVec3::Y.cross(back).normalize();
    let up = back.cross(right);
    let hh = (fov.to_radians() / 2.0).tan();
    let hw = hh * f64::from(w) / f64::from(h);
    let mut far = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let sx = ((f64::from(x) + 0.5) / f64::from(w) * 2.0 - 1.0) * hw;
            let sy = (1.0 - (f64::from(y) + 0.5) / f64::from(h) * 2.0) * hh;
            let d = (-back + sx * right + sy * up).normalize();
            if d.y < 0.0 && -eye.y / d.y > 12.0 {
                far.push((y * w + x) as usize);
            }
        }
    }
    assert!(far.len() > 40, "{} far pixels", far.len());
    let worst = |frame: &penumbra::render::Frame| {
        far.iter()
            .map(|&i| (f64::from(frame.image.pixels[i][0]) - 0.5).abs())
            .fold(0.0, f64::max)
    };
    let filtered = worst(&render(Some(Filter::Linear)));
    let aliased = worst(&render(None));
    assert!(
        filtered <= 0.06,
        "trilinear: far pixels {filtered} from the mean"
    );
    assert!(
        aliased > 0.3,
        "level 0 only: far pixels only {aliased} from the mean"
    );
}

/// Replacing a texture's texels on the device changes the next image as
/// the new texture says; a texture of another size is refused.
#[test]
fn a_replaced_texture_shows_in_the_next_render() {
    let use_ = TextureRef {
        sampler: sampler(Filter::Nearest, Wrap::Repeat, Wrap::Repeat),
        ..TextureRef::new(0)
    };
    let old = texture(true);
    let s = scene(quad(DVec2::ONE), 16, use_, vec![old.clone()]);
    s.validate().unwrap();
    let mut new = old.clone();
    new.texels.reverse();
    let mut r = support::renderer();
    let mut up = r.upload(&s).unwrap();
    let before = r
        .render(&up, penumbra::render::RenderRequest::new(16, 16))
        .map(|r| r.frame)
        .unwrap();
    r.replace_texture(&mut up, 0, &new).unwrap();
    let after = r
        .render(&up, penumbra::render::RenderRequest::new(16, 16))
        .map(|r| r.frame)
        .unwrap();
    let bigger = Texture {
        width: 8,
        texels: vec![[0; 4]; 32],
        ..old.clone()
    };
    let refused = r
        .replace_texture(&mut up, 0, &bigger)
        .unwrap_err()
        .to_string();
    drop(r);
    assert!(refused.contains("8×4"), "{refused}");
    let wrap = (Wrap::Repeat, Wrap::Repeat);
    for (frame, t) in [(&before, &old), (&after, &new)] {
        check_quad(frame, 16, TOL, |x, y| {
            let uv = DVec2::new((x + 1.0) / 2.0, (1.0 - y) / 2.0);
            let e = expected(t, uv, Filter::Nearest, wrap);
            [e[0], e[1], e[2]]
        });
    }
}

/// The ground y = 0 seen from straight above (orthographic, window
/// x ∈ [−2, −1], z ∈ [−0.5, 0.5]) in the shadow that a horizontal quad at
/// y = 1 (x, z ∈ [−1, 1], uv = ((x + 1)/2, (z + 1)/2)) casts under a light
/// from (1, 1, 0): ground point (X, Z) sees the light through quad point
/// (X + 1, Z). The quad itself is out of view.
fn shadow_scene(maps: SurfaceMaps, n: u32) -> Scene {
    let use_ = TextureRef {
        sampler: sampler(Filter::Nearest, Wrap::Repeat, Wrap::Repeat),
        ..TextureRef::new(0)
    };
    let mut s = scene(
        Mesh {
            positions: vec![
                DVec3::new(-1.0, 1.0, -1.0),
                DVec3::new(1.0, 1.0, -1.0),
                DVec3::new(1.0, 1.0, 1.0),
                DVec3::new(-1.0, 1.0, 1.0),
            ],
            normals: None,
            indices: vec![[0, 2, 1], [0, 3, 2]],
            uvs: vec![vec![
                DVec2::ZERO,
                DVec2::new(1.0, 0.0),
                DVec2::ONE,
                DVec2::new(0.0, 1.0),
            ]],
            colours: None,
            tangents: None,
        },
        n,
        use_,
        vec![texture(true)],
    );
    s.objects[0].maps = maps;
    s.shaders.push(Shader::Phong(Phong {
        ambient: Vec3::ZERO,
        diffuse: Vec3::ONE,
        specular: Vec3::ZERO,
        shininess: 1.0,
        textures: PhongTextures::default(),
    }));
    s.objects.push(Object {
        shape: Shape::Plane(penumbra::scene::Plane {
            point: DVec3::ZERO,
            normal: DVec3::Y,
        }),
        shader: 1,
        maps: SurfaceMaps::default(),
    });
    s.lights[0].kind = LightKind::Directional {
        direction: -DVec3::new(1.0, 1.0, 0.0).normalize(),
    };
    s.camera = Camera {
        position: DVec3::new(-1.5, 5.0, 0.0),
        orientation: DMat3::from_cols(DVec3::X, -DVec3::Z, DVec3::Y),
        projection: Projection::Orthographic { half_height: 0.5 },
        width: n,
        height: n,
    };
    s
}

/// The quad point (u, v) that ground pixel (x, y) of `shadow_scene` sees
/// the light through.
fn shadow_uv(x: u32, y: u32, n: u32) -> DVec2 {
    let gx = -1.5 + ((f64::from(x) + 0.5) / f64::from(n) * 2.0 - 1.0) * 0.5;
    let gz = -(1.0 - (f64::from(y) + 0.5) / f64::from(n) * 2.0) * 0.5;
    DVec2::new((gx + 1.0 + 1.0) / 2.0, (gz + 1.0) / 2.0)
}

/// A masked quad casts the shadow of its mask: ground points behind a kept
/// texel are dark, those behind a cut texel lit (cos 45° for this light).
#[test]
fn a_mask_casts_a_shadow_of_its_shape() {
    let n = 16;
    let use_ = TextureRef {
        sampler: sampler(Filter::Nearest, Wrap::Repeat, Wrap::Repeat),
        ..TextureRef::new(0)
    };
    let maps = SurfaceMaps {
        alpha_mode: AlphaMode::Mask { cutoff: 0.75 },
        opacity: 1.0,
        opacity_texture: Some(use_),
        ..SurfaceMaps::default()
    };
    let t = texture(true);
    let frame = support::render(&shadow_scene(maps, n));
    let lit = std::f64::consts::FRAC_1_SQRT_2;
    let (mut dark, mut bright) = (0, 0);
    for y in 0..n {
        for x in 0..n {
            let a = expected(
                &t,
                shadow_uv(x, y, n),
                Filter::Nearest,
                (Wrap::Repeat, Wrap::Repeat),
            )[3];
            let want = if a >= 0.75 { 0.0 } else { lit };
            if a >= 0.75 {
                dark += 1;
            } else {
                bright += 1;
            }
            support::assert_rgb(frame.image.pixels[(y * n + x) as usize], [want; 3], 1e-5);
        }
    }
    assert!(dark > 0 && bright > 0, "dark {dark}, bright {bright}");
    // Opaque, the same quad shadows every one of these pixels.
    let frame = support::render(&shadow_scene(SurfaceMaps::default(), n));
    assert!(frame.image.pixels.iter().all(|p| p[0] == 0.0));
}

/// Blending is stochastic transparency: a shadow ray passes a point of
/// alpha 0.3 with probability 0.7. The same seed gives the same image, and
/// the mean over 64 samples a pixel converges to 0.7 of the light: each
/// pixel is a mean of 64 Bernoulli draws (standard deviation 0.057 of the
/// lit value), the mean over 256 pixels has a standard deviation of 0.0036
/// of it; 0.02 is over five of those.
#[test]
fn blending_is_deterministic_and_converges() {
    let n = 16;
    let maps = SurfaceMaps {
        alpha_mode: AlphaMode::Blend,
        opacity: 0.3,
        ..SurfaceMaps::default()
    };
    let s = shadow_scene(maps, n);
    let sampling = |seed| penumbra::render::Sampling {
        spp: 64,
        seed,
        time_budget: None,
    };
    let kernel = support::renderer().kernel();
    let a = support::render_with(&s, kernel, sampling(7));
    let b = support::render_with(&s, kernel, sampling(7));
    let c = support::render_with(&s, kernel, sampling(8));
    assert_eq!(a.image.pixels, b.image.pixels);
    assert_ne!(a.image.pixels, c.image.pixels);
    let lit = std::f64::consts::FRAC_1_SQRT_2;
    let mean = a.image.pixels.iter().map(|p| f64::from(p[0])).sum::<f64>() / f64::from(n * n);
    assert!(
        (mean / lit - 0.7).abs() <= 0.02,
        "mean {mean}, {} of the light",
        mean / lit
    );
}

/// Textures beyond what the device's texture image holds: one error naming
/// the texture that crosses the limit, and the limit (the cap stands in for
/// a device with less room, so that the test needs no gigabyte of texels).
#[test]
fn textures_beyond_the_device_limit_name_the_texture() {
    let use_ = TextureRef::new(0);
    let mut s = scene(
        quad(DVec2::ONE),
        8,
        use_,
        vec![texture(true), texture(true)],
    );
    s.textures[1].label = "second.png".into();
    s.objects[0].maps.emission = Vec3::ONE;
    s.objects[0].maps.emission_texture = Some(TextureRef::new(1));
    s.validate().unwrap();
    let mut r = support::renderer();
    // Each 4×4 texture takes 16 + 4 + 1 texels of 8 bytes: 168 bytes, 176
    // as whole 16-byte texels; the cap fits the first only.
    r.set_texture_capacity(200);
    let err = r.upload(&s).map(|_| ()).unwrap_err().to_string();
    r.set_texture_capacity(u64::MAX);
    let fits = r.upload(&s).map(|_| ());
    drop(r);
    assert!(err.contains("textures[1] (second.png)"), "{err}");
    assert!(err.contains("maxImageDimension2D"), "{err}");
    fits.unwrap();
}

/// GPU against the f64 reference (`penumbra::reference`) on textured
/// scenes: the same rule as tests/gpu/reference.rs, at least 99.5 % of the
/// pixels within 2e-3 per channel. The reference implements the contract
/// of `penumbra::scene::texture` independently, in f64; what differs is
/// f32 rounding, which can move a nearest-texel or mip-level choice at a
/// boundary for a pixel or two.
#[track_caller]
fn agree(name: &str, s: &Scene, spp: u32) {
    let kernel = support::renderer().kernel();
    let sampling = penumbra::render::Sampling {
        spp,
        seed: 7,
        time_budget: None,
    };
    let g = support::render_with(s, kernel, sampling);
    let r = penumbra::reference::render(s, &sampling, kernel.sampler);
    let (mut over, mut worst) = (0, 0.0f64);
    for (a, b) in g.image.pixels.iter().zip(&r.image.pixels) {
        let d = (0..3)
            .map(|c| (f64::from(a[c]) - f64::from(b[c])).abs())
            .fold(0.0, f64::max);
        if d > 2e-3 {
            over += 1;
        }
        worst = worst.max(d);
    }
    let n = g.image.pixels.len();
    let agreeing = 1.0 - over as f64 / n as f64;
    assert!(
        agreeing >= 0.995,
        "{name}: {over} of {n} pixels differ by more than 2e-3 (worst {worst:.3e})"
    );
}

#[test]
fn the_reference_agrees_on_textured_scenes() {
    let t = texture(true);
    for (filter, wrap) in [
        (Filter::Nearest, Wrap::Repeat),
        (Filter::Linear, Wrap::MirroredRepeat),
        (Filter::Linear, Wrap::ClampToEdge),
    ] {
        let use_ = TextureRef {
            sampler: sampler(filter, wrap, Wrap::Repeat),
            transform: UvTransform {
                offset: DVec2::new(0.1, -0.2),
                rotation: 0.3,
                scale: DVec2::new(1.5, 0.75),
            },
            ..TextureRef::new(0)
        };
        let s = scene(quad(DVec2::new(2.5, 1.5)), 32, use_, vec![t.clone()]);
        agree(&format!("quad {filter:?} {wrap:?}"), &s, 1);
    }
    // Mask.
    let use_ = TextureRef {
        sampler: sampler(Filter::Nearest, Wrap::Repeat, Wrap::Repeat),
        ..TextureRef::new(0)
    };
    let mut s = scene(quad(DVec2::ONE), 16, use_, vec![t.clone()]);
    s.objects[0].maps = SurfaceMaps {
        alpha_mode: AlphaMode::Mask { cutoff: 0.6 },
        opacity: 1.0,
        opacity_texture: Some(use_),
        ..SurfaceMaps::default()
    };
    agree("mask", &s, 1);
    let mut s2 = s.clone();
    s2.objects[0].maps.alpha_mode = AlphaMode::Blend;
    agree("blend quad", &s2, 4);
    let maps = SurfaceMaps {
        alpha_mode: AlphaMode::Mask { cutoff: 0.6 },
        opacity: 1.0,
        opacity_texture: Some(use_),
        ..SurfaceMaps::default()
    };
    agree("mask shadow", &shadow_scene(maps, 16), 1);
    let maps = SurfaceMaps {
        alpha_mode: AlphaMode::Blend,
        opacity: 0.3,
        ..SurfaceMaps::default()
    };
    agree("blend shadow", &shadow_scene(maps, 16), 8);
    // Receding plane with mips, and a textured sphere, in perspective.
    let side = 64u32;
    let texels = (0..side * side)
        .map(|i| {
            let (x, y) = (i % side, i / side);
            let v = ((x * 7 + y * 13) % 256) as u8;
            [v, 255 - v, (x * 4) as u8, 255]
        })
        .collect();
    let big = Texture {
        label: "big".into(),
        file: None,
        width: side,
        height: side,
        texels,
        srgb: true,
    };
    for mip in [None, Some(Filter::Nearest), Some(Filter::Linear)] {
        let use_ = TextureRef {
            sampler: Sampler {
                mip,
                ..Sampler::default()
            },
            ..TextureRef::new(0)
        };
        let mut s = scene(quad(DVec2::ONE), 8, use_, vec![big.clone()]);
        s.objects[0].shape = Shape::Plane(penumbra::scene::Plane {
            point: DVec3::ZERO,
            normal: DVec3::Y,
        });
        s.objects.push(Object {
            shape: Shape::Sphere(penumbra::scene::Sphere {
                center: DVec3::new(0.5, 0.7, -4.0),
                radius: 0.7,
            }),
            shader: 0,
            maps: SurfaceMaps {
                emission: Vec3::new(0.1, 0.05, 0.0),
                emission_texture: Some(use_),
                ..SurfaceMaps::default()
            },
        });
        s.lights[0].kind = LightKind::Directional {
            direction: DVec3::new(0.3, -1.0, -0.2).normalize(),
        };
        let eye = DVec3::new(0.0, 1.0, 0.0);
        s.camera = Camera {
            position: eye,
            orientation: Camera::look_at(eye, DVec3::new(0.0, 0.0, -20.0), DVec3::Y).unwrap(),
            projection: Projection::Perspective { vfov_deg: 40.0 },
            width: 64,
            height: 48,
        };
        agree(&format!("plane+sphere mip {mip:?}"), &s, 1);
    }
    // Normal map + vertex colours + emission on a mesh, perspective.
    let theta = 30f64.to_radians();
    let byte = |c: f64| ((c + 1.0) / 2.0 * 255.0).round() as u8;
    let map = Texture {
        label: "normal map".into(),
        file: None,
        width: 2,
        height: 2,
        texels: vec![
            [byte(theta.sin()), 128, byte(theta.cos()), 255],
            [128, byte(theta.sin()), byte(theta.cos()), 255],
            [128, 128, 255, 255],
            [byte(-theta.sin()), 128, byte(theta.cos()), 255],
        ],
        srgb: false,
    };
    let mut mesh = quad(DVec2::ONE);
    mesh.normals = Some(vec![DVec3::Z; 4]);
    mesh.tangents = Some(vec![glam::DVec4::new(1.0, 0.0, 0.0, -1.0); 4]);
    mesh.colours = Some(
        mesh.positions
            .iter()
            .map(|p| glam::Vec4::new(0.5 + 0.25 * p.x as f32, 0.7, 0.4 + 0.2 * p.y as f32, 1.0))
            .collect(),
    );
    let mut s = scene(mesh, 24, TextureRef::new(0), vec![t.clone(), map]);
    s.lights[0].kind = LightKind::Directional {
        direction: -DVec3::new(1.0, 0.5, 1.0).normalize(),
    };
    if let Shader::Phong(p) = &mut s.shaders[0] {
        p.specular = Vec3::splat(0.3);
        p.shininess = 12.0;
        p.ambient = Vec3::splat(0.2);
        p.textures.specular = Some(TextureRef::new(0));
    }
    s.lights[0].ambient = Vec3::splat(0.1);
    s.objects[0].maps = SurfaceMaps {
        normal: Some((TextureRef::new(1), 0.8)),
        emission: Vec3::new(0.05, 0.1, 0.0),
        ..SurfaceMaps::default()
    };
    let eye = DVec3::new(0.3, 0.4, 3.0);
    s.camera = Camera {
        position: eye,
        orientation: Camera::look_at(eye, DVec3::ZERO, DVec3::Y).unwrap(),
        projection: Projection::Perspective { vfov_deg: 50.0 },
        width: 32,
        height: 32,
    };
    agree("normal map colours", &s, 1);
}
