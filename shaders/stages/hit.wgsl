// Stage 1, camera rays and closest hit: one invocation per pixel of the
// band; writes the pixel's hit record.

@compute @workgroup_size(8, 8, 1)
fn hit_stage(@builtin(global_invocation_id) gid: vec3<u32>) {
    // The warm-up dispatch makes the driver compile the stage (lavapipe
    // compiles at the first dispatch) without touching any buffer.
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
        var rec: HitRecord;
        rec.kind = KIND_NONE;
        rec.t = bitcast<f32>(0x7f800000u);
        rec.object = 0xffffffffu;
        rec.index = 0xffffffffu;
        if hit.found {
            rec.position = hit.position;
            rec.t = hit.t;
            rec.geometric_normal = hit.geometric_normal;
            rec.kind = hit.kind;
            rec.shading_normal = hit.shading_normal;
            rec.index = hit.index;
            rec.to_eye = -ray.dir;
            rec.object = hit.object;
            if hit.kind == KIND_TRIANGLE {
                rec.bary = vec2<f32>(hit.u, hit.v);
            }
            rec.shader = hit.shader;
        }
        hit_records[tile_slot(px)] = rec;
        primary = 1u;
    }
    count_rays(0u, primary);
}
