// Stage 1, camera rays and closest hit: one invocation per pixel of the
// band; writes the pixel's hit record and, when the scene has checkers, its
// resolved material (stages/resolve.wgsl), the background where the ray
// hit nothing (the shade stage writes the other pixels), and, when asked
// for, the AOVs. With
// FUSED_SHADOWS (one chunk holds every light sample of a pixel) it also
// queues the light samples and traces their shadow rays
// (stages/shadow.wgsl), from the hit it has in registers.

@group(0) @binding(14) var hit_records_out: texture_storage_2d<rgba32uint, write>;
// The records' memory as words (STAGE_WORDS: render.wgsl).
@group(0) @binding(24) var<storage, read_write> hit_record_words: array<vec2<u64>>;

// Writes texel `i` of record `slot`.
fn store_record(slot: u32, i: u32, value: vec4<u32>) {
    if STAGE_WORDS {
        hit_record_words[slot * RECORD_TEXELS + i] = stage_words(value);
    } else {
        textureStore(hit_records_out, record_texel(slot, i), value);
    }
}

// Linear RGB; alpha is 1 where a primary ray hit something, else 0.
@group(0) @binding(7) var<storage, read_write> image: array<vec4<f32>>;

@compute @workgroup_size(64, 1, 1)
fn hit_stage(
    @builtin(workgroup_id) workgroup: vec3<u32>,
    @builtin(local_invocation_index) index: u32,
    @builtin(subgroup_id) subgroup: u32,
    @builtin(subgroup_size) subgroup_size: u32,
    @builtin(subgroup_invocation_id) lane: u32,
) {
    // Before any branch (see first_light).
    if FUSED_SHADOWS {
        first_light = lights[0];
    }
    // The warm-up dispatch makes the driver compile the stage (lavapipe
    // compiles at the first dispatch) without touching any resource.
    if (push.flags & FLAG_WARM_UP) != 0u {
        return;
    }
    let px = stage_pixel(StageInvocation(workgroup, index, subgroup, subgroup_size, lane));
    var primary = 0u;
    var traced = 0u;
    if in_image(px) {
        let pixel = px.y * push.size.x + px.x;
        // One sample per pass: the pixel centre, or a stratified point in the
        // pixel (box filter) when several samples per pixel are asked for.
        var sub = vec2<f32>(0.5);
        if PIXEL_JITTER {
            sub = sample_2d(pixel, 0u, push.pass_index);
        }
        let ray = primary_ray(globals.camera, px, push.size, sub);
        alpha_pixel = pixel;
        alpha_stream = 0x0b1e0000u + push.pass_index;
        let hit = closest_hit(ray);
        let slot = tile_slot(px);
        if hit.found {
            store_record(slot, 0u, vec4<u32>(bitcast<vec3<u32>>(hit.position), record_kind_object(hit.kind, hit.object)));
            store_record(slot, 1u, vec4<u32>(bitcast<vec3<u32>>(hit.geometric_normal), hit.index));
            store_record(slot, 2u, vec4<u32>(bitcast<vec3<u32>>(hit.shading_normal), hit.shader));
            if record_coords() {
                store_record(slot, 3u, vec4<u32>(bitcast<vec2<u32>>(hit.coords), bitcast<vec2<u32>>(hit.lambda)));
            }
            // Without checkers the shade stage reads the leaf, the hit's own
            // shader, from the shader table.
            if HAS_CHECKER {
                resolve_material(slot, hit);
            }
        } else {
            store_record(slot, 0u, vec4<u32>(0u, 0u, 0u, KIND_NONE));
            var value = vec4<f32>(globals.background, 0.0);
            let at = pixel - push.slot_base;
            if push.pass_index > 0u && (push.flags & FLAG_FRESH) == 0u {
                value += image[at];
            }
            image[at] = value;
        }
        if HAS_AOV && push.pass_index == 0u {
            write_aov(pixel - push.slot_base, hit);
        }
        // The shade stage reads no queue entry of a pixel that hit nothing.
        if FUSED_SHADOWS && hit.found {
            traced = queue_light_samples(pixel, slot, hit, hit.shading_normal);
        }
        primary = 1u;
    }
    count_rays(0u, primary);
    if FUSED_SHADOWS {
        count_rays(1u, traced);
    }
}
