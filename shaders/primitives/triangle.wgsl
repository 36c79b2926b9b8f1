// Triangles (single, or from meshes), stored as vertex 0 plus two edges.

// Mirrored by render::layout::Triangle.
struct Triangle {
    v0: vec3<f32>,
    shader: u32,
    e1: vec3<f32>,
    object: u32,
    e2: vec3<f32>,
    // Index into `vertex_normals`, or NO_NORMALS for flat shading.
    normals: u32,
}

// Mirrored by render::layout::VertexNormals.
struct VertexNormals {
    n0: vec3<f32>,
    n1: vec3<f32>,
    n2: vec3<f32>,
}

const NO_NORMALS: u32 = 0xffffffffu;

@group(0) @binding(3) var<storage, read> triangles: array<Triangle>;
@group(0) @binding(4) var<storage, read> vertex_normals: array<VertexNormals>;

// Which ray/triangle test the kernel uses (render::TriangleTest).
const TRIANGLE_UV_FIRST: u32 = 0u;
const TRIANGLE_T_FIRST: u32 = 1u;

const TRIANGLE_MISS: vec3<f32> = vec3<f32>(-1.0, 0.0, 0.0);

// Returns (t, u, v) with t > 0 for a hit nearer than t_max, else t = -1.
fn intersect_triangle(tri: Triangle, ray: Ray, t_max: f32) -> vec3<f32> {
    if TRIANGLE_TEST == TRIANGLE_T_FIRST {
        return intersect_triangle_t_first(tri, ray, t_max);
    }
    return intersect_triangle_uv_first(tri, ray, t_max);
}

// Möller–Trumbore in the seminar's order: the barycentric u first, then v,
// each rejecting as early as possible, and only then the distance t (the
// seminar measured 0.68 s against 1 s for computing t first).
fn intersect_triangle_uv_first(tri: Triangle, ray: Ray, t_max: f32) -> vec3<f32> {
    let p = cross(ray.dir, tri.e2);
    let det = dot(tri.e1, p);
    if det == 0.0 {
        return TRIANGLE_MISS;
    }
    let inv = 1.0 / det;
    let s = ray.origin - tri.v0;
    let u = dot(s, p) * inv;
    if u < 0.0 || u > 1.0 {
        return TRIANGLE_MISS;
    }
    let q = cross(s, tri.e1);
    let v = dot(ray.dir, q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return TRIANGLE_MISS;
    }
    let t = dot(tri.e2, q) * inv;
    // NaN fails both comparisons, so it never counts as a hit.
    if t > 0.0 && t < t_max {
        return vec3<f32>(t, u, v);
    }
    return TRIANGLE_MISS;
}

// The same arithmetic with the opposite order: the plane distance t first,
// then u and v (the seminar's slower baseline).
fn intersect_triangle_t_first(tri: Triangle, ray: Ray, t_max: f32) -> vec3<f32> {
    let p = cross(ray.dir, tri.e2);
    let det = dot(tri.e1, p);
    if det == 0.0 {
        return TRIANGLE_MISS;
    }
    let inv = 1.0 / det;
    let s = ray.origin - tri.v0;
    let q = cross(s, tri.e1);
    let t = dot(tri.e2, q) * inv;
    if !(t > 0.0 && t < t_max) {
        return TRIANGLE_MISS;
    }
    let u = dot(s, p) * inv;
    let v = dot(ray.dir, q) * inv;
    if u < 0.0 || v < 0.0 || u + v > 1.0 {
        return TRIANGLE_MISS;
    }
    return vec3<f32>(t, u, v);
}

// Interpolated vertex normal where the mesh has normals, else the geometric
// normal `ng`.
fn triangle_shading_normal(tri: Triangle, ng: vec3<f32>, u: f32, v: f32) -> vec3<f32> {
    if !HAS_VERTEX_NORMALS || tri.normals == NO_NORMALS {
        return ng;
    }
    let n = vertex_normals[tri.normals];
    let interpolated = (1.0 - u - v) * n.n0 + u * n.n1 + v * n.n2;
    let len2 = dot(interpolated, interpolated);
    // Opposite normals can cancel; fall back to the flat normal then.
    return select(ng, interpolated * inverseSqrt(len2), len2 > 1e-12);
}
