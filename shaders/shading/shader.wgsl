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

@group(0) @binding(6) var<storage, read> shader_nodes: array<ShaderNode>;

// Walks down nested checkers to the leaf shader at `p` (`n`: the normal
// facing the viewer); returns its index. Validation rules out cycles; the
// bound keeps a bad table from hanging.
fn resolve_shader(id: u32, p: vec3<f32>, n: vec3<f32>) -> u32 {
    var at = id;
    if HAS_CHECKER {
        var node = shader_nodes[at];
        for (var depth = 0u; depth < globals.num_shaders && node.kind == SHADER_CHECKER; depth++) {
            at = select(node.odd, node.even, checker_is_even(node, p, n));
            node = shader_nodes[at];
        }
    }
    return at;
}
