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
//! decoding them is cheap vector arithmetic. The bunny frame took 0.94× the
//! CPU time this way (docs/bench.md §6), and the nodes take 48 bytes per
//! interior node instead of 32 per node, 0.75× the memory. The kernel now
//! reads each record as three texels of a read-only storage image
//! (`vulkan::TexelImage`, straight-line code on lavapipe: docs/bench.md §6).
//!
//! Conservative by construction: each axis of a record is quantised on a
//! grid `k·2^e` coarse enough that every grid point within reach is an
//! `f32`, so the kernel's `origin + f32(q) * 2^e` is exact — no rounding, no
//! subnormals, the same on every device, fused or not — and the encoder
//! picks the grid points below and above each child's corners (checked
//! exactly). The decoded box therefore always contains the exact `f32` box,
//! and the slab test's widening (Ize 2013) applies to it unchanged.

use rayon::prelude::*;

use super::layout::BvhNode;
use crate::bvh::{Aabb, Bvh};

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

/// Encodes a built hierarchy: one record per interior node, the root's
/// first, each child's decoded box containing `bounds(child)` (the node's
/// box with whatever padding the caller wants). The root's own box is never tested (its children's boxes lie
/// inside it, so that test would only cost a step). A tree that is a single
/// leaf gets one record with that leaf on the left and [`NONE`] on the
/// right. `prims` are the tree's primitive references; the last of each
/// leaf gets [`PRIM_LAST`].
pub fn encode(bvh: &Bvh, bounds: impl Fn(usize) -> Aabb + Sync, prims: &mut [u32]) -> Vec<BvhNode> {
    let nodes = &bvh.nodes;
    if nodes.is_empty() {
        return Vec::new();
    }
    // The interior nodes in depth-first order; record r is interior[r].
    let mut interior = Vec::with_capacity(nodes.len() / 2 + 1);
    for (i, n) in nodes.iter().enumerate() {
        if n.count == 0 {
            interior.push(i);
        } else {
            prims[(n.index + n.count - 1) as usize] |= PRIM_LAST;
        }
    }
    if interior.is_empty() {
        return vec![quantise(bounds(0), None, LEAF | nodes[0].index, NONE)];
    }
    // A child's reference from its parent's record r (node i): an interior
    // left child is the next record; before an interior right child come
    // the left subtree's interior nodes, (size - 1) / 2 of its
    // right - i - 1 nodes (every interior node has two children).
    let child = |r: usize, i: usize, c: usize| {
        let n = &nodes[c];
        if n.count != 0 {
            LEAF | n.index
        } else if c == i + 1 {
            (r + 1) as u32
        } else {
            (r + 1 + (c - i - 2) / 2) as u32
        }
    };
    interior
        .par_iter()
        .enumerate()
        .map(|(r, &i)| {
            let right = nodes[i].index as usize;
            quantise(
                bounds(i + 1),
                Some(bounds(right)),
                child(r, i, i + 1),
                child(r, i, right),
            )
        })
        .collect()
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
        let origin = floor(lo * inv) * s;
        node.origin[axis] = origin as f32;
        node.exponents |= ((e + 127) as u32) << (8 * axis);
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
    use crate::bvh::Aabb;
    use glam::DVec3;
    use proptest::prelude::*;

    /// The boxes (lower, upper corner) of a record's two children, decoded
    /// with exactly the arithmetic of `shaders/bvh.wgsl`.
    fn decode(node: &BvhNode) -> [([f32; 3], [f32; 3]); 2] {
        let q = node.quantised;
        let step = |k: usize| ((q[k / 4] >> (8 * (k % 4))) & 0xff) as f32;
        let mut out = [([0.0; 3], [0.0; 3]); 2];
        for axis in 0..3 {
            let s = f32::from_bits(((node.exponents >> (8 * axis)) & 0xff) << 23);
            let o = node.origin[axis];
            for (k, b) in out.iter_mut().enumerate() {
                b.0[axis] = o + step(6 * k + axis) * s;
                b.1[axis] = o + step(6 * k + 3 + axis) * s;
            }
        }
        out
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
            let node = quantise(aabb(l), Some(aabb(r)), 0, 0);
            let [dl, dr] = decode(&node);
            prop_assert!(contains(dl, l), "{dl:?} !⊇ {l:?}");
            prop_assert!(contains(dr, r), "{dr:?} !⊇ {r:?}");
            prop_assert!(contains(flushed(dl), l));
            prop_assert!(contains(flushed(dr), r));
            prop_assert!(node.origin.iter().all(|o| !o.is_subnormal()));
        }
    }

    #[test]
    fn quantisation_is_tight_for_ordinary_boxes() {
        // Away from huge coordinates a step is below 2/254 of the parent's
        // extent (the smallest power of two above 1/254 of it), and a
        // decoded side is at most one step out.
        let boxes = crate::bvh::random_boxes(2000, 12345);
        for pair in boxes.chunks(2) {
            let (l, r) = (pair[0].outward_f32(), pair[1].outward_f32());
            let [dl, dr] = decode(&quantise(aabb(l), Some(aabb(r)), 0, 0));
            for (d, e) in [(dl, l), (dr, r)] {
                for a in 0..3 {
                    let extent = l.1[a].max(r.1[a]) - l.0[a].min(r.0[a]);
                    let step = extent * 2.0 / 254.0;
                    assert!(e.0[a] - d.0[a] <= step, "{d:?} vs {e:?}");
                    assert!(d.1[a] - e.1[a] <= step, "{d:?} vs {e:?}");
                }
            }
        }
    }

    /// Walks the records from the root's: every primitive sits in
    /// exactly one leaf, every leaf's references end with one PRIM_LAST, and
    /// every decoded box contains the node's exact box.
    #[test]
    fn records_reach_every_primitive_once_inside_their_boxes() {
        let boxes = crate::bvh::random_boxes(5000, 12345);
        let bvh = Bvh::build(&boxes);
        let f32_box = |i: usize| (bvh.nodes[i].min, bvh.nodes[i].max);
        let mut prims = bvh.prims.clone();
        let records = encode(&bvh, |i| bvh.nodes[i].bounds(), &mut prims);
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
        let bvh = Bvh::build(&boxes);
        assert_eq!(bvh.nodes.len(), 1);
        let mut prims = bvh.prims.clone();
        let records = encode(&bvh, |i| bvh.nodes[i].bounds(), &mut prims);
        assert_eq!(records.len(), 1);
        assert_eq!((records[0].left, records[0].right), (LEAF, NONE));
        assert_eq!(prims[1] & PRIM_LAST, PRIM_LAST);
        assert_eq!(prims[0] & PRIM_LAST, 0);
    }
}
