// Triangles (single, or from meshes), stored by their three vertices, so
// that triangles sharing a vertex share its exact bits (watertightness).

// Mirrored by render::layout::Triangle; fetched by triangle().
struct Triangle {
    v0: vec3<f32>,
    shader: u32,
    v1: vec3<f32>,
    object: u32,
    v2: vec3<f32>,
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
// 16-byte texels per triangle (48 bytes).
const TRIANGLE_TEXELS: u32 = 3u;

// Triangle `i`, from its texels: the struct's words in order.
fn triangle(i: u32) -> Triangle {
    let base = i * TRIANGLE_TEXELS;
    let a = textureLoad(triangles, texel(base));
    let b = textureLoad(triangles, texel(base + 1u));
    let c = textureLoad(triangles, texel(base + 2u));
    return Triangle(
        bitcast<vec3<f32>>(a.xyz), a.w,
        bitcast<vec3<f32>>(b.xyz), b.w,
        bitcast<vec3<f32>>(c.xyz), c.w,
    );
}

// Texels, TRIANGLE_TEXELS a triangle (shaders/texels.wgsl says why).
@group(0) @binding(3) var triangles: texture_storage_2d<rgba32uint, read>;
@group(0) @binding(4) var<storage, read> vertex_normals: array<VertexNormals>;

const TRIANGLE_MISS: vec3<f32> = vec3<f32>(-1.0, 0.0, 0.0);

// Returns (t, u, v) with t > 0 for a hit nearer than t_max, else t = -1.
fn intersect_triangle(tri: Triangle, ray: Ray, t_max: f32) -> vec3<f32> {
    if TRIANGLE_TEST == TRIANGLE_T_FIRST {
        return intersect_triangle_t_first(tri, ray, t_max);
    }
    if TRIANGLE_TEST == TRIANGLE_WATERTIGHT {
        return intersect_triangle_watertight(tri, ray, t_max);
    }
    return intersect_triangle_uv_first(tri, ray, t_max);
}

// Möller–Trumbore in the seminar's order: the barycentric u first, then v,
// each rejecting as early as possible, and only then the distance t (the
// seminar measured 0.68 s against 1 s for computing t first).
fn intersect_triangle_uv_first(tri: Triangle, ray: Ray, t_max: f32) -> vec3<f32> {
    let e1 = tri.v1 - tri.v0;
    let e2 = tri.v2 - tri.v0;
    let p = cross(ray.dir, e2);
    let det = dot(e1, p);
    if det == 0.0 {
        return TRIANGLE_MISS;
    }
    let inv = 1.0 / det;
    let s = ray.origin - tri.v0;
    let u = dot(s, p) * inv;
    if u < 0.0 || u > 1.0 {
        return TRIANGLE_MISS;
    }
    let q = cross(s, e1);
    let v = dot(ray.dir, q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return TRIANGLE_MISS;
    }
    let t = dot(e2, q) * inv;
    // NaN fails both comparisons, so it never counts as a hit.
    if t > 0.0 && t < t_max {
        return vec3<f32>(t, u, v);
    }
    return TRIANGLE_MISS;
}

// The same arithmetic with the opposite order: the plane distance t first,
// then u and v (the seminar's slower baseline).
fn intersect_triangle_t_first(tri: Triangle, ray: Ray, t_max: f32) -> vec3<f32> {
    let e1 = tri.v1 - tri.v0;
    let e2 = tri.v2 - tri.v0;
    let p = cross(ray.dir, e2);
    let det = dot(e1, p);
    if det == 0.0 {
        return TRIANGLE_MISS;
    }
    let inv = 1.0 / det;
    let s = ray.origin - tri.v0;
    let q = cross(s, e1);
    let t = dot(e2, q) * inv;
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

// Woop, Benthin and Wald's watertight test (JCGT 2013), in the seminar's
// order too: the edge functions U, V, W (unnormalised barycentrics) first,
// rejecting as soon as their signs differ, then t. Shearing the vertices into
// the ray's frame makes neighbouring triangles compute a shared edge's
// function from the same numbers, so a ray can never slip between them.
// Exact zeros count as inside on both sides (a ray through an edge may hit
// both triangles, never neither).
fn intersect_triangle_watertight(tri: Triangle, ray: Ray, t_max: f32) -> vec3<f32> {
    let k = ray.axes;
    let a = tri.v0 - ray.origin;
    let b = tri.v1 - ray.origin;
    let c = tri.v2 - ray.origin;
    let ax = a[k.x] - ray.shear.x * a[k.z];
    let ay = a[k.y] - ray.shear.y * a[k.z];
    let bx = b[k.x] - ray.shear.x * b[k.z];
    let by = b[k.y] - ray.shear.y * b[k.z];
    let cx = c[k.x] - ray.shear.x * c[k.z];
    let cy = c[k.y] - ray.shear.y * c[k.z];
    let u = cx * by - cy * bx;
    let v = ax * cy - ay * cx;
    if (u < 0.0 || v < 0.0) && (u > 0.0 || v > 0.0) {
        return TRIANGLE_MISS;
    }
    let w = bx * ay - by * ax;
    if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
        return TRIANGLE_MISS;
    }
    let det = u + v + w;
    if det == 0.0 {
        return TRIANGLE_MISS;
    }
    // A degenerate (zero-area) triangle can pass the sign tests through the
    // rounding of the shear; like pbrt-v4, reject it by its true area. Only
    // rays that passed the edge tests pay for this check.
    let n = cross(tri.v1 - tri.v0, tri.v2 - tri.v0);
    if dot(n, n) == 0.0 {
        return TRIANGLE_MISS;
    }
    let az = ray.shear.z * a[k.z];
    let bz = ray.shear.z * b[k.z];
    let cz = ray.shear.z * c[k.z];
    let t_scaled = u * az + v * bz + w * cz;
    let inv = 1.0 / det;
    let t = t_scaled * inv;
    // NaN fails both comparisons, so it never counts as a hit.
    if t > 0.0 && t < t_max {
        // Hit point = (u·v0 + v·v1 + w·v2) / det: barycentrics of v1 and v2.
        return vec3<f32>(t, v * inv, w * inv);
    }
    return TRIANGLE_MISS;
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
