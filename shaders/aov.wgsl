// Arbitrary output variables: what the primary ray of each pixel saw,
// written by the first pass only (pixel centre when there is one sample),
// by the hit stage (stages/hit.wgsl).

// Mirrored by render::layout::Aov. Misses: depth +inf, normal 0, uv 0,
// object and primitive 0xffffffff.
struct Aov {
    // Distance along the (unit) primary ray.
    depth: f32,
    // Geometric normal, unit, facing the viewer.
    normal_x: f32,
    normal_y: f32,
    normal_z: f32,
    // Barycentric u, v of triangle hits (0 elsewhere).
    u: f32,
    v: f32,
    object: u32,
    // Index of the primitive among those of its kind (the host turns it into
    // the index within its object).
    primitive: u32,
}

@group(0) @binding(13) var<storage, read_write> aovs: array<Aov>;

fn write_aov(pixel: u32, hit: Hit) {
    var out = Aov(bitcast<f32>(0x7f800000u), 0.0, 0.0, 0.0, 0.0, 0.0, 0xffffffffu, 0xffffffffu);
    if hit.found {
        let n = hit.geometric_normal;
        var uv = vec2<f32>(0.0);
        if hit.kind == KIND_TRIANGLE {
            uv = hit.coords;
        }
        out = Aov(hit.t, n.x, n.y, n.z, uv.x, uv.y, hit.object, hit.index);
    }
    aovs[pixel] = out;
}
