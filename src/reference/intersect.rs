//! Rays and the three primitives' intersection tests in `f64`, with the
//! formulas of `shaders/ray.wgsl` and `shaders/primitives/`.
//!
//! Triangles always use the watertight test of Woop, Benthin and Wald
//! ("Watertight Ray/Triangle Intersection", JCGT 2013), the GPU's default
//! ([`crate::render::TriangleTest::Watertight`]), here in `f64`: it agrees
//! with the GPU on hit or miss except within `f32` rounding of an edge, and
//! no ray slips between triangles that share an edge (the edge functions of
//! a shared edge are computed from the same numbers on both sides, and exact
//! zeros count as inside on both).

use glam::DVec3;

/// Farther than anything in a scene: "no hit yet", and the length of shadow
/// rays towards directional lights (the kernel's `FAR`).
pub const FAR: f64 = 3.0e38;

/// A ray with what the watertight triangle test needs of it.
#[derive(Clone, Copy, Debug)]
pub struct Ray {
    /// Origin, world coordinates.
    pub origin: DVec3,
    /// Unit direction.
    pub dir: DVec3,
    /// Axes: `k[2]` is where |dir| is largest, `k[0]`, `k[1]` the others
    /// (swapped when dir is negative along `k[2]`, keeping the winding).
    k: [usize; 3],
    /// Shear mapping `dir` onto +z: (dx/dz, dy/dz, 1/dz) in the permuted axes.
    shear: [f64; 3],
    /// 1/dir with zero components replaced by a tiny value of the same sign
    /// (the BVH slab test).
    pub inv_dir: DVec3,
}

impl Ray {
    /// The ray from `origin` along the unit vector `dir`.
    pub fn new(origin: DVec3, dir: DVec3) -> Ray {
        let a = dir.abs();
        let kz = if a.x > a.y && a.x > a.z {
            0
        } else if a.y > a.z {
            1
        } else {
            2
        };
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        if dir[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        const TINY: f64 = 1e-200;
        let safe = |d: f64| {
            if d.abs() < TINY {
                1.0 / TINY.copysign(if d >= 0.0 { 1.0 } else { -1.0 })
            } else {
                1.0 / d
            }
        };
        Ray {
            origin,
            dir,
            k: [kx, ky, kz],
            shear: [dir[kx] / dir[kz], dir[ky] / dir[kz], 1.0 / dir[kz]],
            inv_dir: DVec3::new(safe(dir.x), safe(dir.y), safe(dir.z)),
        }
    }

    /// The point at distance `t`.
    pub fn at(&self, t: f64) -> DVec3 {
        self.origin + t * self.dir
    }
}

/// Distance to the plane through `point` with unit `normal`, or a value ≤ 0
/// (never a hit) when the ray is parallel or the plane lies behind.
pub fn plane(point: DVec3, normal: DVec3, ray: &Ray) -> f64 {
    let denom = normal.dot(ray.dir);
    if denom == 0.0 {
        return -1.0;
    }
    normal.dot(point - ray.origin) / denom
}

/// Both roots along the ray, nearest first, with `x > y` when it misses: the
/// discriminant from the centre's distance to the ray line and the near root
/// as `c / q` (Haines et al., "Precision Improvements for Ray/Sphere
/// Intersection", Ray Tracing Gems, 2019), exactly as `sphere_roots`.
pub fn sphere_roots(center: DVec3, radius: f64, ray: &Ray) -> (f64, f64) {
    let f = ray.origin - center;
    let b = f.dot(ray.dir);
    let perp = f - b * ray.dir;
    let r2 = radius * radius;
    let disc = r2 - perp.dot(perp);
    if disc < 0.0 {
        return (1.0, -1.0);
    }
    let c = f.dot(f) - r2;
    // WGSL `select(-1, 1, b >= 0)`: −0 counts as positive, unlike copysign.
    let sign = if b >= 0.0 { 1.0 } else { -1.0 };
    let q = -b - sign * disc.sqrt();
    if q == 0.0 {
        return (0.0, 0.0);
    }
    let t0 = c / q;
    (t0.min(q), t0.max(q))
}

/// Nearest positive distance to the sphere, or a value ≤ 0 for a miss.
pub fn sphere(center: DVec3, radius: f64, ray: &Ray) -> f64 {
    let (near, far) = sphere_roots(center, radius, ray);
    if near > far {
        return -1.0;
    }
    if near > 0.0 {
        near
    } else {
        far
    }
}

/// A triangle as the reference stores it.
#[derive(Clone, Copy, Debug)]
pub struct Triangle {
    /// Vertices, world coordinates.
    pub v: [DVec3; 3],
    /// Unit geometric normal `(v1 − v0) × (v2 − v0)` normalised (zero for a
    /// degenerate triangle, which is never hit).
    pub normal: DVec3,
    /// Whether the cross product is exactly zero (zero area).
    pub degenerate: bool,
    /// Index into the scene's shaders.
    pub shader: u32,
    /// Index into the vertex-normal table, if the mesh has normals.
    pub normals: Option<u32>,
}

impl Triangle {
    /// A triangle with its normal precomputed.
    pub fn new(v: [DVec3; 3], shader: u32, normals: Option<u32>) -> Triangle {
        let n = (v[1] - v[0]).cross(v[2] - v[0]);
        let degenerate = n.dot(n) == 0.0;
        Triangle {
            v,
            normal: if degenerate {
                DVec3::ZERO
            } else {
                n.normalize()
            },
            degenerate,
            shader,
            normals,
        }
    }
}

/// Woop, Benthin and Wald's watertight test, in the kernel's order (edge
/// functions first, rejecting as soon as their signs differ, then t): returns
/// `(t, u, v)` with `u`, `v` the weights of `v1` and `v2`, for a hit with
/// `0 < t < t_max`.
pub fn triangle(tri: &Triangle, ray: &Ray, t_max: f64) -> Option<(f64, f64, f64)> {
    let [kx, ky, kz] = ray.k;
    let [sx, sy, sz] = ray.shear;
    let a = tri.v[0] - ray.origin;
    let b = tri.v[1] - ray.origin;
    let c = tri.v[2] - ray.origin;
    let ax = a[kx] - sx * a[kz];
    let ay = a[ky] - sy * a[kz];
    let bx = b[kx] - sx * b[kz];
    let by = b[ky] - sy * b[kz];
    let cx = c[kx] - sx * c[kz];
    let cy = c[ky] - sy * c[kz];
    let u = cx * by - cy * bx;
    let v = ax * cy - ay * cx;
    if (u < 0.0 || v < 0.0) && (u > 0.0 || v > 0.0) {
        return None;
    }
    let w = bx * ay - by * ax;
    if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
        return None;
    }
    let det = u + v + w;
    // A zero-area triangle can pass the sign tests through the rounding of
    // the shear; reject it by its true area (as the kernel and pbrt-v4 do).
    if det == 0.0 || tri.degenerate {
        return None;
    }
    let t_scaled = u * (sz * a[kz]) + v * (sz * b[kz]) + w * (sz * c[kz]);
    let inv = 1.0 / det;
    let t = t_scaled * inv;
    // NaN fails both comparisons.
    (t > 0.0 && t < t_max).then_some((t, v * inv, w * inv))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_crack_ray_hits_the_shared_diagonal() {
        // The quad of issue 4, split along its diagonal; the float32
        // Möller–Trumbore misses both halves.
        let s = DVec3::new;
        let t1 = Triangle::new([s(-5., -5., 0.), s(5., -5., 0.), s(5., 5., 0.)], 0, None);
        let t2 = Triangle::new([s(-5., -5., 0.), s(5., 5., 0.), s(-5., 5., 0.)], 0, None);
        let d = s(0.30458447, 0.30458447, -0.9024725).normalize();
        let ray = Ray::new(s(0.0, 0.0, 10.0), d);
        let h1 = triangle(&t1, &ray, FAR);
        let h2 = triangle(&t2, &ray, FAR);
        assert!(h1.is_some() || h2.is_some());
        let t = h1.or(h2).unwrap().0;
        assert!((ray.at(t).z).abs() < 1e-12);
    }

    #[test]
    fn barycentrics_are_the_weights_of_v1_and_v2() {
        let tri = Triangle::new([DVec3::ZERO, DVec3::X, DVec3::Y], 0, None);
        let ray = Ray::new(DVec3::new(0.25, 0.5, 2.0), -DVec3::Z);
        let (t, u, v) = triangle(&tri, &ray, FAR).unwrap();
        assert!((t - 2.0).abs() < 1e-15 && (u - 0.25).abs() < 1e-15 && (v - 0.5).abs() < 1e-15);
        assert!(triangle(&tri, &ray, 1.5).is_none());
        let miss = Ray::new(DVec3::new(0.75, 0.5, 2.0), -DVec3::Z);
        assert!(triangle(&tri, &miss, FAR).is_none());
    }

    #[test]
    fn sphere_roots_and_plane() {
        let ray = Ray::new(DVec3::ZERO, -DVec3::Z);
        let c = DVec3::new(0.0, 0.0, -5.0);
        assert_eq!(sphere_roots(c, 1.0, &ray), (4.0, 6.0));
        assert_eq!(sphere(c, 1.0, &ray), 4.0);
        assert_eq!(sphere(DVec3::ZERO, 1.0, &ray), 1.0);
        assert!(sphere(DVec3::new(0.0, 3.0, -5.0), 1.0, &ray) <= 0.0);
        assert_eq!(plane(DVec3::new(0.0, 0.0, -3.0), DVec3::Z, &ray), 3.0);
        assert!(plane(DVec3::new(0.0, 0.0, -3.0), DVec3::X, &ray) <= 0.0);
    }
}
