// Stage 2, light samples and shadows: for each light sample of the chunk
// the queue holds, the direction to the light and its falloff at the hit
// point (queued: stages/records.wgsl), and an any-hit traversal of its
// shadow ray up to the light. A sample
// below the geometric surface or the shading normal needs no ray (the
// surface itself is in the way); it and an occluded one get falloff 0, so
// the shade stage adds the contribution of every sample that reaches its
// light. Nothing here depends on a shader: after a shading edit the queue is
// still valid. Adjacent pixels trace the same light sample together, so the
// rays of a SIMD group are coherent.
//
// When one chunk holds all of a pixel's samples (FUSED_SHADOWS), the hit
// stage calls `queue_light_samples` right after the closest hit, with the
// hit still in registers, and this pipeline does not run: reading the hit
// records back cost about as much as the shadow rays' traversal
// (docs/stages.md). With several chunks, this pipeline runs once per chunk.

@group(0) @binding(15) var queue: texture_storage_2d<rgba32uint, write>;
// The queue's memory as words (STAGE_WORDS: render.wgsl).
@group(0) @binding(25) var<storage, read_write> queue_words: array<vec2<u64>>;

@compute @workgroup_size(64, 1, 1)
fn shadow_stage(
    @builtin(workgroup_id) workgroup: vec3<u32>,
    @builtin(local_invocation_index) index: u32,
    @builtin(subgroup_id) subgroup: u32,
    @builtin(subgroup_size) subgroup_size: u32,
    @builtin(subgroup_invocation_id) lane: u32,
) {
    // Before any branch (see first_light).
    first_light = lights[0];
    if (push.flags & FLAG_WARM_UP) != 0u {
        return;
    }
    let px = stage_pixel(StageInvocation(workgroup, index, subgroup, subgroup_size, lane));
    var traced = 0u;
    if in_image(px) {
        let slot = tile_slot(px);
        let t0 = textureLoad(hit_records, record_texel(slot, 0u));
        var start: Hit;
        start.found = t0.w != KIND_NONE;
        start.kind = record_kind(t0.w);
        var shading_normal = vec3<f32>(0.0);
        if start.found {
            let t1 = textureLoad(hit_records, record_texel(slot, 1u));
            start.position = bitcast<vec3<f32>>(t0.xyz);
            start.geometric_normal = bitcast<vec3<f32>>(t1.xyz);
            start.index = t1.w;
            shading_normal = bitcast<vec3<f32>>(textureLoad(hit_records, record_texel(slot, 2u)).xyz);
        }
        let pixel = px.y * push.size.x + px.x;
        traced = queue_light_samples(pixel, slot, start, shading_normal);
    }
    count_rays(1u, traced);
}

// Queues the light samples `push.sample_first ..` of the chunk for the
// pixel `pixel` with record `slot`, whose primary ray hit `start` (only its
// found, kind, index, position and geometric normal are read) with shading
// normal `shading_normal`; returns the number of shadow rays traced. The
// caller has loaded `first_light`.
fn queue_light_samples(pixel: u32, slot: u32, start: Hit, shading_normal: vec3<f32>) -> u32 {
    alpha_pixel = pixel;
    alpha_stream = 0x0b1f0000u + push.pass_index;
    var traced = 0u;
    let base = slot * push.sample_count;
    let first = push.sample_first;
    let end = first + push.sample_count;
    // The direction to the eye (the camera sits at the origin): a
    // perspective ray left it towards the point, an orthographic one along
    // the view direction (as the shade stage's to_eye).
    var to_eye = -globals.camera.forward;
    if globals.camera.orthographic == 0u && start.found {
        to_eye = -normalize(start.position);
    }
    // Sample k of the pixel (lights in scene order, each light's samples in
    // turn) is light i's sample j = k - (the samples of the lights before
    // it); the loops visit only the chunk's, first <= k < end.
    var k = 0u;
    for (var i = 0u; i < globals.num_lights; i++) {
        if k >= end {
            break;
        }
        var light = first_light;
        if i > 0u {
            light = light_at(i);
        }
        let count = light_sample_count(light);
        // This light's samples in the chunk: j in [j_first, j_end).
        let j_first = max(first, k) - k;
        let j_end = min(end - k, count);
        // The light's samples share their sequence's shift. (Nested ifs:
        // pruning removes a constant `if`, not a lowered `&&`.)
        var shift = vec2<u32>();
        if HAS_AREA_LIGHTS {
            if SAMPLER != SAMPLER_RANDOM {
                shift = sample_shift(pixel, 1u + i);
            }
        }
        for (var j = j_first; j < j_end; j++) {
            var to_light = vec3<f32>(0.0);
            var falloff = 0.0;
            if start.found {
                var uv = vec2<f32>(0.5);
                if HAS_AREA_LIGHTS {
                    uv = sample_2d_shifted(shift, pixel, 1u + i, push.pass_index * count + j);
                }
                let ls = sample_light(light, start.position, shading_normal, to_eye, uv);
                if dot(ls.to_light, shading_normal) > 0.0 && ls.falloff > 0.0 && dot(ls.to_light, start.geometric_normal) > 0.0 {
                    // Distance 0: a sample evaluated without visibility
                    // (the environment), no shadow ray to trace or count.
                    let traces = ls.distance > 0.0;
                    traced += select(0u, 1u, traces);
                    if !traces || !occluded(start, ls.to_light, ls.distance) {
                        to_light = ls.to_light;
                        falloff = ls.falloff;
                    }
                }
            }
            let entry = base + k + j - first;
            let value = vec4<u32>(bitcast<vec3<u32>>(to_light), bitcast<u32>(falloff));
            if STAGE_WORDS {
                queue_words[entry * QUEUE_TEXELS] = stage_words(value);
            } else {
                textureStore(queue, queue_texel(entry, 0u), value);
            }
        }
        k += count;
    }
    return traced;
}
