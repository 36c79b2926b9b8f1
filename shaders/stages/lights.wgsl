// Stage 3a, light sampling: for each light sample of the chunk the queue
// holds, the direction and distance to the light and its falloff at the hit
// point, or falloff 0 where the sample lies below the geometric surface or
// the shading normal (the surface itself is in the way: no ray needed).
// Shader-independent, so the queue (and, after stage 4, its visibility)
// stays valid across shading edits.

@compute @workgroup_size(8, 8, 1)
fn light_stage(@builtin(global_invocation_id) gid: vec3<u32>) {
    // Before any branch (see first_light).
    first_light = lights[0];
    if (push.flags & FLAG_WARM_UP) != 0u {
        return;
    }
    let px = stage_pixel(gid);
    if !in_image(px) {
        return;
    }
    let slot = tile_slot(px);
    // Only the members this stage needs (stages/resolve.wgsl says why).
    let found = hit_records[slot].kind != KIND_NONE;
    var position = vec3<f32>(0.0);
    var shading_normal = vec3<f32>(0.0);
    var geometric_normal = vec3<f32>(0.0);
    if found {
        position = hit_records[slot].position;
        shading_normal = hit_records[slot].shading_normal;
        geometric_normal = hit_records[slot].geometric_normal;
    }
    let pixel = px.y * push.size.x + px.x;
    let base = slot * push.sample_count;
    let first = push.sample_first;
    let end = first + push.sample_count;
    var k = 0u;
    for (var i = 0u; i < globals.num_lights && k < end; i++) {
        var light = first_light;
        if i > 0u {
            light = lights[i];
        }
        let count = light_sample_count(light);
        if k + count <= first {
            k += count;
            continue;
        }
        for (var j = 0u; j < count; j++) {
            if k >= first && k < end {
                var entry = vec4<f32>(0.0);
                var falloff = 0.0;
                if found {
                    var uv = vec2<f32>(0.5);
                    if HAS_AREA_LIGHTS {
                        uv = sample_2d(pixel, 1u + i, push.pass_index * count + j);
                    }
                    let ls = sample_light(light, position, uv);
                    if dot(ls.to_light, shading_normal) > 0.0 && ls.falloff > 0.0 && dot(ls.to_light, geometric_normal) > 0.0 {
                        entry = vec4<f32>(ls.to_light, ls.distance);
                        falloff = ls.falloff;
                    }
                }
                queue_rays[base + k - first] = entry;
                queue_falloff[base + k - first] = falloff;
            }
            k++;
        }
    }
}
