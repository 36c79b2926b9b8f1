// Stage 4, shadows: any-hit traversal of the queued shadow rays of each
// pixel (adjacent pixels trace the same light sample together, so the rays
// of a SIMD group are coherent). An occluded sample's falloff becomes 0: the
// shade stage adds the contribution of every sample that reaches its light.

@compute @workgroup_size(8, 8, 1)
fn shadow_stage(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (push.flags & FLAG_WARM_UP) != 0u {
        return;
    }
    let px = stage_pixel(gid);
    var traced = 0u;
    if in_image(px) {
        let slot = tile_slot(px);
        // Only the members this stage needs (stages/resolve.wgsl says why).
        let kind = hit_records[slot].kind;
        if kind != KIND_NONE {
            var start: Hit;
            start.found = true;
            start.kind = kind;
            start.index = hit_records[slot].index;
            start.position = hit_records[slot].position;
            start.geometric_normal = hit_records[slot].geometric_normal;
            let base = slot * push.sample_count;
            for (var e = 0u; e < push.sample_count; e++) {
                if queue_falloff[base + e] > 0.0 {
                    traced += 1u;
                    let ray = queue_rays[base + e];
                    if occluded(start, ray.xyz, ray.w) {
                        queue_falloff[base + e] = 0.0;
                    }
                }
            }
        }
    }
    count_rays(1u, traced);
}
