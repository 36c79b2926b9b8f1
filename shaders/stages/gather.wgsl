// Stage 5, gather: each pixel's colour (the shade stage's sum, or the
// background where the primary ray hit nothing) is written to or added to
// the image.

// Linear RGB; alpha is 1 where a primary ray hit something, else 0.
@group(0) @binding(7) var<storage, read_write> image: array<vec4<f32>>;

@compute @workgroup_size(8, 8, 1)
fn gather_stage(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (push.flags & FLAG_WARM_UP) != 0u {
        return;
    }
    let px = stage_pixel(gid);
    if !in_image(px) {
        return;
    }
    let pixel = px.y * push.size.x + px.x;
    let slot = tile_slot(px);
    var value = vec4<f32>(globals.background, 0.0);
    if textureLoad(hit_records, record_texel(slot, 0u)).w != KIND_NONE {
        value = vec4<f32>(radiance[slot].xyz, 1.0);
    }
    if push.pass_index > 0u && (push.flags & FLAG_FRESH) == 0u {
        value += image[pixel - push.slot_base];
    }
    image[pixel - push.slot_base] = value;
}
