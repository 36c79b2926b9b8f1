// Stage 3, shade: one pipeline per shader file. The host compiles this
// file with shading/interface.wgsl, the shader file, and the parameter
// loader it generates from the file's `struct Params` (src/render/shade.rs):
//   fn penumbra_load_params(at: u32) -> Params
//   fn penumbra_prepare(s: Surface, p: Params) -> Params
//   fn penumbra_ambient_sum(s: Surface, p: Params) -> vec3<f32>
// (the file's `prepare`, or `p` unchanged without one; the sum of the
// file's `ambient` over the lights, or 0 without one)
// Every name here starts with `penumbra_`, so no shader file can collide
// with the engine. The stage traces nothing: it sums the shader's ambient
// term of every light and its `shade` of every queued light sample that
// reached the point (the shadow stage zeroed the others), and writes the
// colour to the image with the last chunk of samples (earlier chunks sum in
// the colour sums); the hit stage writes the pixels that hit nothing.
//
// penumbra_PushConstants mirrors PushConstants (render.wgsl); the layout
// test in src/render/layout/mod.rs checks it against the host's.

struct penumbra_PushConstants {
    origin: vec2<u32>,
    size: vec2<u32>,
    flags: u32,
    pass_index: u32,
    seed: u32,
    slot_base: u32,
    tile_origin: vec2<u32>,
    tile_width: u32,
    program: u32,
    sample_first: u32,
    sample_count: u32,
    light_count: u32,
    _pad0: u32,
}

// The hit records, material resolve's result and the queue (texel images:
// stages/records.wgsl), every leaf's parameters (4-word aligned, one texel
// per 4 words of its Params) and each light's colours (3 texels: diffuse and
// intensity, specular and sample count, ambient).
@group(0) @binding(14) var penumbra_hit_records: texture_storage_2d<rgba32uint, read>;
@group(0) @binding(15) var penumbra_queue: texture_storage_2d<rgba32uint, read>;
@group(0) @binding(16) var penumbra_resolved: texture_storage_2d<rgba32uint, read>;
// The scene's shader table (shading/shader.wgsl's shader_nodes): without
// checkers a hit's leaf shader is its own shader, so the shade stage reads
// the leaf's program and parameters from the table, and the hit stage
// writes no resolved material.
@group(0) @binding(6) var penumbra_shader_nodes: texture_storage_2d<rgba32uint, read>;
@group(0) @binding(7) var<storage, read_write> penumbra_image: array<vec4<f32>>;
// The same buffer as 64-bit words, which the stage stores its colours as
// with penumbra_STAGE_WORDS (render.wgsl's STAGE_WORDS and stage_words say
// why); pruning keeps one of the two.
@group(0) @binding(27) var<storage, read_write> penumbra_image_words: array<vec2<u64>>;
@group(0) @binding(17) var<storage, read_write> penumbra_radiance: array<vec4<f32>>;
@group(0) @binding(18) var penumbra_params: texture_storage_2d<rgba32uint, read>;
@group(0) @binding(19) var penumbra_light_colours: texture_storage_2d<rgba32uint, read>;
var<immediate> penumbra_push: penumbra_PushConstants;

// camera.wgsl's Camera, the first member of the globals (render.wgsl's
// Globals, binding 0), all the shade stage reads of them: the direction to
// the eye, which the records do not hold (stages/records.wgsl).
struct penumbra_Camera {
    right: vec3<f32>,
    orthographic: u32,
    up: vec3<f32>,
    _pad0: u32,
    forward: vec3<f32>,
    _pad1: u32,
}
struct penumbra_Globals {
    camera: penumbra_Camera,
}
@group(0) @binding(0) var<uniform> penumbra_globals: penumbra_Globals;

// render.wgsl's FLAG_WARM_UP, FLAG_FRESH and FLAG_LAST_CHUNK,
// stages/records.wgsl's KIND_NONE, KIND_BITS, RECORD_TEXELS
// and QUEUE_TEXELS, and texels.wgsl's TEXEL_ROW (checked against them by
// src/render/layout/mod.rs).
const penumbra_FLAG_WARM_UP: u32 = 1u;
const penumbra_FLAG_FRESH: u32 = 2u;
const penumbra_FLAG_LAST_CHUNK: u32 = 4u;
// The scene has vertex attributes to interpolate (attributes.wgsl) and
// surface maps with emission (surface_maps.wgsl); render.wgsl's
// FLAG_ATTRIBUTES and FLAG_EMISSION.
const penumbra_FLAG_ATTRIBUTES: u32 = 8u;
const penumbra_FLAG_EMISSION: u32 = 16u;
// Some mesh has vertex colours (render.wgsl's FLAG_COLOURS).
const penumbra_FLAG_COLOURS: u32 = 32u;
// The same three resolved per scene by the host (scene::Features; true in
// an unspecialised kernel, where the flags decide): a scene without them
// compiles none of their code, and without colours the colour is a
// constant the compiler folds into the shader's arithmetic.
override penumbra_HAS_ATTRIBUTES: bool = true;
override penumbra_HAS_COLOURS: bool = true;
override penumbra_HAS_EMISSION: bool = true;
// Some object has an occlusion texture and some light is the environment
// (scene::Features::occlusion): only then is the occlusion factor computed
// and the environment's samples scaled by it.
override penumbra_HAS_OCCLUSION: bool = true;
// The scene has checkers (render.wgsl's HAS_CHECKER): only then does the
// hit stage resolve materials into the resolved texels.
override penumbra_HAS_CHECKER: bool = true;
// The scene has planes or spheres (render.wgsl's HAS_PLANES, HAS_SPHERES):
// with them, or with attributes or textures, the records have texel 3.
override penumbra_HAS_PLANES: bool = true;
override penumbra_HAS_SPHERES: bool = true;
// render.wgsl's STAGE_WORDS and LANE_PIXELS (compile.rs:
// shade_setting_values).
override penumbra_STAGE_WORDS: bool = false;
override penumbra_LANE_PIXELS: bool = false;

// stages/records.wgsl's record_coords: whether the records have texel 3.
fn penumbra_record_coords() -> bool {
    return penumbra_HAS_PLANES || penumbra_HAS_SPHERES || penumbra_HAS_ATTRIBUTES || penumbra_HAS_TEXTURES;
}
const penumbra_KIND_TRIANGLE: u32 = 2u;
const penumbra_KIND_NONE: u32 = 0xffffffffu;
const penumbra_RECORD_TEXELS: u32 = 4u;
const penumbra_KIND_BITS: u32 = 2u;
const penumbra_QUEUE_TEXELS: u32 = 1u;
const penumbra_TEXEL_ROW_SHIFT: u32 = 12u;
// shading/shader.wgsl's SHADER_NODE_TEXELS; a node's third texel holds its
// program and its first parameter word (ShaderNode).
const penumbra_SHADER_NODE_TEXELS: u32 = 3u;

fn penumbra_texel(i: u32) -> vec2<u32> {
    return vec2<u32>(i & ((1u << penumbra_TEXEL_ROW_SHIFT) - 1u), i >> penumbra_TEXEL_ROW_SHIFT);
}

// render.wgsl's stage_words (this module cannot call the engine's; the
// words-against-texel-stores test of tests/gpu/stages.rs fails if the two
// pack differently).
fn penumbra_stage_words(v: vec4<u32>) -> vec2<u64> {
    return vec2<u64>(u64(v.x) | (u64(v.y) << 32u), u64(v.z) | (u64(v.w) << 32u));
}

fn penumbra_f3(t: vec4<u32>) -> vec3<f32> {
    return bitcast<vec3<f32>>(t.xyz);
}

// The arguments of render.wgsl's StageInvocation; the pixel as its
// stage_pixel finds it.
@compute @workgroup_size(64, 1, 1)
fn penumbra_shade_stage(
    @builtin(workgroup_id) workgroup: vec3<u32>,
    @builtin(local_invocation_index) index: u32,
    @builtin(subgroup_id) subgroup: u32,
    @builtin(subgroup_size) subgroup_size: u32,
    @builtin(subgroup_invocation_id) lane: u32,
) {
    let push = penumbra_push;
    // Before any branch: lavapipe loads a uniform once per SIMD group only
    // outside branches and loops (shaders/lights.wgsl's first_light).
    let camera = penumbra_globals.camera;
    if (push.flags & penumbra_FLAG_WARM_UP) != 0u {
        return;
    }
    var in_block = index;
    if penumbra_LANE_PIXELS {
        in_block = subgroup * subgroup_size + lane;
    }
    let px = workgroup.xy * 8u + push.origin + vec2<u32>(in_block & 7u, in_block >> 3u);
    if px.x >= push.size.x || px.y >= push.size.y {
        return;
    }
    let local = px - push.tile_origin;
    // stages/records.wgsl's tile_slot: block by block, 64 slots an 8×8 block.
    let block = (local.y >> 3u) * (push.tile_width >> 3u) + (local.x >> 3u);
    let slot = (block << 6u) | ((local.y & 7u) << 3u) | (local.x & 7u);
    let r = slot * penumbra_RECORD_TEXELS;
    let t0 = textureLoad(penumbra_hit_records, penumbra_texel(r));
    if t0.w == penumbra_KIND_NONE {
        return;
    }
    let t2 = textureLoad(penumbra_hit_records, penumbra_texel(r + 2u));
    // The leaf shader's program and first parameter word: material
    // resolve's, or without checkers the hit's own shader's. (Reading the
    // table costs less than a resolved texel written by the hit stage and
    // read back here: docs/stages.md.)
    var material: vec2<u32>;
    if penumbra_HAS_CHECKER {
        material = textureLoad(penumbra_resolved, penumbra_texel(slot)).yz;
    } else {
        material = textureLoad(penumbra_shader_nodes, penumbra_texel(t2.w * penumbra_SHADER_NODE_TEXELS + 2u)).xy;
    }
    if material.x != push.program {
        return;
    }
    let t1 = textureLoad(penumbra_hit_records, penumbra_texel(r + 1u));
    let ns = penumbra_f3(t2);
    // stages/records.wgsl's kind-and-object word (not KIND_NONE here).
    let kind = t0.w & ((1u << penumbra_KIND_BITS) - 1u);
    let object = t0.w >> penumbra_KIND_BITS;
    // The camera sits at the origin: a perspective ray left it towards the
    // point, an orthographic one along the view direction.
    let position = penumbra_f3(t0);
    var to_eye = -camera.forward;
    if camera.orthographic == 0u {
        to_eye = -normalize(position);
    }
    // Without texel 3 the coordinates are (0, 0) and there is no texture
    // to take a level of detail for.
    var t3 = vec4<u32>();
    if penumbra_record_coords() {
        t3 = textureLoad(penumbra_hit_records, penumbra_texel(r + 3u));
    }
    // Texture coordinates and colour: a triangle's interpolated from its
    // vertices, a plane's or sphere's as the hit stage computed them.
    var uv = bitcast<vec2<f32>>(t3.xy);
    var uv1 = uv;
    var vertex_colour = vec4<f32>(1.0);
    if kind == penumbra_KIND_TRIANGLE {
        uv = vec2<f32>(0.0);
        uv1 = uv;
        if penumbra_HAS_ATTRIBUTES && (push.flags & penumbra_FLAG_ATTRIBUTES) != 0u {
            let bary = bitcast<vec2<f32>>(t3.xy);
            let uvs = penumbra_triangle_uvs(t1.w);
            uv = penumbra_triangle_uv(uvs, 0u, bary);
            uv1 = penumbra_triangle_uv(uvs, 1u, bary);
            if penumbra_HAS_COLOURS && (push.flags & penumbra_FLAG_COLOURS) != 0u {
                vertex_colour = penumbra_triangle_colour(t1.w, bary);
            }
        }
    }
    penumbra_lod = bitcast<vec2<f32>>(t3.zw);
    let s = Surface(position, ns, penumbra_f3(t1), to_eye, uv, uv1, vertex_colour);
    let p = penumbra_prepare(s, penumbra_load_params(material.y));
    // The ambient terms with the first chunk of samples, then the samples
    // that reached the point (the shadow stage zeroed the others' falloff).
    var colour: vec3<f32>;
    if push.sample_first == 0u {
        colour = penumbra_ambient_sum(s, p);
        if penumbra_HAS_EMISSION && (push.flags & penumbra_FLAG_EMISSION) != 0u {
            let m = penumbra_surface_map(object, 0u);
            var emission = penumbra_f3(m) * texture_at(m.w, s).rgb;
            // KHR_materials_unlit: the colour emitted is also the vertex
            // colour's (surface_maps.wgsl, texel 3's z).
            if penumbra_HAS_COLOURS && penumbra_surface_map(object, 3u).z != 0u {
                emission *= vertex_colour.rgb;
            }
            colour += emission;
        }
    } else {
        colour = penumbra_radiance[slot].xyz;
    }
    // glTF's occlusionTexture, for the environment's light only (glTF 2.0,
    // material.occlusionTexture: "applies to indirect lighting"): the
    // factor 1 + strength × (R − 1), R linear (surface_maps.wgsl, texel 3).
    var occlusion = 1.0;
    if penumbra_HAS_OCCLUSION {
        let m = penumbra_surface_map(object, 3u);
        if m.x != penumbra_NO_TEXTURE {
            occlusion = 1.0 + bitcast<f32>(m.y) * (texture_at(m.x, s).r - 1.0);
        }
    }
    let base = slot * push.sample_count;
    // The chunk's samples light by light: lights in scene order, each
    // light's samples in turn (its sample count is the w of its specular
    // texel), so a light's colours are loaded once, not per sample. The
    // loops depend on the push constants only: every lane takes the same
    // steps.
    let chunk_end = push.sample_first + push.sample_count;
    var light_first = 0u;
    for (var i = 0u; i < push.light_count && light_first < chunk_end; i++) {
        let specular = textureLoad(penumbra_light_colours, penumbra_texel(3u * i + 1u));
        let light_end = light_first + specular.w;
        let first = max(light_first, push.sample_first);
        let end = min(light_end, chunk_end);
        if first < end {
            let diffuse = textureLoad(penumbra_light_colours, penumbra_texel(3u * i));
            // The environment's samples (its ambient texel's w is 1) take
            // the occlusion factor, the other lights' none.
            var scale = 1.0;
            if penumbra_HAS_OCCLUSION && textureLoad(penumbra_light_colours, penumbra_texel(3u * i + 2u)).w != 0u {
                scale = occlusion;
            }
            for (var k = first; k < end; k++) {
                let e = base + k - push.sample_first;
                let sample = textureLoad(penumbra_queue, penumbra_texel(e * penumbra_QUEUE_TEXELS));
                let falloff = bitcast<f32>(sample.w);
                if falloff > 0.0 {
                    let l = LightSample(penumbra_f3(sample), falloff * bitcast<f32>(diffuse.w), penumbra_f3(diffuse), penumbra_f3(specular));
                    if penumbra_HAS_OCCLUSION {
                        colour += scale * shade(s, l, p);
                    } else {
                        colour += shade(s, l, p);
                    }
                }
            }
        }
        light_first = light_end;
    }
    if (push.flags & penumbra_FLAG_LAST_CHUNK) == 0u {
        penumbra_radiance[slot] = vec4<f32>(colour, 1.0);
        return;
    }
    let at = px.y * push.size.x + px.x - push.slot_base;
    var value = vec4<f32>(colour, 1.0);
    if push.pass_index > 0u && (push.flags & penumbra_FLAG_FRESH) == 0u {
        value += penumbra_image[at];
    }
    if penumbra_STAGE_WORDS {
        penumbra_image_words[at] = penumbra_stage_words(bitcast<vec4<u32>>(value));
    } else {
        penumbra_image[at] = value;
    }
}
