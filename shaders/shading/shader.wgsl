// The scene's shaders as a flat table: leaves (a shader file, its program,
// and where its parameters start in the parameter words) and checkers whose
// sub-shaders are indices into the same table (nesting without recursion).

const SHADER_LEAF: u32 = 0u;
const SHADER_CHECKER: u32 = 2u;

// Mirrored by render::layout::ShaderNode.
struct ShaderNode {
    cell_offset: vec3<f32>,
    inv_size: f32,
    kind: u32,
    parity: u32,
    even: u32,
    odd: u32,
    // Leaves: the shade program (one per shader file) and the first of the
    // shader's parameter words.
    program: u32,
    params: u32,
    _pad0: u32,
    _pad1: u32,
}

// Texels, SHADER_NODE_TEXELS a node (shaders/texels.wgsl says why: the
// resolve walk loads a node at a per-lane index).
@group(0) @binding(6) var shader_nodes: texture_storage_2d<rgba32uint, read>;
const SHADER_NODE_TEXELS: u32 = 3u;

// Node `i`, from its texels: the struct's words in order.
fn shader_node(i: u32) -> ShaderNode {
    let base = i * SHADER_NODE_TEXELS;
    let a = textureLoad(shader_nodes, texel(base));
    let b = textureLoad(shader_nodes, texel(base + 1u));
    let c = textureLoad(shader_nodes, texel(base + 2u));
    return ShaderNode(bitcast<vec3<f32>>(a.xyz), bitcast<f32>(a.w), b.x, b.y, b.z, b.w, c.x, c.y, c.z, c.w);
}

// Walks down nested checkers to the leaf shader at `p` (`n`: the normal
// facing the viewer); returns its index. Validation rules out cycles; the
// bound keeps a bad table from hanging.
fn resolve_shader(id: u32, p: vec3<f32>, n: vec3<f32>) -> u32 {
    var at = id;
    if HAS_CHECKER {
        var node = shader_node(at);
        for (var depth = 0u; depth < globals.num_shaders && node.kind == SHADER_CHECKER; depth++) {
            at = select(node.odd, node.even, checker_is_even(node, p, n));
            node = shader_node(at);
        }
    }
    return at;
}
