//! KHR_materials_unlit's colour is base colour × texture × vertex colour
//! (the extension's specification, "Example"): penumbra emits it, and the
//! vertex colour scales that emission only where the surface maps say so
//! (`emission_by_colour`); other emission is not scaled. A triangle with
//! red, green and blue vertices, a white emission and a black Phong shader,
//! seen head-on by an orthographic camera along −Z with no light: the centre
//! pixel is the colour interpolated at the image's centre.

use glam::{DVec2, DVec3, Vec3};
use penumbra::scene::{Mesh, Object, Phong, Scene, Shader, Shape, SurfaceMaps};

use crate::support;

/// Odd, so that a pixel centre lies at the image's centre (0, 0).
const SIZE: u32 = 9;
const VERTICES: [[f64; 2]; 3] = [[-1.0, -1.0], [3.0, -1.0], [-1.0, 1.0]];
const COLOURS: [[f32; 3]; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// The triangle, its emission scaled by its vertex colours or not.
pub fn scene(emission_by_colour: bool) -> Scene {
    let mesh = Mesh {
        positions: VERTICES
            .iter()
            .map(|&[x, y]| DVec3::new(x, y, 0.0))
            .collect(),
        normals: None,
        indices: vec![[0, 1, 2]],
        uvs: vec![],
        colours: Some(COLOURS.iter().map(|&c| Vec3::from(c).extend(1.0)).collect()),
        tangents: None,
    };
    Scene {
        textures: vec![],
        camera: support::front_on(2.0, SIZE, SIZE),
        background: Vec3::ZERO,
        shaders: vec![Shader::Phong(Phong {
            textures: Default::default(),
            ambient: Vec3::ZERO,
            diffuse: Vec3::ZERO,
            specular: Vec3::ZERO,
            shininess: 1.0,
        })],
        objects: vec![Object {
            shape: Shape::Mesh(mesh),
            shader: 0,
            maps: SurfaceMaps {
                emission: Vec3::ONE,
                emission_by_colour,
                ..SurfaceMaps::NONE
            },
        }],
        lights: vec![],
    }
}

/// The vertex colour interpolated at (0, 0): its barycentric coordinates
/// from the vertices, solved here.
pub fn centre_colour() -> [f64; 3] {
    let [a, b, c] = VERTICES.map(|[x, y]| DVec2::new(x, y));
    let (e1, e2, p) = (b - a, c - a, -a);
    let det = e1.perp_dot(e2);
    let u = p.perp_dot(e2) / det;
    let v = e1.perp_dot(p) / det;
    let w = [1.0 - u - v, u, v];
    let colour = |k: usize| (0..3).map(|i| w[i] * COLOURS[i][k] as f64).sum();
    [colour(0), colour(1), colour(2)]
}

fn centre_pixel(scene: &Scene) -> [f32; 4] {
    let frame = support::render(scene);
    let s = SIZE as usize;
    frame.image.pixels[(s / 2) * s + s / 2]
}

#[test]
fn unlit_emission_is_scaled_by_the_vertex_colour() {
    let want = centre_colour();
    // The centre is inside the triangle, not at a vertex or the centroid.
    assert_eq!(want, [0.25, 0.25, 0.5]);
    support::assert_rgb(centre_pixel(&scene(true)), want, 1e-5);
}

#[test]
fn other_emission_is_not_scaled_by_the_vertex_colour() {
    support::assert_rgb(centre_pixel(&scene(false)), [1.0, 1.0, 1.0], 0.0);
}
