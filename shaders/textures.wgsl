// Texture sampling, exactly as src/scene/texture.rs defines it: RGBA8
// texels, sRGB decoded before filtering (by the host, which stores each
// texel as linear RGBA16), host-built mip chains, nearest or
// bilinear within a level, nearest or linear between levels, the three wrap
// modes and KHR_texture_transform. Filtering is done here, on texel loads,
// rather than by Vulkan samplers: the f64 reference then implements the same
// arithmetic, and every mode glTF names is exact on any device.
//
// Every name starts with `penumbra_`: the shade stage compiles this file
// with users' shader files (stages/shade.wgsl).
//
// All textures of a scene share one texel image (binding 20): each texture's
// levels one after the other, two linear RGBA16 texels packed in each
// rgba32uint texel (render::layout::textures::texture_words). A texture use (binding 21) is a texture
// with its sampler, texture coordinates and transform:
//   0: level-0 width, height, level count, flags (TEXTURE_* below)
//   1: first row of the uv transform, the level-of-detail bias
//      (½·log2(w·h) + log2 of the transform's scale)
//   2: second row of the uv transform, the first word of level 0 (two words
//      a texel)

@group(0) @binding(20) var penumbra_texture_texels: texture_storage_2d<rgba32uint, read>;
@group(0) @binding(21) var penumbra_texture_uses: texture_storage_2d<rgba32uint, read>;

// The index of no texture use: sampling it gives (1, 1, 1, 1).
const penumbra_NO_TEXTURE: u32 = 0xffffffffu;
// Texels per texture use (render::layout::USE_TEXELS).
const penumbra_USE_TEXELS: u32 = 3u;
// Flags of a texture use (render::layout::textures).
const penumbra_TEXTURE_SRGB: u32 = 1u;
const penumbra_TEXTURE_MAG_LINEAR: u32 = 2u;
const penumbra_TEXTURE_MIN_LINEAR: u32 = 4u;
// Bits 3-4: mip mode (0 none, 1 nearest, 2 linear); bits 5-6 and 7-8: wrap
// along u and v (0 repeat, 1 mirrored repeat, 2 clamp to edge); bit 9: the
// use reads texture coordinate set 1.
const penumbra_TEXTURE_MIP_SHIFT: u32 = 3u;
const penumbra_TEXTURE_WRAP_U_SHIFT: u32 = 5u;
const penumbra_TEXTURE_WRAP_V_SHIFT: u32 = 7u;
const penumbra_TEXTURE_SET_1: u32 = 512u;

struct penumbra_TextureUse {
    size: vec2<u32>,
    levels: u32,
    flags: u32,
    row0: vec3<f32>,
    lod_bias: f32,
    row1: vec3<f32>,
    base: u32,
}

fn penumbra_texture_texel(i: u32) -> vec2<u32> {
    return vec2<u32>(i & 4095u, i >> 12u);
}

fn penumbra_texture_use(t: u32) -> penumbra_TextureUse {
    let at = t * penumbra_USE_TEXELS;
    let a = textureLoad(penumbra_texture_uses, penumbra_texture_texel(at));
    let b = textureLoad(penumbra_texture_uses, penumbra_texture_texel(at + 1u));
    let c = textureLoad(penumbra_texture_uses, penumbra_texture_texel(at + 2u));
    return penumbra_TextureUse(a.xy, a.z, a.w, bitcast<vec3<f32>>(b.xyz), bitcast<f32>(b.w), bitcast<vec3<f32>>(c.xyz), c.w);
}

// Which texture coordinate set texture use `t` reads (0 or 1).
fn penumbra_texture_set(t: u32) -> u32 {
    if t == penumbra_NO_TEXTURE {
        return 0u;
    }
    let flags = textureLoad(penumbra_texture_uses, penumbra_texture_texel(t * penumbra_USE_TEXELS)).w;
    return select(0u, 1u, (flags & penumbra_TEXTURE_SET_1) != 0u);
}

// Texel index `i` wrapped into 0..n by `mode` (scene::Wrap::apply). Repeat
// and mirrored repeat share one remainder (of the period n or 2n, made
// non-negative): every `%` is a guarded division that lavapipe compiles at
// each inlined copy (issue 39).
fn penumbra_wrap(i: i32, n: i32, mode: u32) -> i32 {
    if mode > 1u {
        return clamp(i, 0, n - 1);
    }
    let mirrored = mode == 1u;
    let period = select(n, 2 * n, mirrored);
    let r = i % period;
    let m = select(r, r + period, r < 0);
    return select(m, 2 * n - 1 - m, mirrored && m >= n);
}

// Texel (x, y) of the level that starts at word `base` and is `size`
// texels, wrapped, as linear RGBA.
fn penumbra_fetch(u: penumbra_TextureUse, base: u32, size: vec2<u32>, x: i32, y: i32) -> vec4<f32> {
    let xi = penumbra_wrap(x, i32(size.x), (u.flags >> penumbra_TEXTURE_WRAP_U_SHIFT) & 3u);
    let yi = penumbra_wrap(y, i32(size.y), (u.flags >> penumbra_TEXTURE_WRAP_V_SHIFT) & 3u);
    let word = base + 2u * (u32(yi) * size.x + u32(xi));
    let packed = textureLoad(penumbra_texture_texels, penumbra_texture_texel(word >> 2u));
    let pair = select(packed.zw, packed.xy, (word & 2u) == 0u);
    return vec4<f32>(unpack2x16unorm(pair.x), unpack2x16unorm(pair.y));
}

// Level `level` of use `u` at transformed coordinates `st`: the texel that
// holds the point, or bilinear between the four texel centres around it.
//
// The taps are a loop whose body fetches once, not four inlined fetches:
// lavapipe inlines every call, so each copy of `penumbra_fetch` (two wraps
// and a texel load) is compiled again, and a loop's body only once (issue
// 39: the driver compile of a textured shade pipeline). The mixes are the
// same operations on the same values as `mix(mix(t00, t10, w.x), mix(t01,
// t11, w.x), w.y)`, so the results are bit-identical.
fn penumbra_sample_level(u: penumbra_TextureUse, level: u32, st: vec2<f32>, linear: bool) -> vec4<f32> {
    var base = u.base;
    var size = u.size;
    for (var k = 0u; k < level; k++) {
        base += 2u * size.x * size.y;
        size = max(size >> vec2<u32>(1u), vec2<u32>(1u));
    }
    let p = st * vec2<f32>(size);
    // Nearest: one tap, the texel that holds the point; bilinear: four, from
    // the texel centre below and left of it.
    let q = select(p, p - 0.5, linear);
    let f = floor(q);
    let w = q - f;
    let x = i32(f.x);
    let y = i32(f.y);
    let taps = select(1u, 4u, linear);
    var top = vec4<f32>(0.0);
    var bottom = vec4<f32>(0.0);
    for (var k = 0u; k < taps; k++) {
        let texel = penumbra_fetch(u, base, size, x + i32(k & 1u), y + i32(k >> 1u));
        if k == 0u {
            top = texel;
        } else if k == 1u {
            top = mix(top, texel, w.x);
        } else if k == 2u {
            bottom = texel;
        } else {
            bottom = mix(bottom, texel, w.x);
        }
    }
    if !linear {
        return top;
    }
    return mix(top, bottom, w.y);
}

// Texture use `t` at texture coordinates `uv`, whose geometric level of
// detail is `lambda` (ray cones, without the texture's own terms; -inf or
// NaN magnifies): linear RGBA, or (1, 1, 1, 1) for no texture.
//
// Which levels and filter the use's modes choose is decided first, then
// one loop samples them (one level, or two for trilinear): one inlined
// copy of the sampling code instead of one per case (issue 39).
fn penumbra_texture_lod(t: u32, uv: vec2<f32>, lambda: f32) -> vec4<f32> {
    if t == penumbra_NO_TEXTURE {
        return vec4<f32>(1.0);
    }
    let u = penumbra_texture_use(t);
    let st = vec2<f32>(dot(u.row0.xy, uv) + u.row0.z, dot(u.row1.xy, uv) + u.row1.z);
    let l = lambda + u.lod_bias;
    // Magnified: level 0 with the magnification filter.
    var linear = (u.flags & penumbra_TEXTURE_MAG_LINEAR) != 0u;
    var level = 0u;
    var levels = 1u;
    var lo = 0.0;
    if l > 0.0 {
        linear = (u.flags & penumbra_TEXTURE_MIN_LINEAR) != 0u;
        let mip = (u.flags >> penumbra_TEXTURE_MIP_SHIFT) & 3u;
        let last = f32(u.levels - 1u);
        if mip == 1u {
            level = u32(min(round(l), last));
        } else if mip != 0u {
            lo = min(floor(l), last);
            level = u32(lo);
            // Between two levels, unless past the last.
            if lo < last {
                levels = 2u;
            }
        }
    }
    var a = vec4<f32>(0.0);
    var b = vec4<f32>(0.0);
    for (var i = 0u; i < levels; i++) {
        let s = penumbra_sample_level(u, level + i, st, linear);
        if i == 0u {
            a = s;
        } else {
            b = s;
        }
    }
    if levels == 1u {
        return a;
    }
    return mix(a, b, l - lo);
}
