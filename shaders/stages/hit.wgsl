// Stage 1, camera rays and closest hit: one invocation per pixel of the
// band; writes the pixel's hit record (and, when asked for, its AOVs).

@group(0) @binding(14) var hit_records_out: texture_storage_2d<rgba32uint, write>;

@compute @workgroup_size(8, 8, 1)
fn hit_stage(@builtin(global_invocation_id) gid: vec3<u32>) {
    // The warm-up dispatch makes the driver compile the stage (lavapipe
    // compiles at the first dispatch) without touching any resource.
    if (push.flags & FLAG_WARM_UP) != 0u {
        return;
    }
    let px = stage_pixel(gid);
    var primary = 0u;
    if in_image(px) {
        let pixel = px.y * push.size.x + px.x;
        // One sample per pass: the pixel centre, or a stratified point in the
        // pixel (box filter) when several samples per pixel are asked for.
        var sub = vec2<f32>(0.5);
        if PIXEL_JITTER {
            sub = sample_2d(pixel, 0u, push.pass_index);
        }
        let ray = primary_ray(globals.camera, px, push.size, sub);
        let hit = closest_hit(ray);
        let slot = tile_slot(px);
        if hit.found {
            textureStore(hit_records_out, record_texel(slot, 0u), vec4<u32>(bitcast<vec3<u32>>(hit.position), hit.kind));
            textureStore(hit_records_out, record_texel(slot, 1u), vec4<u32>(bitcast<vec3<u32>>(hit.geometric_normal), hit.index));
            textureStore(hit_records_out, record_texel(slot, 2u), vec4<u32>(bitcast<vec3<u32>>(hit.shading_normal), hit.shader));
            textureStore(hit_records_out, record_texel(slot, 3u), vec4<u32>(bitcast<vec3<u32>>(-ray.dir), 0u));
            textureStore(hit_records_out, record_texel(slot, 4u), vec4<u32>(0u));
        } else {
            textureStore(hit_records_out, record_texel(slot, 0u), vec4<u32>(0u, 0u, 0u, KIND_NONE));
        }
        if HAS_AOV && push.pass_index == 0u {
            write_aov(pixel, hit);
        }
        primary = 1u;
    }
    count_rays(0u, primary);
}
