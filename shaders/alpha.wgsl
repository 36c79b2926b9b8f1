// Alpha cut-outs in traversal (scene::AlphaMode): a masked or blended
// triangle is there for a ray only where its alpha passes the test, for
// camera and shadow rays alike, so a leaf texture casts leaf-shaped
// shadows. Compiled in only for scenes with such a material
// (HAS_ALPHA_TESTS); the others pay nothing.
//
// A blended point is there when alpha > ξ, ξ a hash of the pixel, the
// triangle and the seed in the stream the stage sets (stochastic
// transparency: Enderton, Sintorn, Shirley and Luebke, "Stochastic
// Transparency", I3D 2010): deterministic for a seed, and converging to
// alpha blending with the samples per pixel.

// Set by the stage before it traverses: the pixel and the hash stream.
var<private> alpha_pixel: u32;
var<private> alpha_stream: u32;

// Whether triangle `i` is there at barycentrics `bary`.
fn triangle_is_there(i: u32, tri: Triangle, bary: vec2<f32>) -> bool {
    if !HAS_ALPHA_TESTS {
        return true;
    }
    let m1 = penumbra_surface_map(tri.object, 1u);
    let mode = m1.z;
    if mode == penumbra_ALPHA_OPAQUE {
        return true;
    }
    let m2 = penumbra_surface_map(tri.object, 2u);
    var alpha = bitcast<f32>(m2.x);
    if HAS_ATTRIBUTES {
        let t = m2.y;
        if t != penumbra_NO_TEXTURE {
            let uv = penumbra_triangle_uv(penumbra_triangle_uvs(i), penumbra_texture_set(t), bary);
            alpha *= penumbra_texture_lod(t, uv, -3.0e38).a;
        }
        alpha *= penumbra_triangle_colour(i, bary).a;
    }
    if mode == penumbra_ALPHA_MASK {
        return alpha >= bitcast<f32>(m1.w);
    }
    return alpha > unit_float(hash3(alpha_pixel, i, push.seed ^ alpha_stream));
}
