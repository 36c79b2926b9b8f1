//! The BVH as the kernel reads it: one record per interior node holding both
//! children's boxes, quantised to 8 bits per coordinate in a frame of the
//! node (after Ylitie, Karras and Laine, "Efficient Incoherent Ray Traversal
//! on GPUs Through Compressed Wide BVHs", HPG 2017, here for two children).
//!
//! Why: lavapipe loads storage-buffer data separately for each of the 8
//! lanes of a SIMD group (a mask test per lane, then a bounds check, a
//! branch and a scalar load per lane and 32-bit component), so a traversal
//! step costs about as much as the words it loads. With a node per child
//! (`f32` box, child index, count) a step loaded 16 words: the node's index
//! and count, then each child's two box corners. A record here needs 9: the
//! frame and its scales, the twelve steps, the two child references;
//! decoding them is cheap vector arithmetic. The kernel reads each record
//! as texels of a read-only storage image (`vulkan::TexelImage`), whose
//! loads are straight-line code on lavapipe, two of them: each axis's frame
//! origin is stored as its step count and the step's exponent in one word,
//! so a record takes 32 bytes per interior node (half the memory of two
//! 32-byte nodes) and a traversal step fetches two texels, not three.
//! docs/bench.md §6 and docs/history.md have the measurements.
//!
//! Conservative by construction: each axis of a record is quantised on a
//! grid `k·2^e` coarse enough that every grid point within reach is an
//! `f32`, so the kernel's `origin + f32(q) * 2^e` is exact — no rounding, no
//! subnormals, the same on every device, fused or not — and the encoder
//! picks the grid points below and above each child's corners (checked
//! exactly). The decoded box therefore always contains the exact `f32` box,
//! and the slab test's widening (Ize 2013) applies to it unchanged.
//!
//! Fast: the encoder quantises all three axes at once in `f32` SIMD lanes
//! (exact for coordinates below 2⁹⁰, where every step of it is a normal
//! `f32`; an `f64` path with the same checks takes larger ones), and walks
//! the tree in parallel, each subtree writing its own run of records
//! (straight from the builder's chunks), so encoding stays a small part of
//! the build (`cargo run --release -p penumbra-tools --bin build_time` prints the phases).

use glam::Vec3A;

use super::layout::{node_bounds, BvhNode};
use crate::bvh::{Aabb, Chunked, Node, Tree};

/// A child reference with this bit set is a leaf: the low bits give its
/// first entry in the primitive references (the last one carries
/// [`PRIM_LAST`]).
pub const LEAF: u32 = 1 << 31;
/// The absent child (the right one of a tree that is a single leaf).
pub const NONE: u32 = u32::MAX;
/// Set on the last primitive reference of each leaf.
pub const PRIM_LAST: u32 = 1 << 30;
/// Smallest scale exponent: `q * 2^e` stays a normal float for `q >= 1`.
const MIN_EXP: i32 = -118;
/// Largest scale exponent (biased 254, the largest finite one).
const MAX_EXP: i32 = 127;

/// Encodes a built hierarchy as the builder leaves it ([`Chunked`]: no
/// flat copy needed): one record per interior node in depth-first order,
/// the root's first, each child's decoded box containing [`node_bounds`]
/// of the child's box (padded for the rounding of the ray/primitive
/// tests). The root's own box is never tested (its children's boxes lie
/// inside it, so that test would only cost a step). A tree that is a single
/// leaf gets one record with that leaf on the left and [`NONE`] on the
/// right. `prims` are the tree's primitive references; the last of each
/// leaf gets [`PRIM_LAST`].
pub fn encode(built: &Chunked, prims: &mut [u32]) -> Vec<BvhNode> {
    let Some(tree) = &built.tree else {
        return Vec::new();
    };
    let root = tree.root();
    if root.count != 0 {
        return single_leaf(&root, prims);
    }
    // Every interior node has two children, so a subtree of s nodes has
    // (s - 1) / 2 interior ones: each subtree's records form a run whose
    // place follows from the sizes alone, and the subtrees are encoded in
    // parallel into their own runs (no pass to number the records first).
    let mut records = bytemuck::zeroed_vec((tree.size() - 1) / 2);
    chunked_subtree(tree, 0, &mut records, prims, 0);
    records
}

/// Each leaf's references moved to start at a multiple of
/// [`PRIMS_PER_TEXEL`] (zeros between leaves), and the records' leaf
/// references moved with them, so that the kernel loads a leaf's references
/// a texel at a time (`shaders/bvh.wgsl`). Returns the new references.
pub fn align_leaves(records: &mut [BvhNode], prims: &[u32]) -> Vec<u32> {
    let mut out = Vec::with_capacity(prims.len() * 2);
    for record in records.iter_mut() {
        for child in [&mut record.left, &mut record.right] {
            if *child == NONE || *child & LEAF == 0 {
                continue;
            }
            let first = (*child & !LEAF) as usize;
            // (`encode` ends every leaf with PRIM_LAST.)
            let last = first
                + prims[first..]
                    .iter()
                    .position(|&p| p & PRIM_LAST != 0)
                    .unwrap_or(0);
            out.resize(out.len().next_multiple_of(PRIMS_PER_TEXEL), 0);
            *child = LEAF | out.len() as u32;
            out.extend_from_slice(&prims[first..=last]);
        }
    }
    out.resize(
        out.len()
            .next_multiple_of(PRIMS_PER_TEXEL)
            .max(PRIMS_PER_TEXEL),
        0,
    );
    out
}

/// Primitive references per 16-byte texel.
pub const PRIMS_PER_TEXEL: usize = 4;

/// The one record of a tree that is a single leaf: the leaf on the left.
fn single_leaf(root: &Node, prims: &mut [u32]) -> Vec<BvhNode> {
    prims[(root.index + root.count - 1) as usize] |= PRIM_LAST;
    vec![record(root, None, LEAF | root.index, NONE)]
}

/// [`subtree`] above the chunks: the boxed top nodes, then each chunk as a
/// flat subtree (its right-child indices count from the chunk's start,
/// which is what [`subtree`] reads; its leaves hold global references).
fn chunked_subtree(tree: &Tree, r: usize, out: &mut [BvhNode], prims: &mut [u32], base: usize) {
    let Tree::Interior { children, .. } = tree else {
        let Tree::Chunk(nodes) = tree else {
            unreachable!()
        };
        let root = &nodes[0];
        if root.count != 0 {
            prims[(root.index + root.count - 1) as usize - base] |= PRIM_LAST;
        } else {
            subtree(nodes, 0, r, out, prims, base);
        }
        return;
    };
    let (left, right) = (&children.0, &children.1);
    let (left_r, right_r) = (r + 1, r + 1 + (left.size() - 1) / 2);
    let (head, rest) = out.split_at_mut(1);
    let (left_out, right_out) = rest.split_at_mut(right_r - left_r);
    let (l, rt) = (left.root(), right.root());
    let reference = |n: &Node, record: usize| match n.count {
        0 => record as u32,
        _ => LEAF | n.index,
    };
    head[0] = record(
        &l,
        Some(&rt),
        reference(&l, left_r),
        reference(&rt, right_r),
    );
    let right_base = right.first_prim() as usize;
    let (lp, rp) = prims.split_at_mut(right_base - base);
    rayon::join(
        || chunked_subtree(left, left_r, left_out, lp, base),
        || chunked_subtree(right, right_r, right_out, rp, right_base),
    );
}

/// Subtrees of more records than this are split between rayon's threads.
const PARALLEL_RECORDS: usize = 1 << 13;

/// Writes the records of the subtree at interior node `i`, whose record is
/// `r` (the first of `out`), and marks the last reference of each of its
/// leaves in `prims`, which starts at reference `base`.
fn subtree(
    nodes: &[Node],
    i: usize,
    r: usize,
    out: &mut [BvhNode],
    prims: &mut [u32],
    base: usize,
) {
    let parallel = out.len() > PARALLEL_RECORDS;
    let (left, right) = (i + 1, nodes[i].index as usize);
    // The left subtree's records follow this one; the right's follow them.
    let (left_r, right_r) = (r + 1, r + 1 + (right - left - 1) / 2);
    let (head, rest) = out.split_at_mut(1);
    let (left_out, right_out) = rest.split_at_mut(right_r - left_r);
    let reference = |c: usize, record: usize| match nodes[c].count {
        0 => record as u32,
        _ => LEAF | nodes[c].index,
    };
    head[0] = self::record(
        &nodes[left],
        Some(&nodes[right]),
        reference(left, left_r),
        reference(right, right_r),
    );
    let child = |c: usize, r: usize, out: &mut [BvhNode], prims: &mut [u32], base: usize| {
        let n = &nodes[c];
        if n.count != 0 {
            prims[(n.index + n.count - 1) as usize - base] |= PRIM_LAST;
        } else {
            subtree(nodes, c, r, out, prims, base);
        }
    };
    if parallel {
        // The right subtree's references start at its leftmost leaf's.
        let mut c = right;
        while nodes[c].count == 0 {
            c += 1;
        }
        let right_base = nodes[c].index as usize;
        let (lp, rp) = prims.split_at_mut(right_base - base);
        rayon::join(
            || child(left, left_r, left_out, lp, base),
            || child(right, right_r, right_out, rp, right_base),
        );
    } else {
        child(left, left_r, left_out, prims, base);
        child(right, right_r, right_out, prims, base);
    }
}

/// Coordinates below this magnitude (2⁹⁰) take the `f32` path of
/// [`record`]: every step of it then stays a normal `f32` (see
/// [`quantise32`]); beyond it the `f64` encoder takes over.
const F32_LIMIT: f32 = (1u128 << 90) as f32;

/// The record of two nodes (the second absent for a single-leaf tree): each
/// decoded box contains [`node_bounds`] of the node's box. Most boxes take
/// the vector `f32` path ([`padded`], [`quantise32`]); the `f64` one gives
/// the same guarantee for any coordinates and serves the huge ones.
fn record(left: &Node, right: Option<&Node>, left_ref: u32, right_ref: u32) -> BvhNode {
    let l = (Vec3A::from(left.min), Vec3A::from(left.max));
    let r = right.map_or(l, |r| (Vec3A::from(r.min), Vec3A::from(r.max)));
    let magnitude = l.0.abs().max(l.1.abs()).max(r.0.abs().max(r.1.abs()));
    if magnitude.cmplt(Vec3A::splat(F32_LIMIT)).all() {
        return quantise32(padded(l), padded(r), left_ref, right_ref);
    }
    let f64_bounds = |n: &Node| node_bounds(n.bounds());
    quantise(f64_bounds(left), right.map(f64_bounds), left_ref, right_ref)
}

/// A box of finite `f32` corners below [`F32_LIMIT`] grown so that it
/// contains [`node_bounds`] of it, in `f32` arithmetic: that pads by 2⁻²⁰
/// of the largest magnitude, exactly (in `f64`); this pads by twice as much
/// (at least 2⁻¹²⁶), which covers the rounding of the `f32` subtraction
/// (at most 2⁻²³ of the largest magnitude).
fn padded((min, max): (Vec3A, Vec3A)) -> (Vec3A, Vec3A) {
    let magnitude = min.abs().max(max.abs()).max_element();
    let pad = (magnitude * (1.0 / (1u32 << 19) as f32)).max(f32::MIN_POSITIVE);
    (min - Vec3A::splat(pad), max + Vec3A::splat(pad))
}

/// [`quantise`] for boxes of magnitude below 2⁹¹ (padded from below
/// [`F32_LIMIT`]), all three axes at once in `f32` lanes: the grid's
/// steps are then normal `f32`s (2^e for e in [-118, 93]), every quotient
/// below is under 2²⁴ in magnitude, so `floor` is exact, and each grid
/// point `origin + q·s` is exact — so checking each grid point against the
/// coordinate it bounds (the quotients may round, or underflow) makes each
/// decoded box contain its input.
fn quantise32(l: (Vec3A, Vec3A), r: (Vec3A, Vec3A), left_ref: u32, right_ref: u32) -> BvhNode {
    let (lo, hi) = (l.0.min(r.0), l.1.max(r.1));
    let e = [0, 1, 2].map(|a| grid_exponent32(lo[a], hi[a]));
    let s = Vec3A::from_array(e.map(|e| f32::from_bits(((e + 127) as u32) << 23)));
    let inv = Vec3A::from_array(e.map(|e| f32::from_bits(((127 - e) as u32) << 23)));
    // The frame starts at the grid point at or below lo (checked: a tiny
    // negative lo over a coarse step underflows to -0, whose floor is 0).
    let origin = (lo * inv).floor() * s;
    let origin = origin - Vec3A::select(origin.cmpgt(lo), s, Vec3A::ZERO);
    let (zero, top) = (Vec3A::ZERO, Vec3A::splat(255.0));
    // Steps from the origin; the subtraction can round (a tiny x far from
    // a huge origin), so each grid point is checked, exactly.
    let below = |x: Vec3A| {
        let q = ((x - origin) * inv).floor().clamp(zero, top);
        q - Vec3A::select((origin + q * s).cmpgt(x), Vec3A::ONE, zero)
    };
    let above = |y: Vec3A| {
        let q = (-((origin - y) * inv).floor()).clamp(zero, top);
        q + Vec3A::select((origin + q * s).cmplt(y), Vec3A::ONE, zero)
    };
    let steps = [below(l.0), above(l.1), below(r.0), above(r.1)].map(|q| q.as_uvec3());
    let byte = |k: usize| steps[k / 3][k % 3];
    let word = |w: usize| (0..4).fold(0, |acc, b| acc | byte(4 * w + b) << (8 * b));
    // origin / s is the integer k, exactly.
    let k = (origin * inv).to_array();
    BvhNode {
        origin: [0, 1, 2].map(|a| pack_origin(k[a] as i32, e[a])),
        left: left_ref,
        quantised: [word(0), word(1), word(2)],
        right: right_ref,
    }
}

/// A frame's lower corner `k·2^e` on one axis as the record stores it: the
/// signed `k` in the upper 24 bits, the biased exponent in the low 8. The
/// grid keeps |k| ≤ 2²² + 1 (see [`grid_exponent`]).
fn pack_origin(k: i32, e: i32) -> u32 {
    debug_assert!(k.unsigned_abs() < 1 << 23 && (MIN_EXP..=MAX_EXP).contains(&e));
    ((k << 8) as u32) | (e + 127) as u32
}

/// [`grid_exponent`] in `f32` for |lo|, |hi| < 2⁹¹: the span and its
/// 253rd part round by at most 2⁻²³ together, well inside the margin of 253
/// steps for 254; a 253rd part below the normal range means the finest grid.
fn grid_exponent32(lo: f32, hi: f32) -> i32 {
    let part = (hi - lo) / 253.0;
    let fine = if part >= f32::MIN_POSITIVE {
        let bits = part.to_bits();
        ((bits >> 23) as i32 - 127) + i32::from(bits & ((1 << 23) - 1) != 0)
    } else {
        MIN_EXP
    };
    // |lo|, |hi| < 2^(m + 1) ≤ 2^22 · 2^e, as in `grid_exponent` (a
    // subnormal or zero magnitude gives the finest grid).
    let coarse = ((lo.abs().max(hi.abs()).to_bits() >> 23) as i32 - 127) - 21;
    fine.max(coarse).clamp(MIN_EXP, MAX_EXP)
}

/// The record of two children (the second absent for a single-leaf tree).
fn quantise(left: Aabb, right: Option<Aabb>, left_ref: u32, right_ref: u32) -> BvhNode {
    let r = right.unwrap_or(left);
    let mut node = BvhNode {
        left: left_ref,
        right: right_ref,
        ..BvhNode::default()
    };
    let mut bytes = [0u8; 12];
    for axis in 0..3 {
        let lo = left.min[axis].min(r.min[axis]);
        let hi = left.max[axis].max(r.max[axis]);
        let e = grid_exponent(lo, hi);
        let s = f64::from_bits(((e + 1023) as u64) << 52);
        let inv = f64::from_bits(((1023 - e) as u64) << 52);
        // The frame starts at the grid point at or below lo.
        let k = floor(lo * inv);
        let origin = k * s;
        node.origin[axis] = pack_origin(k as i32, e);
        // Grid point q (exact in f64 as in f32).
        let point = |q: f64| origin + q * s;
        for (k, b) in [left, r].iter().enumerate() {
            // Steps from the origin; the subtraction can round (a tiny x
            // far from a huge origin), so the grid point is checked, exactly.
            let (x, y) = (b.min[axis], b.max[axis]);
            let mut q = floor((x - origin) * inv).clamp(0.0, 255.0);
            if point(q) > x {
                q -= 1.0;
            }
            bytes[6 * k + axis] = q as u8;
            let mut q = (-floor((origin - y) * inv)).clamp(0.0, 255.0);
            if point(q) < y {
                q += 1.0;
            }
            bytes[6 * k + 3 + axis] = q as u8;
        }
    }
    for (w, chunk) in node.quantised.iter_mut().zip(bytes.chunks(4)) {
        *w = u32::from_le_bytes(chunk.try_into().expect("chunks of 4"));
    }
    node
}

/// The exponent `e` of the grid `k·2^e` a record's axis is quantised on:
/// fine enough that 253 steps span `[lo, hi]` (the origin may lie up to one
/// step below `lo`), and coarse enough that every point of the grid within
/// reach (|k| < 2^24) is an `f32`, so the kernel's `origin + q·2^e` is
/// exact: no rounding, no subnormals (2^e is normal), the same on every
/// device, with or without fused multiply-add.
fn grid_exponent(lo: f64, hi: f64) -> i32 {
    // 253 rather than 254 steps: margin for the rounding of `hi - lo`.
    let fine = if hi > lo {
        ceil_log2((hi - lo) / 253.0)
    } else {
        MIN_EXP
    };
    // |lo|, |hi| < 2^(m + 1) ≤ 2^22 · 2^e: with the origin one step out and
    // 255 steps on, every grid point reached stays below 2^24 · 2^e.
    let magnitude = lo.abs().max(hi.abs());
    let coarse = if magnitude > 0.0 {
        ((magnitude.to_bits() >> 52) as i32 - 1023) - 21
    } else {
        MIN_EXP
    };
    fine.max(coarse).clamp(MIN_EXP, MAX_EXP)
}

/// ⌈log2 x⌉ for a positive normal `x`, from its bits.
fn ceil_log2(x: f64) -> i32 {
    let bits = x.to_bits();
    let e = ((bits >> 52) & 0x7ff) as i32 - 1023;
    e + i32::from(bits & ((1 << 52) - 1) != 0)
}

/// ⌊x⌋ for |x| < 2^62 (the target may lack a rounding instruction, which
/// makes `f64::floor` a library call).
fn floor(x: f64) -> f64 {
    let t = x as i64 as f64;
    if t > x {
        t - 1.0
    } else {
        t
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::Bvh;
    use glam::DVec3;
    use proptest::prelude::*;

    /// The boxes (lower, upper corner) of a record's two children, decoded
    /// with exactly the arithmetic of `shaders/bvh.wgsl`.
    fn decode(node: &BvhNode) -> [([f32; 3], [f32; 3]); 2] {
        let q = node.quantised;
        let step = |k: usize| ((q[k / 4] >> (8 * (k % 4))) & 0xff) as f32;
        let mut out = [([0.0; 3], [0.0; 3]); 2];
        for axis in 0..3 {
            let s = f32::from_bits((node.origin[axis] & 0xff) << 23);
            let o = origins(node)[axis];
            for (k, b) in out.iter_mut().enumerate() {
                b.0[axis] = o + step(6 * k + axis) * s;
                b.1[axis] = o + step(6 * k + 3 + axis) * s;
            }
        }
        out
    }

    /// A record's frame origin, decoded as `shaders/bvh.wgsl` does.
    fn origins(node: &BvhNode) -> [f32; 3] {
        node.origin
            .map(|w| (w as i32 >> 8) as f32 * f32::from_bits((w & 0xff) << 23))
    }

    fn contains(outer: ([f32; 3], [f32; 3]), inner: ([f32; 3], [f32; 3])) -> bool {
        (0..3).all(|a| outer.0[a] <= inner.0[a] && outer.1[a] >= inner.1[a])
    }

    fn aabb(b: ([f32; 3], [f32; 3])) -> Aabb {
        Aabb {
            min: DVec3::from_array(b.0.map(f64::from)),
            max: DVec3::from_array(b.1.map(f64::from)),
        }
    }

    fn flushed(b: ([f32; 3], [f32; 3])) -> ([f32; 3], [f32; 3]) {
        let f = |x: f32| if x.is_subnormal() { 0.0 } else { x };
        (b.0.map(f), b.1.map(f))
    }

    fn sorted(a: [f32; 3], b: [f32; 3]) -> ([f32; 3], [f32; 3]) {
        let lo = [a[0].min(b[0]), a[1].min(b[1]), a[2].min(b[2])];
        let hi = [a[0].max(b[0]), a[1].max(b[1]), a[2].max(b[2])];
        (lo, hi)
    }

    /// Any float a box coordinate may be, biased towards the hard ones:
    /// subnormals, zeros of both signs, huge and tiny magnitudes.
    fn coordinate() -> impl Strategy<Value = f32> {
        prop_oneof![
            -1e3f32..1e3,
            (-1e-36f32..1e-36),
            Just(0.0f32),
            Just(-0.0f32),
            (-100i32..100).prop_map(|k| k as f32 * f32::MIN_POSITIVE / 64.0),
            (any::<u32>()).prop_map(|b| {
                let x = f32::from_bits(b);
                if x.is_finite() && x.abs() < 1e30 {
                    x
                } else {
                    1.0
                }
            }),
        ]
    }

    fn boxed() -> impl Strategy<Value = ([f32; 3], [f32; 3])> {
        (
            [coordinate(), coordinate(), coordinate()],
            [coordinate(), coordinate(), coordinate()],
        )
            .prop_map(|(a, b)| sorted(a, b))
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(4096))]
        /// Both decoded children contain their exact boxes, whether or not
        /// the device flushes subnormals.
        #[test]
        fn decoded_boxes_contain_the_exact_ones(l in boxed(), r in boxed()) {
            contains_both(&quantise(aabb(l), Some(aabb(r)), 0, 0), l, r)?;
        }

        /// The same for the `f32` quantiser, on boxes within its range.
        #[test]
        fn f32_decoded_boxes_contain_the_exact_ones(l in boxed(), r in boxed()) {
            // Coordinates beyond the f32 path's range scaled into it.
            let within = |b: ([f32; 3], [f32; 3])| {
                let f = |x: f32| if x.abs() < 2.0 * F32_LIMIT { x } else { x / (1u64 << 40) as f32 };
                sorted(b.0.map(f), b.1.map(f))
            };
            let (l, r) = (within(l), within(r));
            contains_both(&quantise32(lanes(l), lanes(r), 0, 0), l, r)?;
        }

        /// Each record's decoded boxes contain `node_bounds` of its nodes'
        /// boxes (checked in `f64`), whichever path encoded it.
        #[test]
        fn records_contain_the_padded_node_boxes(l in boxed(), r in boxed()) {
            let node = |b: ([f32; 3], [f32; 3])| Node { min: b.0, max: b.1, index: 0, count: 1 };
            let [dl, dr] = decode(&record(&node(l), Some(&node(r)), 0, 0));
            for (d, b) in [(dl, l), (dr, r)] {
                let want = node_bounds(aabb(b));
                prop_assert!(aabb(d).contains(&want), "{d:?} !⊇ {want:?}");
                prop_assert!(aabb(flushed(d)).contains(&want));
            }
        }
    }

    /// Both decoded children of `node` contain their boxes `l` and `r`,
    /// flushed to zero or not, and the frame's origin is a normal number.
    fn contains_both(
        node: &BvhNode,
        l: ([f32; 3], [f32; 3]),
        r: ([f32; 3], [f32; 3]),
    ) -> Result<(), TestCaseError> {
        let [dl, dr] = decode(node);
        prop_assert!(contains(dl, l), "{dl:?} !⊇ {l:?}");
        prop_assert!(contains(dr, r), "{dr:?} !⊇ {r:?}");
        prop_assert!(contains(flushed(dl), l));
        prop_assert!(contains(flushed(dr), r));
        prop_assert!(origins(node).iter().all(|o| !o.is_subnormal()));
        Ok(())
    }

    fn lanes(b: ([f32; 3], [f32; 3])) -> (Vec3A, Vec3A) {
        (Vec3A::from(b.0), Vec3A::from(b.1))
    }

    #[test]
    fn quantisation_is_tight_for_ordinary_boxes() {
        // Away from huge coordinates a step is below 2/254 of the parent's
        // extent (the smallest power of two above 1/254 of it), and a
        // decoded side is at most one step out, on both paths.
        let boxes = crate::bvh::random_boxes(2000, 12345);
        for pair in boxes.chunks(2) {
            let (l, r) = (pair[0].outward_f32(), pair[1].outward_f32());
            let [dl, dr] = decode(&quantise(aabb(l), Some(aabb(r)), 0, 0));
            let [fl, fr] = decode(&quantise32(lanes(l), lanes(r), 0, 0));
            for (d, e) in [(dl, l), (dr, r), (fl, l), (fr, r)] {
                for a in 0..3 {
                    let extent = l.1[a].max(r.1[a]) - l.0[a].min(r.0[a]);
                    let step = extent * 2.0 / 254.0;
                    assert!(e.0[a] - d.0[a] <= step, "{d:?} vs {e:?}");
                    assert!(d.1[a] - e.1[a] <= step, "{d:?} vs {e:?}");
                }
            }
        }
    }

    /// Walks the records from the root's alongside the flat tree: every
    /// primitive sits in exactly one leaf, every leaf's references end with
    /// one PRIM_LAST, and every decoded box contains the node's exact box.
    /// For a tree that is one chunk, and one with boxed nodes above its
    /// chunks.
    #[test]
    fn records_reach_every_primitive_once_inside_their_boxes() {
        for n in [3000, 60_000] {
            let boxes = crate::bvh::random_boxes(n, 12345);
            let built = Bvh::build_f32_chunked(n, |i| boxes[i].outward_f32());
            let boxed_top = matches!(built.tree, Some(Tree::Interior { .. }));
            assert_eq!(boxed_top, n > 4096, "{n}");
            let mut prims = built.prims.clone();
            let records = encode(&built, &mut prims);
            let bvh = built.flatten();
            walk(&bvh, &boxes, &records, &prims);
        }
    }

    fn walk(bvh: &Bvh, boxes: &[Aabb], records: &[BvhNode], prims: &[u32]) {
        let f32_box = |i: usize| (bvh.nodes[i].min, bvh.nodes[i].max);
        let interior = bvh.nodes.iter().filter(|n| n.count == 0).count();
        assert_eq!(records.len(), interior);
        let mut seen = vec![0u32; boxes.len()];
        // (host node, its reference, its decoded box); the root's own box is
        // never tested.
        let [l, r] = decode(&records[0]);
        let mut stack = vec![
            (1usize, records[0].left, l),
            (bvh.nodes[0].index as usize, records[0].right, r),
        ];
        while let Some((i, r, b)) = stack.pop() {
            let n = &bvh.nodes[i];
            assert!(contains(b, f32_box(i)), "node {i}: {b:?}");
            if n.count > 0 {
                assert_eq!(r, LEAF | n.index);
                for k in n.index..n.index + n.count {
                    let p = prims[k as usize];
                    assert_eq!(p & PRIM_LAST != 0, k + 1 == n.index + n.count);
                    let index = (p & !PRIM_LAST) as usize;
                    seen[index] += 1;
                    assert!(contains(b, boxes[index].outward_f32()));
                }
            } else {
                let rec = &records[r as usize];
                let [dl, dr] = decode(rec);
                stack.push((i + 1, rec.left, dl));
                stack.push((n.index as usize, rec.right, dr));
            }
        }
        assert!(seen.iter().all(|&s| s == 1));
        let lasts = prims.iter().filter(|&&p| p & PRIM_LAST != 0).count();
        assert_eq!(lasts, bvh.nodes.iter().filter(|n| n.count > 0).count());
    }

    #[test]
    fn a_single_leaf_tree_gets_one_record() {
        let boxes = crate::bvh::random_boxes(2, 12345);
        let built = Bvh::build_f32_chunked(2, |i| boxes[i].outward_f32());
        assert_eq!(built.tree.as_ref().map(|t| t.size()), Some(1));
        let mut prims = built.prims.clone();
        let records = encode(&built, &mut prims);
        assert_eq!(records.len(), 1);
        assert_eq!((records[0].left, records[0].right), (LEAF, NONE));
        assert_eq!(prims[1] & PRIM_LAST, PRIM_LAST);
        assert_eq!(prims[0] & PRIM_LAST, 0);
    }

    /// The references of a leaf, from its first up to its PRIM_LAST.
    fn leaf(prims: &[u32], reference: u32) -> &[u32] {
        let first = (reference & !LEAF) as usize;
        let n = prims[first..]
            .iter()
            .position(|&p| p & PRIM_LAST != 0)
            .unwrap();
        &prims[first..=first + n]
    }

    /// Aligned, every leaf starts at a multiple of PRIMS_PER_TEXEL and holds
    /// the same references in the same order; interior references and the
    /// boxes are unchanged, and the references fill whole texels.
    #[test]
    fn aligned_leaves_start_on_texels_and_keep_their_references() {
        for n in [2, 3000, 60_000] {
            let boxes = crate::bvh::random_boxes(n, 777);
            let built = Bvh::build_f32_chunked(n, |i| boxes[i].outward_f32());
            let mut prims = built.prims.clone();
            let records = encode(&built, &mut prims);
            let mut aligned = records.clone();
            let out = align_leaves(&mut aligned, &prims);
            assert_eq!(out.len() % PRIMS_PER_TEXEL, 0);
            let mut leaves = 0;
            for (old, new) in records.iter().zip(&aligned) {
                assert_eq!((old.origin, old.quantised), (new.origin, new.quantised));
                for (o, r) in [(old.left, new.left), (old.right, new.right)] {
                    if o == NONE || o & LEAF == 0 {
                        assert_eq!(o, r);
                        continue;
                    }
                    leaves += 1;
                    assert_eq!((r & !LEAF) as usize % PRIMS_PER_TEXEL, 0);
                    assert_eq!(leaf(&prims, o), leaf(&out, r));
                }
            }
            let lasts = prims.iter().filter(|&&p| p & PRIM_LAST != 0).count();
            assert_eq!(leaves, lasts, "{n}");
        }
    }
}
