//! glTF's `occlusionTexture` (glTF 2.0, material.occlusionTexture: it
//! applies to indirect lighting): the environment's light on a point is
//! scaled by `1 + strength × (R − 1)`, R the texture's red channel
//! (linear); punctual lights are not. Two quads side by side fill the
//! image, seen head-on by an orthographic camera along −Z: the left one's
//! occlusion texture has R = 64/255, the right one's R = 1 (factor 1). Each
//! render is compared, pixel by pixel, with the same scene without
//! occlusion textures: same seed, so the same environment directions.

use glam::{DVec3, Vec3};
use penumbra::render::Image;
use penumbra::scene::{
    Light, LightKind, Object, Phong, Scene, Shader, Shape, SurfaceMaps, Texture, TextureRef,
    Triangle,
};

use crate::support;

const WIDTH: u32 = 32;
const HEIGHT: u32 = 16;
/// The left quad's occlusion texel (linear, so R = 64/255 exactly).
const LEFT_R: u8 = 64;

/// The lights a scene has.
#[derive(Clone, Copy, PartialEq)]
pub enum Lights {
    Environment,
    Point,
    Both,
}

/// The two quads under `lights`, with occlusion textures of `strength`
/// when it is given.
pub fn scene(lights: Lights, strength: Option<f32>) -> Scene {
    let quad = |x0: f64, x1: f64| {
        let c = |x: f64, y: f64| DVec3::new(x, y, 0.0);
        // Counter-clockwise seen from +Z.
        [
            [c(x0, -1.5), c(x1, -1.5), c(x1, 1.5)],
            [c(x0, -1.5), c(x1, 1.5), c(x0, 1.5)],
        ]
    };
    let texture = |r: u8| Texture {
        label: format!("occlusion {r}"),
        file: None,
        width: 1,
        height: 1,
        texels: vec![[r, 0, 0, 255]],
        srgb: false,
    };
    let mut objects = Vec::new();
    for (k, x) in [(0, [-2.5, 0.0]), (1, [0.0, 2.5])] {
        let maps = SurfaceMaps {
            occlusion: strength.map(|s| (TextureRef::new(k), s)),
            ..SurfaceMaps::NONE
        };
        objects.extend(quad(x[0], x[1]).map(|vertices| Object {
            maps,
            shape: Shape::Triangle(Triangle { vertices }),
            shader: 0,
        }));
    }
    let environment = Light {
        kind: LightKind::Environment {
            up: DVec3::new(0.2, 1.0, 0.3).normalize(),
            samples: 4,
        },
        intensity: 1.5,
        ambient: Vec3::ZERO,
        diffuse: Vec3::new(1.0, 0.9, 0.8),
        specular: Vec3::ONE,
    };
    let point = Light {
        kind: LightKind::Point {
            position: DVec3::new(0.5, 0.5, 3.0),
        },
        intensity: 2.0,
        ambient: Vec3::new(0.05, 0.05, 0.05),
        diffuse: Vec3::new(0.5, 0.7, 1.0),
        specular: Vec3::ONE,
    };
    let lights = match lights {
        Lights::Environment => vec![environment],
        Lights::Point => vec![point],
        // The environment first: its samples then draw the same random
        // numbers as in the environment-only scene.
        Lights::Both => vec![environment, point],
    };
    Scene {
        textures: match strength {
            Some(_) => vec![texture(LEFT_R), texture(255)],
            None => vec![],
        },
        camera: support::front_on(1.0, WIDTH, HEIGHT),
        background: Vec3::ZERO,
        shaders: vec![Shader::Phong(Phong {
            textures: Default::default(),
            ambient: Vec3::new(0.1, 0.2, 0.3),
            diffuse: Vec3::new(0.8, 0.6, 0.4),
            specular: Vec3::new(0.3, 0.3, 0.3),
            shininess: 10.0,
        })],
        objects,
        lights,
    }
}

/// glTF's occlusion factor for the left quad.
fn factor(strength: f32) -> f64 {
    1.0 + strength as f64 * (LEFT_R as f64 / 255.0 - 1.0)
}

/// Whether pixel `i` lies on the left quad (x = 0 falls between columns).
fn left(i: usize) -> bool {
    (i % WIDTH as usize) < WIDTH as usize / 2
}

fn image(lights: Lights, strength: Option<f32>) -> Image {
    support::render(&scene(lights, strength)).image
}

/// Asserts `got` = `want` within 2·10⁻⁶ relative (f32 rounding of a sum of
/// a few samples, each scaled once).
#[track_caller]
fn assert_close(got: f64, want: f64, at: usize) {
    assert!(
        (got - want).abs() <= 2e-6 * want.abs().max(1e-3),
        "pixel {at}: got {got}, want {want}"
    );
}

#[test]
fn occlusion_scales_the_environment_light() {
    let plain = image(Lights::Environment, None);
    assert!(
        plain.pixels.iter().all(|p| p[0] > 0.05),
        "every pixel is lit by the environment"
    );
    for strength in [1.0, 0.5] {
        let occluded = image(Lights::Environment, Some(strength));
        let f = factor(strength);
        for (i, (o, p)) in occluded.pixels.iter().zip(&plain.pixels).enumerate() {
            if left(i) {
                for c in 0..3 {
                    assert_close(o[c] as f64, f * p[c] as f64, i);
                }
            } else {
                // R = 1: factor 1 whatever the strength.
                assert_eq!(o, p, "pixel {i} of the right quad, strength {strength}");
            }
        }
    }
}

#[test]
fn occlusion_leaves_punctual_light_alone() {
    let plain = image(Lights::Point, None);
    let occluded = image(Lights::Point, Some(1.0));
    // Lit by the light, beyond the ambient term (0.1 × 0.05).
    assert!(plain.pixels.iter().all(|p| p[0] > 0.01));
    assert_eq!(occluded.pixels, plain.pixels, "bit-identical");
}

#[test]
fn occlusion_scales_only_the_environment_beside_a_point_light() {
    // Both lights: the point light's share unchanged, the environment's
    // scaled on the left quad.
    let environment = image(Lights::Environment, None);
    let point = image(Lights::Point, None);
    let strength = 1.0;
    let both = image(Lights::Both, Some(strength));
    for (i, b) in both.pixels.iter().enumerate() {
        let f = if left(i) { factor(strength) } else { 1.0 };
        let (p, e) = (point.pixels[i], environment.pixels[i]);
        for (c, got) in b[..3].iter().enumerate() {
            assert_close(*got as f64, p[c] as f64 + f * e[c] as f64, i);
        }
    }
}
