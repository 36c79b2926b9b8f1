// Sphere given by centre and radius.

// Mirrored by render::layout::Sphere.
struct Sphere {
    center: vec3<f32>,
    radius: f32,
    shader: u32,
    object: u32,
    _pad: vec2<u32>,
}

@group(0) @binding(2) var<storage, read> spheres: array<Sphere>;

// Both roots along a unit-length direction, nearest first; NaN-free, with
// x > y (no roots) when the ray misses. The discriminant is taken from the
// centre's distance to the ray line and the near root as c / q, the
// cancellation-free forms of Haines et al., "Precision Improvements for
// Ray/Sphere Intersection" (Ray Tracing Gems, 2019).
fn sphere_roots(sphere: Sphere, ray: Ray) -> vec2<f32> {
    let f = ray.origin - sphere.center;
    let b = dot(f, ray.dir);
    let perp = f - b * ray.dir;
    let r2 = sphere.radius * sphere.radius;
    let disc = r2 - dot(perp, perp);
    if disc < 0.0 {
        return vec2<f32>(1.0, -1.0);
    }
    let c = dot(f, f) - r2;
    let q = -b - select(-1.0, 1.0, b >= 0.0) * sqrt(disc);
    if q == 0.0 {
        return vec2<f32>(0.0);
    }
    let t0 = c / q;
    return vec2<f32>(min(t0, q), max(t0, q));
}

// Nearest positive distance, or a value <= 0 for a miss.
fn intersect_sphere(sphere: Sphere, ray: Ray) -> f32 {
    let roots = sphere_roots(sphere, ray);
    if roots.x > roots.y {
        return -1.0;
    }
    return select(roots.y, roots.x, roots.x > 0.0);
}
