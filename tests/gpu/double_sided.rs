//! glTF's `doubleSided: false` (glTF 2.0, material.doubleSided): camera rays
//! pass through the back face of a single-sided triangle; shadow rays do
//! not (a single-sided occluder still casts its shadow). A red quad at
//! y = 0.5 over a blue floor, seen from straight above and lit from
//! straight above; the quad faces up (its counter-clockwise front, the side
//! of (v1 − v0) × (v2 − v0)) or, flipped, down.

use glam::{DVec3, Vec3};
use penumbra::scene::{
    Light, LightKind, Object, Phong, Plane, Scene, Shader, Shape, SurfaceMaps, Triangle,
};

use crate::support;

fn lambert(rgb: [f32; 3]) -> Shader {
    Shader::Phong(Phong {
        textures: Default::default(),
        ambient: Vec3::ZERO,
        diffuse: Vec3::from(rgb),
        specular: Vec3::ZERO,
        shininess: 1.0,
    })
}

/// The quad facing up (`flipped`: down), single- or double-sided.
pub fn scene(flipped: bool, double_sided: bool) -> Scene {
    let y = 0.5;
    let c = |x: f64, z: f64| DVec3::new(x, y, z);
    // (v1 − v0) × (v2 − v0) = +Y for both triangles as listed.
    let mut tris = [
        [c(-0.5, -0.5), c(-0.5, 0.5), c(0.5, 0.5)],
        [c(-0.5, -0.5), c(0.5, 0.5), c(0.5, -0.5)],
    ];
    if flipped {
        for t in &mut tris {
            t.swap(1, 2);
        }
    }
    let maps = SurfaceMaps {
        double_sided,
        ..SurfaceMaps::NONE
    };
    let mut objects = vec![Object {
        maps: SurfaceMaps::NONE,
        shape: Shape::Plane(Plane {
            point: DVec3::ZERO,
            normal: DVec3::Y,
        }),
        shader: 0,
    }];
    objects.extend(tris.map(|vertices| Object {
        maps,
        shape: Shape::Triangle(Triangle { vertices }),
        shader: 1,
    }));
    Scene {
        textures: vec![],
        camera: support::top_down(1.0, 32),
        background: Vec3::new(0.2, 0.2, 0.2),
        shaders: vec![lambert([0.0, 0.0, 0.8]), lambert([0.8, 0.0, 0.0])],
        objects,
        lights: vec![Light {
            kind: LightKind::Directional {
                direction: DVec3::NEG_Y,
            },
            intensity: 1.0,
            ambient: Vec3::ZERO,
            diffuse: Vec3::ONE,
            specular: Vec3::ZERO,
        }],
    }
}

/// The pixel at the image's centre (inside the quad) and one in a corner
/// (outside it, on the lit floor).
fn centre_and_corner(scene: &Scene) -> ([f32; 4], [f32; 4]) {
    let frame = support::render(scene);
    let w = frame.image.width as usize;
    let centre = frame.image.pixels[(w / 2) * w + w / 2];
    (centre, frame.image.pixels[w + 1])
}

#[test]
fn a_single_sided_quad_is_seen_from_its_front() {
    let (centre, corner) = centre_and_corner(&scene(false, false));
    // Lit head-on: Lambert's 0.8 red; the floor outside is lit blue.
    support::assert_rgb(centre, [0.8, 0.0, 0.0], 1e-4);
    support::assert_rgb(corner, [0.0, 0.0, 0.8], 1e-4);
}

#[test]
fn camera_rays_pass_through_the_back_of_a_single_sided_quad_and_it_still_casts_its_shadow() {
    let (centre, corner) = centre_and_corner(&scene(true, false));
    // The floor under the quad, in the quad's shadow (no ambient): black,
    // where a double-sided quad would show its red back.
    support::assert_rgb(centre, [0.0, 0.0, 0.0], 1e-4);
    support::assert_rgb(corner, [0.0, 0.0, 0.8], 1e-4);
}

#[test]
fn a_double_sided_quad_is_seen_from_its_back() {
    let (centre, _) = centre_and_corner(&scene(true, true));
    // Its back, turned to face the ray, lit head-on.
    support::assert_rgb(centre, [0.8, 0.0, 0.0], 1e-4);
}
