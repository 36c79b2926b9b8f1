//! SPIR-V post-processing: every floating-point add, subtract, multiply and
//! negate the kernels compute is decorated `NoContraction`, so no driver
//! fuses a multiply and an add into one rounding (FMA).
//!
//! Why: the watertight triangle test (Woop, Benthin and Wald, JCGT 2013)
//! holds only if two triangles that share an edge compute that edge's
//! function from the same rounded products; a compiler that fuses
//! `cx * by - cy * bx` into `fma(cx, by, -(cy * bx))` rounds the two
//! triangles' products differently, and rays slip between them. WGSL lets an
//! implementation contract, and naga emits no `NoContraction` of its own
//! (there is no `precise` in WGSL), so we add it here, as glslang does for
//! GLSL's `precise`. NVIDIA's driver does contract, and without this pass
//! the closed meshes of `tests/gpu/hard_cases.rs` leaked there, as did the
//! diagonal of the textured quads of `tests/gpu/textures.rs`; lavapipe does
//! not, so on it the decoration changes no bit of any image (docs/gpu.md has
//! both runs and their commands).

/// `OpDecorate`.
const OP_DECORATE: u32 = 71;
/// `OpMemberDecorate`.
const OP_MEMBER_DECORATE: u32 = 72;
/// `OpFunction`: the first function ends the module's declarations.
const OP_FUNCTION: u32 = 54;
/// The `NoContraction` decoration.
const NO_CONTRACTION: u32 = 42;
/// Words of the module header (magic, version, generator, bound, schema).
const HEADER_WORDS: usize = 5;

/// The float arithmetic instructions a driver could fuse, each with its
/// result id as word 2 (word 1 is the result type): `OpFNegate`, `OpFAdd`,
/// `OpFSub`, `OpFMul`, `OpVectorTimesScalar`, `OpMatrixTimesScalar`,
/// `OpVectorTimesMatrix`, `OpMatrixTimesVector`, `OpMatrixTimesMatrix`,
/// `OpDot`.
const CONTRACTIBLE: [u32; 10] = [127, 129, 131, 133, 142, 143, 144, 145, 146, 148];

/// The module's instructions after the header, each as its word offset,
/// opcode and operands (the words after the first); `None` if the words do
/// not parse as instructions (a word count of zero or past the end).
fn instructions(words: &[u32]) -> Option<Vec<(usize, u32, &[u32])>> {
    let mut out = Vec::new();
    let mut at = HEADER_WORDS;
    while at < words.len() {
        let (op, count) = (words[at] & 0xffff, (words[at] >> 16) as usize);
        if count == 0 || at + count > words.len() {
            return None;
        }
        out.push((at, op, &words[at + 1..at + count]));
        at += count;
    }
    Some(out)
}

/// The result id of a [`CONTRACTIBLE`] instruction (its second operand).
fn contractible_result(op: u32, operands: &[u32]) -> Option<u32> {
    CONTRACTIBLE
        .contains(&op)
        .then(|| operands.get(1).copied())
        .flatten()
}

/// `words` with a `NoContraction` decoration for the result of every
/// [`CONTRACTIBLE`] instruction, placed after the module's other
/// decorations (the annotation section, which precedes the types).
///
/// A module that does not parse as a sequence of instructions (a word count
/// of zero or past the end) is returned unchanged: naga wrote it, so that
/// would be a bug of ours, and the driver's own validation then reports it.
pub fn forbid_contraction(words: Vec<u32>) -> Vec<u32> {
    let Some(ins) = instructions(&words) else {
        return words;
    };
    let results: Vec<u32> = ins
        .iter()
        .filter_map(|&(_, op, operands)| contractible_result(op, operands))
        .collect();
    // Where the new decorations go: after the last decoration before the
    // first function, or, with none, before the first function.
    let first_function = ins
        .iter()
        .position(|&(_, op, _)| op == OP_FUNCTION)
        .unwrap_or(ins.len());
    let insert_at = ins[..first_function]
        .iter()
        .rfind(|&&(_, op, _)| op == OP_DECORATE || op == OP_MEMBER_DECORATE)
        .map(|&(at, _, operands)| at + 1 + operands.len())
        .or(ins.get(first_function).map(|&(at, _, _)| at));
    let Some(insert_at) = insert_at else {
        return words;
    };
    let mut out = Vec::with_capacity(words.len() + 3 * results.len());
    out.extend_from_slice(&words[..insert_at]);
    for id in results {
        out.extend_from_slice(&[(3 << 16) | OP_DECORATE, id, NO_CONTRACTION]);
    }
    out.extend_from_slice(&words[insert_at..]);
    out
}

/// The float arithmetic results of `words` that lack `NoContraction`
/// (tests check that every module the renderer compiles has none).
#[cfg(test)]
pub(crate) fn contractible_results(words: &[u32]) -> usize {
    let ins = instructions(words).expect("SPIR-V that parses");
    let decorated: std::collections::HashSet<u32> = ins
        .iter()
        .filter(|&&(_, op, w)| op == OP_DECORATE && w.len() == 2 && w[1] == NO_CONTRACTION)
        .map(|&(_, _, w)| w[0])
        .collect();
    ins.iter()
        .filter_map(|&(_, op, w)| contractible_result(op, w))
        .filter(|id| !decorated.contains(id))
        .count()
}

/// The capabilities `words` declares (`OpCapability` operands).
#[cfg(test)]
pub(crate) fn capabilities(words: &[u32]) -> Vec<u32> {
    /// `OpCapability`.
    const OP_CAPABILITY: u32 = 17;
    instructions(words)
        .expect("SPIR-V that parses")
        .into_iter()
        .filter(|&(_, op, _)| op == OP_CAPABILITY)
        .filter_map(|(_, _, w)| w.first().copied())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// SPIR-V of a small WGSL module.
    fn spirv(src: &str) -> Vec<u32> {
        let (module, info) = crate::render::compile::valid_module(src);
        let options = naga::back::spv::Options {
            lang_version: (1, 3),
            flags: naga::back::spv::WriterFlags::empty(),
            ..Default::default()
        };
        naga::back::spv::write_vec(&module, &info, &options, None).expect("SPIR-V")
    }

    /// The instructions of a module as (opcode, operands).
    fn ops(words: &[u32]) -> Vec<(u32, Vec<u32>)> {
        instructions(words)
            .expect("SPIR-V that parses")
            .into_iter()
            .map(|(_, op, w)| (op, w.to_vec()))
            .collect()
    }

    const SRC: &str = "
        @group(0) @binding(0) var<storage, read_write> data: array<vec4<f32>>;
        fn edge(a: vec2<f32>, b: vec2<f32>) -> f32 {
            return a.x * b.y - a.y * b.x;
        }
        @compute @workgroup_size(1)
        fn main() {
            let a = data[0];
            let d = dot(a.xyz, a.yzx) + edge(a.xy, a.zw) - a.w;
            data[1] = vec4<f32>(-d, a.x * 2.0, a.y + a.z, d);
        }";

    #[test]
    fn every_float_operation_is_decorated_once_in_the_annotations() {
        let before = spirv(SRC);
        let after = forbid_contraction(before.clone());
        let ins = ops(&after);
        let arithmetic: Vec<u32> = ins
            .iter()
            .filter(|(op, _)| CONTRACTIBLE.contains(op))
            .map(|(_, w)| w[1])
            .collect();
        // The module has multiplies, adds, subtractions, a negation and a dot.
        assert!(arithmetic.len() >= 6, "{arithmetic:?}");
        let decorated: Vec<u32> = ins
            .iter()
            .filter(|(op, w)| *op == OP_DECORATE && w.get(1) == Some(&NO_CONTRACTION))
            .map(|(_, w)| w[0])
            .collect();
        assert_eq!(decorated, arithmetic);
        // Nothing else changed: the module is the old one plus 3 words a
        // decoration, and every decoration precedes every type and function
        // (OpTypeVoid is 19).
        assert_eq!(after.len(), before.len() + 3 * arithmetic.len());
        let last_decoration = ins.iter().rposition(|(op, _)| *op == OP_DECORATE).unwrap();
        let first_type = ins
            .iter()
            .position(|(op, _)| (19..=39).contains(op))
            .unwrap();
        assert!(last_decoration < first_type);
        let without: Vec<(u32, Vec<u32>)> = ins
            .into_iter()
            .filter(|(op, w)| !(*op == OP_DECORATE && w.get(1) == Some(&NO_CONTRACTION)))
            .collect();
        assert_eq!(without, ops(&before));
        assert!(contractible_results(&before) >= 6);
        assert_eq!(contractible_results(&after), 0);
    }

    #[test]
    fn a_module_that_does_not_parse_is_left_alone() {
        // An OpFAdd of five words, cut off after the first.
        let mut words = spirv(SRC);
        words.push((5 << 16) | 129);
        assert_eq!(forbid_contraction(words.clone()), words);
        let mut zero = spirv(SRC);
        zero[HEADER_WORDS] &= 0xffff;
        assert_eq!(forbid_contraction(zero.clone()), zero);
    }
}
