// Infinite plane through `point` with unit `normal`.

// Mirrored by render::layout::Plane.
struct Plane {
    point: vec3<f32>,
    shader: u32,
    normal: vec3<f32>,
    object: u32,
    // Texture coordinates at `point` (world units along the plane's axes,
    // computed in f64 on the host: surface.wgsl).
    uv_origin: vec2<f32>,
    _pad: vec2<u32>,
}

@group(0) @binding(1) var<storage, read> planes: array<Plane>;

// Distance to the plane, or a value <= 0 (never a hit) when the ray is
// parallel or the plane lies behind.
fn intersect_plane(plane: Plane, ray: Ray) -> f32 {
    let denom = dot(plane.normal, ray.dir);
    if denom == 0.0 {
        return -1.0;
    }
    return dot(plane.normal, plane.point - ray.origin) / denom;
}
