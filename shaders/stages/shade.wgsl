// Stage 3b, shade: one pipeline per shader file. The host compiles this
// file with shading/interface.wgsl, the shader file, and the parameter
// loader it generates from the file's `struct Params` (src/render/shade.rs):
//   fn penumbra_load_params(at: u32) -> Params
//   fn penumbra_ambient_sum(s: Surface, p: Params) -> vec3<f32>
// (the sum of the file's `ambient` over the lights, or 0 without one)
// Every name here starts with `penumbra_`, so no shader file can collide
// with the engine. The stage traces nothing: it sums the shader's ambient
// term of every light and its `shade` of every queued light sample that
// reached the point (the shadow stage zeroed the others).
//
// The structs below mirror HitRecord (stages/records.wgsl), Light
// (lights.wgsl) and PushConstants (render.wgsl); the layout test in
// src/render/layout.rs checks all of them against the host's.

struct penumbra_HitRecord {
    position: vec3<f32>,
    t: f32,
    geometric_normal: vec3<f32>,
    kind: u32,
    shading_normal: vec3<f32>,
    index: u32,
    to_eye: vec3<f32>,
    object: u32,
    uv: vec2<f32>,
    bary: vec2<f32>,
    shader: u32,
    program: u32,
    params: u32,
    _pad: u32,
}

struct penumbra_Light {
    position: vec3<f32>,
    kind: u32,
    direction: vec3<f32>,
    cone_scale: f32,
    ambient: vec3<f32>,
    cone_offset: f32,
    diffuse: vec3<f32>,
    samples: u32,
    specular: vec3<f32>,
    radius: f32,
    edge1: vec3<f32>,
    intensity: f32,
    edge2: vec3<f32>,
    _pad1: u32,
}

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

@group(0) @binding(5) var<storage, read> penumbra_lights: array<penumbra_Light>;
@group(0) @binding(14) var<storage, read> penumbra_hit_records: array<penumbra_HitRecord>;
@group(0) @binding(15) var<storage, read> penumbra_queue_rays: array<vec4<f32>>;
@group(0) @binding(16) var<storage, read> penumbra_queue_samples: array<vec2<f32>>;
@group(0) @binding(17) var<storage, read_write> penumbra_radiance: array<vec4<f32>>;
// Every leaf shader's parameters, packed as 32-bit words in the order of
// its Params fields (a vecN takes N words).
@group(0) @binding(18) var<storage, read> penumbra_params: array<u32>;
var<immediate> penumbra_push: penumbra_PushConstants;

// render.wgsl's FLAG_WARM_UP and KIND_NONE of stages/records.wgsl.
const penumbra_FLAG_WARM_UP: u32 = 1u;
const penumbra_KIND_NONE: u32 = 0xffffffffu;

@compute @workgroup_size(8, 8, 1)
fn penumbra_shade_stage(@builtin(global_invocation_id) gid: vec3<u32>) {
    let push = penumbra_push;
    if (push.flags & penumbra_FLAG_WARM_UP) != 0u {
        return;
    }
    let px = gid.xy + push.origin;
    if px.x >= push.size.x || px.y >= push.size.y {
        return;
    }
    let local = px - push.tile_origin;
    let slot = local.y * push.tile_width + local.x;
    // Member by member, the test first: lavapipe loads a storage buffer at
    // a per-lane address word by word (shaders/texels.wgsl).
    if penumbra_hit_records[slot].kind == penumbra_KIND_NONE || penumbra_hit_records[slot].program != push.program {
        return;
    }
    let rec = &penumbra_hit_records[slot];
    let s = Surface((*rec).position, (*rec).shading_normal, (*rec).geometric_normal, (*rec).to_eye, (*rec).uv);
    let p = penumbra_load_params((*rec).params);
    // The ambient terms with the first chunk of samples, then the samples
    // that reached the point (the shadow stage zeroed the others' falloff).
    var colour: vec3<f32>;
    if push.sample_first == 0u {
        colour = penumbra_ambient_sum(s, p);
    } else {
        colour = penumbra_radiance[slot].xyz;
    }
    let base = slot * push.sample_count;
    for (var e = 0u; e < push.sample_count; e++) {
        let sample = penumbra_queue_samples[base + e];
        if sample.x > 0.0 {
            let light = &penumbra_lights[bitcast<u32>(sample.y)];
            let l = LightSample(penumbra_queue_rays[base + e].xyz, sample.x * (*light).intensity, (*light).diffuse, (*light).specular);
            colour += shade(s, l, p);
        }
    }
    penumbra_radiance[slot] = vec4<f32>(colour, 1.0);
}
