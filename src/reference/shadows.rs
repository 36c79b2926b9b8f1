//! Hard shadows as `shaders/shadows.wgsl` casts them: one any-hit shadow ray
//! per light sample, without a fixed epsilon.
//!
//! * A plane or triangle cannot shadow itself: the shadow ray skips the
//!   primitive it starts on.
//! * A sphere shadows a point on itself exactly when the ray heads into it,
//!   along the chord `2·l·(c − p)`: decided analytically.
//! * From a triangle the origin moves off the surface along the geometric
//!   normal (towards the light, which the first rule guarantees), so that
//!   neighbouring mesh triangles do not catch the ray at `t ≈ 0` through
//!   rounding. The GPU moves it by 256 `f32` ulps of the camera-relative
//!   position (Wächter and Binder, "A Fast and Robust Method for Avoiding
//!   Self-Intersection", Ray Tracing Gems, 2019); here the offset is
//!   [`OFFSET_SCALE`] (2⁻³²) times the magnitude of the coordinates involved
//!   (hit point, primary-ray origin, distance), about 10⁶ times the `f64`
//!   rounding error of the hit point and 10⁻⁴ of the GPU's offset, so only
//!   occluders closer than that to the surface (concave creases right at the
//!   point) are treated differently.
//!
//! [`crate::render::ShadowOffset::Fixed`] is a GPU approximation of this and
//! is not reproduced: the reference is the ground truth it is measured
//! against.

use glam::DVec3;

use super::bvh::PRIM_SPHERE;
use super::hit::{Hit, Kind};
use super::intersect::{self, Ray};
use super::lights::LightSample;
use super::surface::{self, AlphaRay};
use super::World;

/// Relative offset of a shadow ray leaving a triangle (see the module docs).
pub const OFFSET_SCALE: f64 = 1.0 / 4_294_967_296.0;

/// Whether anything blocks the light sample `ls` from `hit`. In scenes
/// with `Mask` or `Blend` objects (triangles only: validation) a blocking
/// triangle must pass the alpha test of `alpha_ray`
/// ([`surface::is_there`]).
pub fn occluded(world: &World, hit: &Hit, ls: &LightSample, alpha_ray: AlphaRay) -> bool {
    // (shade() only asks for lights above the geometric surface.)
    let origin = if hit.kind == Kind::Triangle {
        hit.position + hit.geometric_normal * (hit.error_scale * OFFSET_SCALE)
    } else {
        hit.position
    };
    let ray = Ray::new(origin, ls.to_light);
    let t_max = ls.distance;
    for (i, p) in world.planes.iter().enumerate() {
        if hit.kind == Kind::Plane && hit.index == i as u32 {
            continue;
        }
        let t = intersect::plane(p.point, p.normal, &ray);
        if t > 0.0 && t < t_max {
            return true;
        }
    }
    world.accel.any(&ray, t_max, |prim| {
        if prim & PRIM_SPHERE != 0 {
            sphere_blocks(world, prim & !PRIM_SPHERE, &ray, t_max, hit)
        } else {
            !(hit.kind == Kind::Triangle && hit.index == prim)
                && intersect::triangle(&world.triangles[prim as usize], &ray, t_max).is_some_and(
                    |(t, u, v)| {
                        !world.alpha || surface::is_there(world, alpha_ray, prim, u, v, ray.at(t))
                    },
                )
        }
    })
}

/// Whether sphere `i` blocks the shadow ray that leaves `start`.
fn sphere_blocks(world: &World, i: u32, ray: &Ray, t_max: f64, start: &Hit) -> bool {
    let s = &world.spheres[i as usize];
    if start.kind == Kind::Sphere && start.index == i {
        let into = ray.dir.dot(s.center - start.position);
        return into > 0.0 && 2.0 * into < t_max;
    }
    let (near, far) = intersect::sphere_roots(s.center, s.radius, ray);
    // Either root inside (0, t_max) blocks; a ray starting inside a sphere
    // is blocked by its far side.
    near <= far && ((near > 0.0 && near < t_max) || (far > 0.0 && far < t_max))
}

/// The magnitude the rounding error of a hit point scales with.
pub fn error_scale(origin: DVec3, position: DVec3, t: f64) -> f64 {
    origin
        .abs()
        .max_element()
        .max(position.abs().max_element())
        .max(t)
}
