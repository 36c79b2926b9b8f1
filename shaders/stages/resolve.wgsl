// Material resolve, run by the hit stage for each hit of a scene with
// checkers (HAS_CHECKER; without them the leaf is the hit's own shader,
// which the shade stage looks up itself): the checker is a
// selector between shaders, so the hit's shader is walked down its (possibly
// nested) checkers to the leaf shader at the hit point, whose program and
// parameters the shade stage then reads. (A pipeline of its own cost a
// full-screen pass; see docs/stages.md.)

// Material resolve's result per record (stages/records.wgsl), and the same
// memory as words (STAGE_WORDS).
@group(0) @binding(16) var resolved: texture_storage_2d<rgba32uint, write>;
@group(0) @binding(26) var<storage, read_write> resolved_words: array<vec2<u64>>;

fn resolve_material(slot: u32, hit: Hit) {
    let leaf = resolve_shader(hit.shader, hit.position, hit.geometric_normal);
    let node = shader_node(leaf);
    let value = vec4<u32>(leaf, node.program, node.params, 0u);
    if STAGE_WORDS {
        resolved_words[slot] = stage_words(value);
    } else {
        textureStore(resolved, texel(slot), value);
    }
}
