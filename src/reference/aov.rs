//! Arbitrary output variables from the reference: what the primary ray of
//! each pixel's first pass sees, numbered like the GPU's
//! ([`crate::frame::Aovs`]), in f64 and then rounded once to f32.

use rayon::prelude::*;

use super::hit::Kind;
use super::surface::AlphaRay;
use super::{hit, sampling, World};
use crate::frame::{Aovs, Sampling};
use crate::scene::{Scene, Shape};

/// The AOVs of `scene` as `render` would see them in pass 0.
pub(super) fn aovs(world: &World, scene: &Scene, sampling: &Sampling) -> Aovs {
    // Which object each plane, sphere and triangle came from, and the index
    // of each object's first triangle (the World lists them in scene order).
    let (mut planes, mut spheres, mut triangles, mut first) = (vec![], vec![], vec![], vec![]);
    for (i, o) in scene.objects.iter().enumerate() {
        let i = i as u32;
        first.push(triangles.len() as u32);
        match &o.shape {
            Shape::Plane(_) => planes.push(i),
            Shape::Sphere(_) => spheres.push(i),
            Shape::Triangle(_) => triangles.push(i),
            Shape::Mesh(m) => triangles.extend(std::iter::repeat_n(i, m.indices.len())),
        }
    }
    let (width, height) = (scene.camera.width, scene.camera.height);
    let jitter = sampling.spp > 1;
    let per_pixel: Vec<_> = (0..width * height)
        .into_par_iter()
        .map(|pixel| {
            let (x, y) = (pixel % width, pixel / width);
            let sub = if jitter {
                sampling::sample_2d(world.sampler, world.seed, pixel, 0, 0)
            } else {
                [0.5, 0.5]
            };
            let ray = world.camera.primary_ray(x, y, width, height, sub);
            hit::closest_hit(world, &ray, AlphaRay::camera(pixel, 0)).map(|h| {
                let (object, primitive, uv) = match h.kind {
                    Kind::Plane => (planes[h.index as usize], 0, [0.0; 2]),
                    Kind::Sphere => (spheres[h.index as usize], 0, [0.0; 2]),
                    Kind::Triangle => {
                        let o = triangles[h.index as usize];
                        (o, h.index - first[o as usize], [h.u as f32, h.v as f32])
                    }
                };
                (
                    h.t as f32,
                    h.geometric_normal.as_vec3().to_array(),
                    uv,
                    object,
                    primitive,
                )
            })
        })
        .collect();
    let mut a = Aovs::default();
    for p in per_pixel {
        let (t, n, uv, object, primitive) =
            p.unwrap_or((f32::INFINITY, [0.0; 3], [0.0; 2], u32::MAX, u32::MAX));
        a.depth.push(t);
        a.normal.push(n);
        a.uv.push(uv);
        a.object.push(object);
        a.primitive.push(primitive);
    }
    a
}
