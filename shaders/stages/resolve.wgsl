// Stage 2, material resolve: the checker is a selector between shaders, so
// each hit's shader is walked down its (possibly nested) checkers to the
// leaf shader at the hit point, whose program and parameters the shade stage
// then reads.

@group(0) @binding(16) var resolved: texture_storage_2d<rgba32uint, write>;

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
    let t0 = textureLoad(hit_records, record_texel(slot, 0u));
    if t0.w == KIND_NONE {
        return;
    }
    let t1 = textureLoad(hit_records, record_texel(slot, 1u));
    let shader = textureLoad(hit_records, record_texel(slot, 2u)).w;
    let leaf = resolve_shader(shader, bitcast<vec3<f32>>(t0.xyz), bitcast<vec3<f32>>(t1.xyz));
    let node = shader_nodes[leaf];
    textureStore(resolved, texel(slot), vec4<u32>(leaf, node.program, node.params, 0u));
}
