// The surface at a hit beyond its normals: texture coordinates, their level
// of detail, and the normal a normal map tilts (src/scene/texture.rs is the
// contract).
//
// Level of detail comes from ray cones (Akenine-Möller, Nelson, Lu, Jänis,
// Fernando and Ray, "Texture Level of Detail Strategies for Real-Time Ray
// Tracing", Ray Tracing Gems 2019, ch. 20): a camera ray is a cone that
// spans one pixel, of width W = α·t at distance t, and a texture seen
// through it needs level
//   λ = log2(W/|n·d|) + ½·log2(A_uv/A_world) + ½·log2(w·h) + log2(s);
// the hit stores the geometric part, one per texture coordinate set, and
// sampling adds the texture's own (textures.wgsl).

// Where a ray starts a cone of width 0 spanning `α` a unit of distance: the
// camera's pixel at the dispatch's size (the image plane's half height at
// distance 1 is |up|), or the orthographic pixel's constant width.
fn cone_width(t: f32) -> f32 {
    let pixel = 2.0 * length(globals.camera.up) / f32(push.size.y);
    if globals.camera.orthographic != 0u {
        return pixel;
    }
    return pixel * t;
}

// A plane's planar axes (e_u, e_v) from its unit normal.
fn plane_axes(n: vec3<f32>) -> mat2x3<f32> {
    let a = select(vec3<f32>(0.0, 1.0, 0.0), vec3<f32>(0.0, 0.0, -1.0), abs(n.y) > 0.999);
    let e_u = normalize(cross(a, n));
    return mat2x3<f32>(e_u, cross(e_u, n));
}

// Texture coordinates of point `p` (camera-relative) on `plane`: world
// units along its axes, from the uv the host computed at its stored point.
fn plane_uv(plane: Plane, p: vec3<f32>) -> vec2<f32> {
    let axes = plane_axes(plane.normal);
    let d = p - plane.point;
    return plane.uv_origin + vec2<f32>(dot(d, axes[0]), dot(d, axes[1]));
}

const TAU: f32 = 6.283185307179586;
const PI: f32 = 3.141592653589793;

// Latitude-longitude coordinates of unit direction `d` from a sphere's
// centre: v = 0 at the +Y pole, the seam at −X.
fn sphere_uv(d: vec3<f32>) -> vec2<f32> {
    return vec2<f32>(0.5 - atan2(d.z, d.x) / TAU, acos(clamp(d.y, -1.0, 1.0)) / PI);
}

// Fills the hit's texture coordinates (triangles: their barycentrics, which
// the stages interpolate attributes with; planes and spheres: their uv) and,
// for scenes with textures, the geometric level of detail of each set.
fn surface_coords(ray: Ray, hit: ptr<function, Hit>, ng: vec3<f32>) {
    var ratio = vec2<f32>(1.0);
    switch (*hit).kind {
        case KIND_PLANE: {
            (*hit).coords = plane_uv(planes[(*hit).index], (*hit).position);
        }
        case KIND_SPHERE: {
            let sphere = spheres[(*hit).index];
            let d = ng;
            (*hit).coords = sphere_uv(d);
            let sin_theta = max(sqrt(max(1.0 - d.y * d.y, 0.0)), 1e-4);
            ratio = vec2<f32>(1.0 / (2.0 * PI * PI * sphere.radius * sphere.radius * sin_theta));
        }
        default: {
            if HAS_TEXTURES && HAS_ATTRIBUTES {
                let tri = triangle((*hit).index);
                let world = length(cross(tri.v1 - tri.v0, tri.v2 - tri.v0));
                let uvs = penumbra_triangle_uvs((*hit).index);
                let a0 = abs(cross2(uvs.b0 - uvs.a0, uvs.c0 - uvs.a0));
                let a1 = abs(cross2(uvs.b1 - uvs.a1, uvs.c1 - uvs.a1));
                ratio = vec2<f32>(a0, a1) / world;
            }
        }
    }
    if HAS_TEXTURES {
        let cosine = max(abs(dot(ng, ray.dir)), 1e-6);
        let base = log2(cone_width((*hit).t) / cosine);
        // log2(0) is −∞: a set with no uv area magnifies.
        (*hit).lambda = vec2<f32>(base) + 0.5 * log2(ratio);
    }
}

fn cross2(a: vec2<f32>, b: vec2<f32>) -> f32 {
    return a.x * b.y - a.y * b.x;
}

// The shading normal `n` (unit, not yet facing the viewer) of a triangle hit
// tilted by its object's normal map, if it has one.
fn normal_mapped(hit: Hit, n: vec3<f32>) -> vec3<f32> {
    let m = penumbra_surface_map(hit.object, 1u);
    let t = m.x;
    if t == penumbra_NO_TEXTURE {
        return n;
    }
    let uv_set = penumbra_texture_set(t);
    let uv = penumbra_triangle_uv(penumbra_triangle_uvs(hit.index), uv_set, hit.coords);
    let texel = penumbra_texture_lod(t, uv, hit.lambda[uv_set]).xyz;
    let s = bitcast<f32>(m.y);
    let local = normalize((2.0 * texel - 1.0) * vec3<f32>(s, s, 1.0));
    let tangent = penumbra_triangle_tangent(hit.index, hit.coords);
    let tn = tangent.xyz - n * dot(n, tangent.xyz);
    let len2 = dot(tn, tn);
    if !(len2 > 1e-20) {
        return n;
    }
    let tu = tn * inverseSqrt(len2);
    let b = tangent.w * cross(n, tu);
    return normalize(local.x * tu + local.y * b + local.z * n);
}
