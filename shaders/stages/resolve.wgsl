// Stage 2, material resolve: the checker is a selector between shaders, so
// each hit's shader is walked down its (possibly nested) checkers to the
// leaf shader at the hit point, whose program and parameters the shade stage
// then reads from the record.

@compute @workgroup_size(8, 8, 1)
fn resolve_stage(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (push.flags & FLAG_WARM_UP) != 0u {
        return;
    }
    let px = stage_pixel(gid);
    if !in_image(px) {
        return;
    }
    let slot = tile_slot(px);
    // Member by member: lavapipe loads a storage buffer at a per-lane
    // address word by word (shaders/texels.wgsl), so a stage reads only the
    // members it needs.
    if hit_records[slot].kind == KIND_NONE {
        return;
    }
    let leaf = resolve_shader(hit_records[slot].shader, hit_records[slot].position, hit_records[slot].geometric_normal);
    let node = shader_nodes[leaf];
    hit_records[slot].shader = leaf;
    hit_records[slot].program = node.program;
    hit_records[slot].params = node.params;
}
