//! The nearest intersection along a ray and the normals it carries back, as
//! `closest_hit` and `finish_hit` in `shaders/hit.wgsl`.

use glam::DVec3;

use super::bvh::PRIM_SPHERE;
use super::intersect::{self, Ray, FAR};
use super::surface::{self, AlphaRay, Surface};
use super::{texture, World};

/// Which kind of primitive a hit is on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// An infinite plane.
    Plane,
    /// A sphere.
    Sphere,
    /// A triangle (single or from a mesh).
    Triangle,
}

/// The nearest hit of a ray.
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    /// Distance along the ray.
    pub t: f64,
    /// Kind of primitive, and index into that kind's list.
    pub kind: Kind,
    /// Index into [`World`]'s planes, spheres or triangles.
    pub index: u32,
    /// Barycentric weights of a triangle's `v1` and `v2`.
    pub u: f64,
    /// See `u`.
    pub v: f64,
    /// Hit point, world coordinates.
    pub position: DVec3,
    /// Unit geometric normal, turned towards the incoming ray.
    pub geometric_normal: DVec3,
    /// Unit shading normal (interpolated vertex normal where the mesh has
    /// them, tilted by the normal map where the object has one), turned
    /// towards the incoming ray.
    pub shading_normal: DVec3,
    /// Uv, colour, tangent and level of detail at the hit, in scenes with
    /// textures, vertex colours or surface maps (`None` in the others).
    pub surface: Option<Surface>,
    /// Index into the scene's shaders.
    pub shader: u32,
    /// Magnitude of the coordinates that went into `position` (its rounding
    /// error is a few `f64` ulps of this): sizes the shadow-ray offset.
    pub error_scale: f64,
}

/// Nearest hit over every primitive: planes one by one, spheres and
/// triangles through the BVH. `None` when the ray hits nothing. In scenes
/// with `Mask` or `Blend` objects (triangles only: validation) every
/// candidate triangle must pass the alpha test ([`surface::is_there`]) of
/// `alpha_ray`; `ray` is a camera ray (the level of detail of its hit is
/// the primary ray cone's).
pub fn closest_hit(world: &World, ray: &Ray, alpha_ray: AlphaRay) -> Option<Hit> {
    let mut best: Option<(f64, Kind, u32, f64, f64)> = None;
    let mut t_best = FAR;
    for (i, p) in world.planes.iter().enumerate() {
        let t = intersect::plane(p.point, p.normal, ray);
        if t > 0.0 && t < t_best {
            t_best = t;
            best = Some((t, Kind::Plane, i as u32, 0.0, 0.0));
        }
    }
    world.accel.closest(ray, t_best, |prim, t_max| {
        if prim & PRIM_SPHERE != 0 {
            let i = prim & !PRIM_SPHERE;
            let s = &world.spheres[i as usize];
            let t = intersect::sphere(s.center, s.radius, ray);
            if t > 0.0 && t < t_max {
                best = Some((t, Kind::Sphere, i, 0.0, 0.0));
                return t;
            }
        } else if let Some((t, u, v)) =
            intersect::triangle(&world.triangles[prim as usize], ray, t_max)
        {
            if faces_the_ray(world, prim, ray)
                && (!world.alpha || surface::is_there(world, alpha_ray, prim, u, v, ray.at(t)))
            {
                best = Some((t, Kind::Triangle, prim, u, v));
                return t;
            }
        }
        t_max
    });
    let (t, kind, index, u, v) = best?;
    Some(finish_hit(world, ray, t, kind, index, u, v))
}

/// Whether a camera ray sees triangle `prim`: always, but for a
/// single-sided one (glTF's `doubleSided: false`) hit from its back, where
/// the ray meets the side its normal `(v1 − v0) × (v2 − v0)` points away
/// from (`faces_the_ray` in `shaders/hit.wgsl`). Shadow rays do not ask.
fn faces_the_ray(world: &World, prim: u32, ray: &Ray) -> bool {
    let tri = &world.triangles[prim as usize];
    tri.normal.dot(ray.dir) < 0.0
        || world.objects[world.triangle_objects[prim as usize] as usize]
            .maps
            .double_sided
}

/// Position, normals (both turned to face the ray: surfaces are two-sided)
/// and shader of a hit.
fn finish_hit(world: &World, ray: &Ray, t: f64, kind: Kind, index: u32, u: f64, v: f64) -> Hit {
    let p = ray.at(t);
    let (mut ng, mut ns, shader) = match kind {
        Kind::Plane => {
            let plane = &world.planes[index as usize];
            (plane.normal, plane.normal, plane.shader)
        }
        Kind::Sphere => {
            let s = &world.spheres[index as usize];
            let n = (p - s.center).normalize();
            (n, n, s.shader)
        }
        Kind::Triangle => {
            let tri = &world.triangles[index as usize];
            let ng = tri.normal;
            let ns = match tri.normals {
                Some(k) => {
                    let [n0, n1, n2] = world.vertex_normals[k as usize];
                    let n = (1.0 - u - v) * n0 + u * n1 + v * n2;
                    let len2 = n.dot(n);
                    // Opposite normals can cancel: the flat normal then.
                    if len2 > 1e-12 {
                        n / len2.sqrt()
                    } else {
                        ng
                    }
                }
                None => ng,
            };
            (ng, ns, tri.shader)
        }
    };
    let surface = world.textured.then(|| {
        let mut s = surface::at(world, kind, index, u, v, p);
        // The primary ray cone's width at the hit, over the cosine with the
        // geometric normal, and each uv set's area ratio (Ray Tracing Gems
        // ch. 20).
        let cone = texture::cone_width(world.pixel_spread, world.orthographic, t);
        let cos = ng.dot(ray.dir);
        s.lod_base = s.uv_per_world.map(|r| texture::lod_base(cone, cos, r));
        s
    });
    if let Some(s) = &surface {
        let object = surface::object_of(world, kind, index) as usize;
        if let (Some((t, scale)), Some(tangent)) = (world.objects[object].maps.normal, s.tangent) {
            let texel = s.sample(world, &t);
            ns = texture::normal_mapped(ns, tangent, texel.truncate(), f64::from(scale));
        }
    }
    if ng.dot(ray.dir) > 0.0 {
        ng = -ng;
    }
    if ns.dot(ray.dir) > 0.0 {
        ns = -ns;
    }
    Hit {
        t,
        kind,
        index,
        u,
        v,
        position: p,
        geometric_normal: ng,
        shading_normal: ns,
        surface,
        shader,
        error_scale: super::shadows::error_scale(ray.origin, p, t),
    }
}
