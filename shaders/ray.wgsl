// A ray: origin and unit direction.
struct Ray {
    origin: vec3<f32>,
    dir: vec3<f32>,
}

// Farther than anything in a scene; used as "no hit yet" and as the length
// of shadow rays towards directional lights.
const FAR: f32 = 3.0e38;

fn ray_at(ray: Ray, t: f32) -> vec3<f32> {
    return ray.origin + t * ray.dir;
}
