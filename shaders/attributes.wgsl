// Vertex attributes of triangles beyond positions and normals: two texture
// coordinate sets, a colour and a tangent per vertex (binding 23), for
// scenes whose meshes have any; a triangle's attributes are interpolated
// with its hit's barycentrics. Mirrored by render::layout::attributes,
// ATTRIBUTE_TEXELS texels a triangle, indexed like the triangles:
//   0: uv0 of vertex 0, uv0 of vertex 1
//   1: uv0 of vertex 2, uv1 of vertex 0
//   2: uv1 of vertex 1, uv1 of vertex 2
//   3, 4, 5: the colours of vertices 0, 1, 2 (linear RGBA)
//   6, 7, 8: the tangents of vertices 0, 1, 2 (camera-relative world
//            space, w the bitangent's sign)
// A triangle without a set has uv (0, 0); without colours, (1, 1, 1, 1);
// without tangents, 0.
//
// Every name starts with `penumbra_`: the shade stage compiles this file
// with users' shader files.

@group(0) @binding(23) var penumbra_attributes: texture_storage_2d<rgba32uint, read>;

const penumbra_ATTRIBUTE_TEXELS: u32 = 9u;

struct penumbra_TriangleUvs {
    // Set 0 at vertices 0, 1, 2, then set 1.
    a0: vec2<f32>,
    b0: vec2<f32>,
    c0: vec2<f32>,
    a1: vec2<f32>,
    b1: vec2<f32>,
    c1: vec2<f32>,
}

fn penumbra_attribute(i: u32) -> vec4<u32> {
    return textureLoad(penumbra_attributes, vec2<u32>(i & 4095u, i >> 12u));
}

fn penumbra_triangle_uvs(triangle: u32) -> penumbra_TriangleUvs {
    let at = triangle * penumbra_ATTRIBUTE_TEXELS;
    let p = bitcast<vec4<f32>>(penumbra_attribute(at));
    let q = bitcast<vec4<f32>>(penumbra_attribute(at + 1u));
    let r = bitcast<vec4<f32>>(penumbra_attribute(at + 2u));
    return penumbra_TriangleUvs(p.xy, p.zw, q.xy, q.zw, r.xy, r.zw);
}

// Barycentric interpolation: weight 1 − u − v at vertex 0, u at 1, v at 2.
fn penumbra_mix3_2(a: vec2<f32>, b: vec2<f32>, c: vec2<f32>, bary: vec2<f32>) -> vec2<f32> {
    return (1.0 - bary.x - bary.y) * a + bary.x * b + bary.y * c;
}

fn penumbra_mix3_4(a: vec4<f32>, b: vec4<f32>, c: vec4<f32>, bary: vec2<f32>) -> vec4<f32> {
    return (1.0 - bary.x - bary.y) * a + bary.x * b + bary.y * c;
}

// Texture coordinate set `set` of `triangle` at barycentrics `bary`.
fn penumbra_triangle_uv(uvs: penumbra_TriangleUvs, uv_set: u32, bary: vec2<f32>) -> vec2<f32> {
    if uv_set == 0u {
        return penumbra_mix3_2(uvs.a0, uvs.b0, uvs.c0, bary);
    }
    return penumbra_mix3_2(uvs.a1, uvs.b1, uvs.c1, bary);
}

// The vertex colour of `triangle` at barycentrics `bary`.
fn penumbra_triangle_colour(triangle: u32, bary: vec2<f32>) -> vec4<f32> {
    let at = triangle * penumbra_ATTRIBUTE_TEXELS + 3u;
    let a = bitcast<vec4<f32>>(penumbra_attribute(at));
    let b = bitcast<vec4<f32>>(penumbra_attribute(at + 1u));
    let c = bitcast<vec4<f32>>(penumbra_attribute(at + 2u));
    return penumbra_mix3_4(a, b, c, bary);
}

// The interpolated tangent of `triangle` (not normalised; w: the sign).
fn penumbra_triangle_tangent(triangle: u32, bary: vec2<f32>) -> vec4<f32> {
    let at = triangle * penumbra_ATTRIBUTE_TEXELS + 6u;
    let a = bitcast<vec4<f32>>(penumbra_attribute(at));
    let b = bitcast<vec4<f32>>(penumbra_attribute(at + 1u));
    let c = bitcast<vec4<f32>>(penumbra_attribute(at + 2u));
    return penumbra_mix3_4(a, b, c, bary);
}
