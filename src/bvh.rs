//! Bounding volume hierarchy over the scene's finite primitives (triangles
//! and spheres; infinite planes stay outside), built on the host and
//! traversed by `shaders/bvh.wgsl`.
//!
//! Construction is top-down binned SAH after Wald, "On fast Construction of
//! SAH-based Bounding Volume Hierarchies" (IEEE RT 2007): primitive centroids
//! are sorted into [`BINS`] equal bins along each axis, and the split plane
//! between bins with the lowest surface area heuristic cost
//! `C_trav + (A_L·N_L + A_R·N_R) / A · C_isect` wins, compared with the cost
//! `N · C_isect` of a leaf. We use C_trav = 1 and C_isect = 1 (a box test and
//! a primitive test cost about the same in our kernel), 16 bins (Wald found
//! 16 to 32 bins within a few percent of a full sweep) and at most
//! [`MAX_LEAF`] primitives per leaf; nodes with fewer than 16 primitives use
//! that many bins. A plane through the centroids cannot separate a huge
//! primitive from small ones whose centroids lie beside its own (a ground
//! quad under a mesh that stands on it): the binned split would peel off a
//! thin slice of the mesh with the quad, level after level, and every ray
//! that meets the quad would descend all those levels. So a node whose best
//! plane leaves a child almost as large as the node (`LARGE_CHILD`) also
//! prices putting its large primitives on a side of their own
//! (`size_split`), by the same SAH cost. Nodes of at most [`SMALL_NODE`]
//! primitives split at the median centroid of their widest axis: near the
//! leaves SAH gains little and its fixed cost per node dominates the
//! build. With 8 the bunny's
//! frames match a pure SAH tree within the timing noise (12 cost a few
//! per cent). Subtrees are built in parallel with rayon, and so is the
//! binning of large nodes.
//!
//! For speed the builder works in `f32` SIMD lanes on 32-byte primitive
//! records that it permutes itself (each pass over a node streams through
//! memory), takes each child's bounds from the partition pass instead of a
//! pass of its own, and writes the subtrees below the parallel levels as
//! flat depth-first chunks of finished nodes (no allocation per node).
//! Boxes given in `f64`
//! are rounded outwards first, so every box still contains its primitive,
//! and the finished nodes keep their `f32` boxes (32 bytes a node).
//! Bin indices come from one SSE2 truncation for all three axes, and the
//! partition tests the split plane with one compare. Nodes below the
//! parallel levels (they fit in the cache) partition through a scratch
//! buffer, each primitive going to its side by a conditional move rather
//! than Hoare's branches, which mispredict on unordered nodes.
//!
//! Nodes of more than `SAMPLE_ABOVE` (2k) primitives, all but the last
//! few levels, pick their split from the bins of a stratified sample of at
//! least `SAMPLES` (512) primitives, then partition all of them while
//! gathering the children's exact bounds: one pass over the node instead
//! of two. A sample misses the rare huge primitive (a ground quad beside a
//! dense mesh) that decides the best split, so when the sample's bounds
//! cover less than `SAMPLE_COVER` (95 %) of the node's area the node bins
//! everything. The sample costs the trees a fraction of a per cent of SAH
//! cost ([`Bvh::sah_cost`]; `cargo run --release -p penumbra-tools --bin build_time`
//! prints it) and saves a pass over every large node. Sampling, chunking
//! and every reduction are fixed by the input alone, so the tree does not
//! depend on rayon's scheduling. docs/history.md has the measurements
//! behind these choices.
//!
//! The flattened layout is depth-first: a node's left child follows it
//! directly, so an interior node stores only its right child's index.
//! Subtrees know their sizes, so they are flattened in parallel, each into
//! its own slice of the array. The GPU's encoder needs no flat copy: it
//! reads the builder's tree as it is ([`Chunked`]), which saves the copy's
//! 32 bytes a node of memory and the time to make it.

use glam::{DVec3, UVec3, Vec3A, Vec4};
use rayon::prelude::*;

/// Primitive references with this bit set are spheres, else triangles.
pub const PRIM_SPHERE: u32 = 1 << 31;

/// Number of SAH bins per axis.
pub const BINS: usize = 16;
/// Largest leaf the builder makes (unless the primitives cannot be split).
pub const MAX_LEAF: usize = 4;
/// Deepest tree the builder makes; the shader's traversal stack holds this
/// many entries, so it can never overflow.
pub const MAX_DEPTH: usize = 64;
/// Nodes of at most this many primitives split at the median instead of
/// by SAH.
pub const SMALL_NODE: usize = 8;
/// Below this many primitives a subtree is built on the current thread.
const PARALLEL_THRESHOLD: usize = 4096;
/// Nodes of more than this many primitives choose their split from a
/// sample of them (see [`split`]) ...
const SAMPLE_ABOVE: usize = 1 << 11;
/// ... of at least this many.
const SAMPLES: usize = 1 << 9;
/// Least share of a node's area its sample must cover to be trusted.
const SAMPLE_COVER: f32 = 0.95;
const C_TRAV: f64 = 1.0;
const C_ISECT: f64 = 1.0;

/// Axis-aligned box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Lower corner.
    pub min: DVec3,
    /// Upper corner.
    pub max: DVec3,
}

impl Aabb {
    /// The empty box (the identity of [`Aabb::union`]).
    pub const EMPTY: Aabb = Aabb {
        min: DVec3::INFINITY,
        max: DVec3::NEG_INFINITY,
    };

    /// Smallest box holding the points.
    pub fn of_points(points: &[DVec3]) -> Aabb {
        points.iter().fold(Aabb::EMPTY, |b, p| b.grow(*p))
    }

    /// The box grown to hold `p`.
    pub fn grow(self, p: DVec3) -> Aabb {
        Aabb {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    /// Smallest box holding both.
    pub fn union(self, o: Aabb) -> Aabb {
        Aabb {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    /// Surface area (0 for the empty box).
    pub fn area(&self) -> f64 {
        let d = self.max - self.min;
        if d.min_element() < 0.0 {
            return 0.0;
        }
        2.0 * (d.x * d.y + d.y * d.z + d.z * d.x)
    }

    /// Centre point.
    pub fn centre(&self) -> DVec3 {
        (self.min + self.max) * 0.5
    }

    /// Whether `o` lies inside (or on) this box.
    pub fn contains(&self, o: &Aabb) -> bool {
        self.min.cmple(o.min).all() && self.max.cmpge(o.max).all()
    }

    /// The smallest `f32` box (lower and upper corner) that contains this
    /// one: each coordinate rounded outwards.
    pub fn outward_f32(&self) -> ([f32; 3], [f32; 3]) {
        let down = |x: f64| {
            let f = x as f32;
            if f as f64 > x {
                f.next_down()
            } else {
                f
            }
        };
        let up = |x: f64| {
            let f = x as f32;
            if (f as f64) < x {
                f.next_up()
            } else {
                f
            }
        };
        (self.min.to_array().map(down), self.max.to_array().map(up))
    }
}

/// One node of the flattened tree: 32 bytes, its box in `f32` (the
/// builder's boxes, which contain the inputs' boxes rounded outwards).
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Zeroable)]
pub struct Node {
    /// Lower corner of the bounds of everything below.
    pub min: [f32; 3],
    /// Leaf: index of the first primitive reference; interior: index of the
    /// right child (the left child is the next node).
    pub index: u32,
    /// Upper corner.
    pub max: [f32; 3],
    /// Leaf: number of primitives (≥ 1); interior: 0.
    pub count: u32,
}

impl Node {
    /// A node over the builder's box `b`.
    fn new(b: &Box32, index: u32, count: u32) -> Node {
        Node {
            min: b.min.to_array(),
            max: b.max.to_array(),
            index,
            count,
        }
    }

    /// The bounds, exactly, in `f64`.
    pub fn bounds(&self) -> Aabb {
        Aabb {
            min: DVec3::from_array(self.min.map(f64::from)),
            max: DVec3::from_array(self.max.map(f64::from)),
        }
    }
}

/// A built hierarchy.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Bvh {
    /// Depth-first nodes; node 0 is the root (absent when there are no
    /// primitives).
    pub nodes: Vec<Node>,
    /// Primitive indices (into the slice given to [`Bvh::build`]) in leaf
    /// order: leaf `n` covers `prims[n.index..n.index + n.count]`.
    pub prims: Vec<u32>,
    /// Deepest leaf (root = 0).
    pub depth: usize,
}

/// The tree while it is built: subtrees built on one thread are flat
/// depth-first chunks (no allocation per node); only the few nodes above
/// them, split while the work is still handed out to rayon, are boxed.
/// [`Chunked::flatten`] makes it a [`Bvh`]; the GPU encoder
/// (`render::quantised_bvh`) reads it as it is.
pub(crate) enum Tree {
    /// Nodes as in [`Bvh::nodes`], except that an interior node's right
    /// child is counted from the start of its chunk.
    Chunk(Vec<Node>),
    Interior {
        bounds: Box32,
        children: Box<(Tree, Tree)>,
        size: usize,
    },
}

impl Tree {
    /// Nodes in the subtree.
    pub(crate) fn size(&self) -> usize {
        match self {
            Tree::Chunk(nodes) => nodes.len(),
            Tree::Interior { size, .. } => *size,
        }
    }

    /// The subtree's root: its box, and for a leaf its primitives (an
    /// interior root's `index` is meaningless here).
    pub(crate) fn root(&self) -> Node {
        match self {
            Tree::Chunk(nodes) => nodes[0],
            Tree::Interior { bounds, .. } => Node::new(bounds, 0, 0),
        }
    }

    /// The subtree's first primitive reference (its leftmost leaf's).
    pub(crate) fn first_prim(&self) -> u32 {
        match self {
            // Depth-first: the first leaf of a chunk is its leftmost.
            Tree::Chunk(nodes) => {
                let leaf = nodes.iter().find(|n| n.count != 0);
                leaf.expect("a chunk ends in leaves").index
            }
            Tree::Interior { children, .. } => children.0.first_prim(),
        }
    }
}

/// A hierarchy as the builder leaves it, before [`Chunked::flatten`]: the
/// subtrees built on one thread as flat chunks under a few boxed top
/// nodes. The GPU encoder reads it as it is and needs no flat copy.
pub struct Chunked {
    /// The tree; `None` when there are no primitives.
    pub(crate) tree: Option<Tree>,
    /// As [`Bvh::prims`].
    pub prims: Vec<u32>,
    /// As [`Bvh::depth`].
    pub depth: usize,
}

impl Chunked {
    /// The flat depth-first [`Bvh`] (subtrees copied in parallel).
    pub fn flatten(self) -> Bvh {
        let Some(tree) = self.tree else {
            return Bvh::default();
        };
        // Zeroed pages straight from the allocator, filled in parallel.
        let mut nodes = bytemuck::zeroed_vec(tree.size());
        flatten(&tree, &mut nodes, 0);
        Bvh {
            nodes,
            prims: self.prims,
            depth: self.depth,
        }
    }

    /// [`Bvh::prim_refs`] of the flattened tree.
    pub fn prim_refs(&self, n_triangles: usize) -> Vec<u32> {
        prim_refs(&self.prims, n_triangles)
    }
}

impl Bvh {
    /// Builds the hierarchy over primitives given by their bounds.
    ///
    /// # Panics
    ///
    /// With more than [`MAX_PRIMS`] primitives (far beyond any device's
    /// buffer limits).
    pub fn build(bounds: &[Aabb]) -> Bvh {
        Self::build_with(bounds.len(), |i| Box32::outward(&bounds[i]))
    }

    /// Builds the hierarchy over `n` primitives whose `f32` bounds (lower
    /// and upper corner) `bounds(i)` gives: for primitives already in
    /// `f32`, such as the GPU's triangles, whose boxes are then exact.
    ///
    /// # Panics
    ///
    /// With more than [`MAX_PRIMS`] primitives.
    pub fn build_f32(n: usize, bounds: impl Fn(usize) -> ([f32; 3], [f32; 3]) + Sync) -> Bvh {
        Self::build_f32_chunked(n, bounds).flatten()
    }

    /// [`Bvh::build_f32`] without the final flattening.
    ///
    /// # Panics
    ///
    /// With more than [`MAX_PRIMS`] primitives.
    pub fn build_f32_chunked(
        n: usize,
        bounds: impl Fn(usize) -> ([f32; 3], [f32; 3]) + Sync,
    ) -> Chunked {
        Self::build_sampled(
            n,
            |i| {
                let (min, max) = bounds(i);
                Box32::new(min, max)
            },
            SAMPLE_ABOVE,
        )
    }

    fn build_with(n: usize, bounds: impl Fn(usize) -> Box32 + Sync) -> Bvh {
        Self::build_sampled(n, bounds, SAMPLE_ABOVE).flatten()
    }

    /// The hierarchy with nodes above `sample_above` primitives binning a
    /// sample (tests compare with `usize::MAX`: no sampling).
    fn build_sampled(
        n: usize,
        bounds: impl Fn(usize) -> Box32 + Sync,
        sample_above: usize,
    ) -> Chunked {
        if n == 0 {
            return Chunked {
                tree: None,
                prims: Vec::new(),
                depth: 0,
            };
        }
        assert!(
            n <= MAX_PRIMS,
            "the BVH builder takes at most 2^30 primitives"
        );
        // The builder permutes these records themselves (not indices into
        // the inputs), so every pass over a node streams through memory.
        let mut prims: Vec<Prim> = (0..n)
            .into_par_iter()
            .map(|i| Prim::new(bounds(i), i as u32))
            .collect();
        let (b, cb) = bounds_of(&prims);
        let (tree, depth) = build_subtree(&mut prims, 0, 0, b, cb, sample_above);
        Chunked {
            tree: Some(tree),
            prims: prims.par_iter().map(Prim::index).collect(),
            depth,
        }
    }

    /// The primitive references of a tree built over `n_triangles` triangle
    /// boxes followed by sphere boxes: triangle `i` stays `i`, sphere `j`
    /// becomes `j | PRIM_SPHERE` (the encoding `shaders/bvh.wgsl` reads).
    pub fn prim_refs(&self, n_triangles: usize) -> Vec<u32> {
        prim_refs(&self.prims, n_triangles)
    }

    /// The tree's SAH cost (Goldsmith and Salmon 1987; MacDonald and Booth
    /// 1990): the expected cost of tracing a ray that hits the root box,
    /// `Σ_interior A(n)/A(root)·C_trav + Σ_leaves A(n)/A(root)·count·C_isect`
    /// with the builder's C_trav = C_isect = 1, where a node's area ratio is
    /// the chance that a random ray through the root also crosses it. Lower
    /// is better; it compares trees over the same primitives (a leaf-only
    /// tree of `n` primitives costs `n`). 0 for the empty tree; with a flat
    /// root box (area 0) every ratio counts as 1.
    pub fn sah_cost(&self) -> f64 {
        let Some(root) = self.nodes.first() else {
            return 0.0;
        };
        let root_area = root.bounds().area();
        self.nodes
            .iter()
            .map(|n| {
                let p = if root_area > 0.0 {
                    n.bounds().area() / root_area
                } else {
                    1.0
                };
                p * if n.count == 0 {
                    C_TRAV
                } else {
                    n.count as f64 * C_ISECT
                }
            })
            .sum()
    }
}

/// See [`Bvh::prim_refs`].
fn prim_refs(prims: &[u32], n_triangles: usize) -> Vec<u32> {
    let n = n_triangles as u32;
    prims
        .par_iter()
        .map(|&p| if p < n { p } else { (p - n) | PRIM_SPHERE })
        .collect()
}

/// Writes `tree` depth-first into `out` (exactly its size), whose first
/// node sits at `offset` in the whole array; subtrees in parallel.
fn flatten(tree: &Tree, out: &mut [Node], offset: u32) {
    match tree {
        Tree::Chunk(nodes) => {
            for (o, n) in out.iter_mut().zip(nodes) {
                *o = *n;
                if n.count == 0 {
                    o.index += offset;
                }
            }
        }
        Tree::Interior {
            bounds, children, ..
        } => {
            let left = children.0.size();
            let (head, rest) = out.split_at_mut(1);
            let (l, r) = rest.split_at_mut(left);
            let right_at = offset + 1 + left as u32;
            head[0] = Node::new(bounds, right_at, 0);
            rayon::join(
                || flatten(&children.0, l, offset + 1),
                || flatten(&children.1, r, right_at),
            );
        }
    }
}

/// The builder's box: `f32` in SIMD lanes, half the memory traffic of
/// [`Aabb`] and one instruction per union. Inputs are rounded outwards, so
/// it always contains the `f64` box it came from; the SAH only needs
/// relative areas, which `f32` gives to 7 digits.
#[derive(Clone, Copy)]
pub(crate) struct Box32 {
    min: Vec3A,
    max: Vec3A,
}

impl Box32 {
    const EMPTY: Box32 = Box32 {
        min: Vec3A::INFINITY,
        max: Vec3A::NEG_INFINITY,
    };

    fn new(min: [f32; 3], max: [f32; 3]) -> Box32 {
        Box32 {
            min: Vec3A::from_array(min),
            max: Vec3A::from_array(max),
        }
    }

    fn outward(b: &Aabb) -> Box32 {
        let (min, max) = b.outward_f32();
        Box32::new(min, max)
    }

    #[cfg(test)]
    fn to_f64(self) -> Aabb {
        Aabb {
            min: self.min.as_dvec3(),
            max: self.max.as_dvec3(),
        }
    }

    fn union(self, o: Box32) -> Box32 {
        Box32 {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    fn grow(self, p: Vec3A) -> Box32 {
        Box32 {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    /// Half the surface area (0 for the empty box): the SAH compares ratios.
    fn half_area(&self) -> f32 {
        let d = self.max - self.min;
        if d.min_element() < 0.0 {
            return 0.0;
        }
        d.x * d.y + d.y * d.z + d.z * d.x
    }

    /// Half the surface area of a box known not to be empty (the sweep
    /// skips planes with an empty side): no test.
    fn half_area_unchecked(&self) -> f32 {
        let d = self.max - self.min;
        d.x * d.y + d.y * d.z + d.z * d.x
    }

    /// Twice the centre (min + max): binning only compares centres, so
    /// the halving is left out.
    fn centre2(&self) -> Vec3A {
        self.min + self.max
    }
}

/// A primitive during the build: its box and its index in the input, in 32
/// bytes (two SIMD lanes of four): the index rides in the lower corner's
/// unused fourth lane, as the bits of a float offset by 1.0's bits so the
/// lane always holds a normal number (no slow denormal arithmetic) for
/// every index below 2³⁰.
#[derive(Clone, Copy)]
struct Prim {
    min: Vec4,
    max: Vec3A,
}

const ONE_BITS: u32 = 0x3f80_0000;
/// Most primitives the builder takes (its records keep an index below 2³⁰).
pub const MAX_PRIMS: usize = 1 << 30;

impl Prim {
    fn new(b: Box32, index: u32) -> Prim {
        Prim {
            min: b.min.extend(f32::from_bits(ONE_BITS + index)),
            max: b.max,
        }
    }

    fn bounds(&self) -> Box32 {
        Box32 {
            min: Vec3A::from_vec4(self.min),
            max: self.max,
        }
    }

    fn index(&self) -> u32 {
        self.min.w.to_bits() - ONE_BITS
    }
}

/// Builds the subtree over `order` (whose first element sits at `first`
/// in the final reference array), given the primitives' bounds `b` and the
/// bounds `cb` of their doubled centres; returns it with its depth. Large
/// nodes hand their two halves to rayon; below [`PARALLEL_THRESHOLD`]
/// primitives the subtree is built on this thread into one flat chunk.
fn build_subtree(
    order: &mut [Prim],
    first: usize,
    depth: usize,
    b: Box32,
    cb: Box32,
    sample_above: usize,
) -> (Tree, usize) {
    if order.len() < PARALLEL_THRESHOLD {
        // At most 2n - 1 nodes; about 0.6 n in practice.
        let mut nodes = Vec::with_capacity(order.len());
        let depth = build_chunk(order, first, depth, b, cb, sample_above, &mut nodes);
        return (Tree::Chunk(nodes), depth);
    }
    let split = if depth + 1 >= MAX_DEPTH {
        None
    } else {
        split(order, &b, &cb, sample_above)
    };
    let Some((mid, ((lb, lcb), (rb, rcb)))) = split else {
        let leaf = Node::new(&b, first as u32, order.len() as u32);
        return (Tree::Chunk(vec![leaf]), depth);
    };
    let (left, right) = order.split_at_mut(mid);
    let ((l, dl), (r, dr)) = rayon::join(
        || build_subtree(left, first, depth + 1, lb, lcb, sample_above),
        || build_subtree(right, first + mid, depth + 1, rb, rcb, sample_above),
    );
    let size = 1 + l.size() + r.size();
    (
        Tree::Interior {
            bounds: b,
            children: Box::new((l, r)),
            size,
        },
        dl.max(dr),
    )
}

/// Appends the subtree over `order` to `out` depth-first (see
/// [`build_subtree`]); returns its depth.
fn build_chunk(
    order: &mut [Prim],
    first: usize,
    depth: usize,
    b: Box32,
    cb: Box32,
    sample_above: usize,
    out: &mut Vec<Node>,
) -> usize {
    let at = out.len();
    out.push(Node::new(&b, first as u32, order.len() as u32));
    if order.len() <= 1 || depth + 1 >= MAX_DEPTH {
        return depth;
    }
    // Nodes of a chunk above `sample_above` primitives bin a sample too.
    let Some((mid, ((lb, lcb), (rb, rcb)))) = split(order, &b, &cb, sample_above) else {
        return depth;
    };
    let (left, right) = order.split_at_mut(mid);
    out[at].count = 0;
    let dl = build_chunk(left, first, depth + 1, lb, lcb, sample_above, out);
    // The right child's position in this chunk.
    out[at].index = out.len() as u32;
    let dr = build_chunk(right, first + mid, depth + 1, rb, rcb, sample_above, out);
    dl.max(dr)
}

/// Bounds (box, doubled-centre box) of each side of a split.
type Sides = ((Box32, Box32), (Box32, Box32));

/// Partitions `order` by the best binned-SAH split and returns the size of
/// the left part with the bounds of both parts, or `None` when a leaf is
/// cheaper (and small enough) or the primitives cannot be separated.
fn split(
    order: &mut [Prim],
    bounds: &Box32,
    cb: &Box32,
    sample_above: usize,
) -> Option<(usize, Sides)> {
    let n = order.len();
    let extent = cb.max - cb.min;
    // Near the leaves SAH buys little and its fixed cost per node dominates
    // the build (most nodes are small): split at the median centroid of the
    // widest axis instead.
    if n <= SMALL_NODE {
        if n <= MAX_LEAF {
            return None;
        }
        let axis = extent.max_position();
        if extent[axis] > 0.0 {
            sort_small(order, axis);
        }
        let (l, r) = order.split_at(n / 2);
        return Some((n / 2, (bounds_of(l), bounds_of(r))));
    }
    // Small nodes need fewer bins than primitives: the per-node cost of the
    // sweep then shrinks with the node. Bins per unit length on each axis;
    // 0 where the centroids coincide.
    let nb = BINS.min(n.max(2));
    let scale = Vec3A::select(extent.cmpgt(Vec3A::ZERO), nb as f32 / extent, Vec3A::ZERO);
    // Nodes above `sample_above` primitives choose their plane from a
    // stratified sample of at least SAMPLES of them: the binned SAH is only
    // an estimate at 16 bins anyway, the partition below still takes every
    // primitive and the children's exact bounds, and so the top levels make
    // one pass over their primitives instead of two. (The counts are then
    // the sample's: fine for choosing the plane, and the leaf test below
    // only concerns nodes of at most MAX_LEAF.)
    let mut stride = if n > sample_above { n / SAMPLES } else { 1 };
    let mut bins = EMPTY_BINS;
    bin(order, stride, cb, scale, nb, &mut bins);
    // A few huge primitives among many small ones (a ground quad beside a
    // dense mesh) decide the best split yet are rarely sampled: when the
    // sample's bounds miss part of the node's, bin everything.
    if stride > 1 {
        let sampled = bins.bounds[0].iter().fold(Box32::EMPTY, |a, b| a.union(*b));
        if sampled.half_area() < SAMPLE_COVER * bounds.half_area() {
            stride = 1;
            bins = EMPTY_BINS;
            bin(order, stride, cb, scale, nb, &mut bins);
        }
    }
    // (cost, axis, split bin, the larger child's half area)
    let mut best: Option<(f32, usize, usize, f32)> = None;
    for axis in (0..3).filter(|&a| scale[a] > 0.0) {
        let (boxes, counts) = (&bins.bounds[axis], &bins.count[axis]);
        // Sweep from the right to get the area and count right of each plane.
        let mut right_area = [0.0; BINS];
        let mut right_count = [0u32; BINS];
        let (mut acc, mut cnt) = (Box32::EMPTY, 0);
        for k in (1..nb).rev() {
            acc = acc.union(boxes[k]);
            cnt += counts[k];
            right_area[k] = acc.half_area_unchecked();
            right_count[k] = cnt;
        }
        let (mut acc, mut cnt) = (Box32::EMPTY, 0);
        for k in 1..nb {
            acc = acc.union(boxes[k - 1]);
            cnt += counts[k - 1];
            if cnt == 0 || right_count[k] == 0 {
                continue;
            }
            let left_area = acc.half_area_unchecked();
            let cost = left_area * cnt as f32 + right_area[k] * right_count[k] as f32;
            if best.is_none_or(|(c, ..)| cost < c) {
                best = Some((cost, axis, k, left_area.max(right_area[k])));
            }
        }
    }
    let area = bounds.half_area();
    let Some((mut cost, axis, k, larger)) = best else {
        // All centroids coincide: split by count if the leaf is too big.
        if n <= MAX_LEAF {
            return None;
        }
        let (l, r) = order.split_at(n / 2);
        return Some((n / 2, (bounds_of(l), bounds_of(r))));
    };
    // A child nearly as large as the node holds a primitive almost as large
    // (a ground quad beside a dense mesh), which no plane through the
    // centroids can separate from its small neighbours: each level would
    // peel off another thin slice of them, and every ray that meets the
    // large primitive would descend through all those levels. Try putting
    // the large primitives on a side of their own.
    let mut by_size = None;
    if larger >= LARGE_CHILD * area {
        if let Some((c, threshold)) = size_split(order, stride, area) {
            if c < cost {
                cost = c;
                by_size = Some(threshold);
            }
        }
    }
    let split_cost = C_TRAV
        + if area > 0.0 {
            cost as f64 / area as f64
        } else {
            n as f64
        } * C_ISECT;
    if n <= MAX_LEAF && n as f64 * C_ISECT <= split_cost {
        return None;
    }
    if let Some(threshold) = by_size {
        return Some(partition(order, &|p: &Prim| {
            p.bounds().half_area_unchecked() > threshold
        }));
    }
    // Left of the plane iff the bin on `axis` is below `k`: for x = (centre
    // - cb.min)·scale that is `!(x >= k)` (NaN and negatives land in bin 0,
    // x ≥ nb - 1 in the last bin), one compare and no conversion.
    let plane = Vec3A::splat(k as f32);
    let goes_left = |p: &Prim| {
        let x = (p.bounds().centre2() - cb.min) * scale;
        x.cmpge(plane).bitmask() & (1 << axis) == 0
    };
    Some(partition(order, &goes_left))
}

/// The cheapest split of `order` into large primitives (left) and small
/// ones (right), by the SAH cost `A_L·N_L + A_R·N_R` that [`split`] sweeps,
/// over every primitive or, with `stride` above 1, over one of each run of
/// `stride` (the counts are then a sample's, as the bins' are). A primitive
/// is large when its box's half area exceeds a share of the node's half
/// area `area`, one of [`LARGE_SHARES`]; returns the best cost with its
/// least large half area, or `None` when no share puts primitives on both
/// sides.
fn size_split(order: &[Prim], stride: usize, area: f32) -> Option<(f32, f32)> {
    type Sizes = [(Box32, u32, Box32, u32); LARGE_SHARES.len()];
    let thresholds = LARGE_SHARES.map(|s| s * area);
    let empty: Sizes = [(Box32::EMPTY, 0, Box32::EMPTY, 0); LARGE_SHARES.len()];
    let add = |mut acc: Sizes, p: &Prim| {
        let b = p.bounds();
        let a = b.half_area_unchecked();
        for (side, &t) in acc.iter_mut().zip(&thresholds) {
            if a > t {
                side.0 = side.0.union(b);
                side.1 += 1;
            } else {
                side.2 = side.2.union(b);
                side.3 += 1;
            }
        }
        acc
    };
    let merge = |mut a: Sizes, b: Sizes| {
        for (x, y) in a.iter_mut().zip(b) {
            *x = (x.0.union(y.0), x.1 + y.1, x.2.union(y.2), x.3 + y.3);
        }
        a
    };
    let sides = if stride > 1 {
        let sample = order.chunks(stride).enumerate();
        sample.fold(empty, |acc, (r, run)| add(acc, &run[jitter(r) % run.len()]))
    } else if order.len() < PARALLEL_THRESHOLD * 4 {
        order.iter().fold(empty, add)
    } else {
        // Min, max and integer counts: the same result however rayon
        // splits the work.
        order.par_iter().fold(|| empty, add).reduce(|| empty, merge)
    };
    sides
        .iter()
        .zip(thresholds)
        .filter(|(side, _)| side.1 > 0 && side.3 > 0)
        .map(|(side, t)| {
            let cost = side.0.half_area_unchecked() * side.1 as f32
                + side.2.half_area_unchecked() * side.3 as f32;
            (cost, t)
        })
        .min_by(|a, b| a.0.total_cmp(&b.0))
}

/// A node whose best plane leaves a child of at least this share of its
/// half area also tries [`size_split`].
const LARGE_CHILD: f32 = 0.8;
/// The shares of a node's half area above which [`size_split`] counts a
/// primitive as large.
const LARGE_SHARES: [f32; 4] = [1.0 / 2.0, 1.0 / 8.0, 1.0 / 32.0, 1.0 / 128.0];

/// Partitions `order` in place by `goes_left` (Hoare: swap only misplaced
/// pairs), gathering both sides' bounds on the way, so the children need
/// no pass of their own; returns the size of the left part with them.
/// Nodes that fit in the cache take [`partition_scratch`].
fn partition(order: &mut [Prim], goes_left: &impl Fn(&Prim) -> bool) -> (usize, Sides) {
    if order.len() <= SCRATCH_PARTITION {
        return partition_scratch(order, goes_left);
    }
    let mut left = (Box32::EMPTY, Box32::EMPTY);
    let mut right = (Box32::EMPTY, Box32::EMPTY);
    let add = |side: &mut (Box32, Box32), p: &Prim| {
        side.0 = side.0.union(p.bounds());
        side.1 = side.1.grow(p.bounds().centre2());
    };
    let (mut i, mut j) = (0, order.len());
    loop {
        while i < j && goes_left(&order[i]) {
            add(&mut left, &order[i]);
            i += 1;
        }
        while i < j && !goes_left(&order[j - 1]) {
            add(&mut right, &order[j - 1]);
            j -= 1;
        }
        if i >= j {
            break;
        }
        order.swap(i, j - 1);
    }
    (i, (left, right))
}

/// Nodes of at most this many primitives partition through a scratch
/// buffer (it stays in the cache).
const SCRATCH_PARTITION: usize = PARALLEL_THRESHOLD;

thread_local! {
    static SCRATCH: std::cell::RefCell<Vec<Prim>> = const { std::cell::RefCell::new(Vec::new()) };
}

/// [`partition`] without a data-dependent branch: each primitive is written
/// to the next free place at the front or the back of a scratch buffer
/// (the choice is a conditional move, not a jump the predictor must guess
/// for every primitive of an unordered node), then copied back; the sides'
/// bounds take a second pass over the cached records.
fn partition_scratch(order: &mut [Prim], goes_left: &impl Fn(&Prim) -> bool) -> (usize, Sides) {
    let n = order.len();
    let left = SCRATCH.with_borrow_mut(|scratch| {
        if scratch.len() < n {
            scratch.resize(
                n,
                Prim {
                    min: Vec4::ZERO,
                    max: Vec3A::ZERO,
                },
            );
        }
        let (mut l, mut r) = (0, n);
        for p in order.iter() {
            let left = goes_left(p);
            scratch[if left { l } else { r - 1 }] = *p;
            l += usize::from(left);
            r -= usize::from(!left);
        }
        order.copy_from_slice(&scratch[..n]);
        l
    });
    let (l, r) = order.split_at(left);
    (left, (bounds_of(l), bounds_of(r)))
}

/// The bins of a node, per axis.
#[derive(Clone, Copy)]
struct Bins {
    bounds: [[Box32; BINS]; 3],
    count: [[u32; BINS]; 3],
}

const EMPTY_BINS: Bins = Bins {
    bounds: [[Box32::EMPTY; BINS]; 3],
    count: [[0; BINS]; 3],
};

/// Adds one primitive of every run of `stride` in `order` to `acc`, along
/// all three axes (in parallel chunks for large nodes: the top levels would
/// otherwise run on one thread). Min, max and integer counts make the
/// result independent of how rayon splits the work. `acc` is filled in
/// place: most nodes are small, and copying the bins would cost about as
/// much as binning their primitives.
fn bin(order: &[Prim], stride: usize, cb: &Box32, scale: Vec3A, nb: usize, acc: &mut Bins) {
    let add = |acc: &mut Bins, chunk: &[Prim]| {
        let mut add_one = |p: &Prim| {
            let k = bins_of(p, cb.min, scale, nb);
            for axis in 0..3 {
                let k = k[axis] as usize;
                acc.bounds[axis][k] = acc.bounds[axis][k].union(p.bounds());
                acc.count[axis][k] += 1;
            }
        };
        if stride == 1 {
            chunk.iter().for_each(add_one);
        } else {
            // One primitive of each run, at a pseudo-random place in it
            // (fixed by the run's position in the chunk): a regular stride
            // would alias with the input's order (every 4th triangle of a
            // subdivided mesh is the same corner; a sphere's rings repeat).
            for (r, run) in chunk.chunks(stride).enumerate() {
                add_one(&run[jitter(r) % run.len()]);
            }
        }
    };
    if order.len() < PARALLEL_THRESHOLD * 4 * stride {
        add(acc, order);
        return;
    }
    // Chunk lengths are multiples of the stride, so the same primitives are
    // sampled however the chunks are handed out.
    let sum = order
        .par_chunks(PARALLEL_THRESHOLD * stride)
        .fold(
            || EMPTY_BINS,
            |mut a, chunk| {
                add(&mut a, chunk);
                a
            },
        )
        .reduce(
            || EMPTY_BINS,
            |mut a, b| {
                merge(&mut a, &b);
                a
            },
        );
    merge(acc, &sum);
}

fn merge(a: &mut Bins, b: &Bins) {
    for axis in 0..3 {
        for k in 0..BINS {
            a.bounds[axis][k] = a.bounds[axis][k].union(b.bounds[axis][k]);
            a.count[axis][k] += b.count[axis][k];
        }
    }
}

/// A hash of `i` (a 32-bit integer mix, after Wellons' "prospecting"):
/// deterministic, and well spread in its low bits.
fn jitter(i: usize) -> usize {
    let mut x = i as u32;
    x ^= x >> 16;
    x = x.wrapping_mul(0x7feb_352d);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846c_a68b);
    x ^= x >> 16;
    x as usize
}

/// Bounds of the primitives and of their doubled centres, in one pass.
fn bounds_of(order: &[Prim]) -> (Box32, Box32) {
    let add =
        |(b, c): (Box32, Box32), p: &Prim| (b.union(p.bounds()), c.grow(p.bounds().centre2()));
    let empty = (Box32::EMPTY, Box32::EMPTY);
    if order.len() < PARALLEL_THRESHOLD * 4 {
        return order.iter().fold(empty, add);
    }
    order
        .par_iter()
        .fold(|| empty, add)
        .reduce(|| empty, |(a, b), (c, d)| (a.union(c), b.union(d)))
}

/// The bins (of `nb`, per axis) of a primitive's doubled centre; 0 on an
/// axis without extent. Binning and partitioning both call this, so a
/// primitive always goes to the side its bin was counted on. The
/// float-to-int casts saturate: NaN and negatives go to bin 0.
#[inline]
fn bins_of(p: &Prim, cb_min: Vec3A, scale: Vec3A, nb: usize) -> UVec3 {
    // Clamped as floats (`max` returns its second operand for NaN), then
    // truncated; exact for the small integers in range.
    let x = ((p.bounds().centre2() - cb_min) * scale)
        .max(Vec3A::ZERO)
        .min(Vec3A::splat((nb - 1) as f32));
    truncate(x)
}

/// `x` truncated to integers, for `x` in `[0, 2³¹)`: one SSE2 instruction
/// for all lanes (`as` casts convert lane by lane, with saturation checks).
#[cfg(target_arch = "x86_64")]
#[inline]
fn truncate(x: Vec3A) -> UVec3 {
    use std::arch::x86_64::{__m128i, _mm_cvttps_epi32};
    // SAFETY: SSE2 is part of every x86_64 target.
    let i = unsafe { _mm_cvttps_epi32(x.into()) };
    let i: [u32; 4] = bytemuck::cast::<__m128i, _>(i);
    UVec3::new(i[0], i[1], i[2])
}

#[cfg(not(target_arch = "x86_64"))]
#[inline]
fn truncate(x: Vec3A) -> UVec3 {
    x.as_uvec3()
}

/// Sorts a small node's primitives by centre along `axis` (insertion sort
/// on keys computed once; the median split takes the first half).
fn sort_small(order: &mut [Prim], axis: usize) {
    let mut keys = [0.0f32; SMALL_NODE];
    for (k, p) in keys.iter_mut().zip(order.iter()) {
        *k = p.bounds().centre2()[axis];
    }
    for i in 1..order.len() {
        let (key, p) = (keys[i], order[i]);
        let mut j = i;
        while j > 0 && keys[j - 1] > key {
            keys[j] = keys[j - 1];
            order[j] = order[j - 1];
            j -= 1;
        }
        keys[j] = key;
        order[j] = p;
    }
}

/// Random boxes for tests (a small LCG: deterministic, no dependency).
#[cfg(test)]
pub(crate) fn random_boxes(n: usize, seed: u64) -> Vec<Aabb> {
    let mut s = seed;
    let mut next = move || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    (0..n)
        .map(|_| {
            let c = DVec3::new(next(), next(), next()) * 100.0 - 50.0;
            let h = DVec3::new(next(), next(), next()) * 2.0;
            Aabb {
                min: c - h,
                max: c + h,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Checks the structural invariants and returns the leaves' total size.
    fn check(bvh: &Bvh, boxes: &[Aabb], node: usize, depth: usize) -> usize {
        let n = &bvh.nodes[node];
        assert!(depth < MAX_DEPTH);
        if n.count > 0 {
            for &p in &bvh.prims[n.index as usize..(n.index + n.count) as usize] {
                assert!(n.bounds().contains(&boxes[p as usize]));
            }
            n.count as usize
        } else {
            let (l, r) = (node + 1, n.index as usize);
            assert!(
                n.bounds().contains(&bvh.nodes[l].bounds())
                    && n.bounds().contains(&bvh.nodes[r].bounds())
            );
            check(bvh, boxes, l, depth + 1) + check(bvh, boxes, r, depth + 1)
        }
    }

    #[test]
    fn every_primitive_in_exactly_one_leaf_inside_its_boxes() {
        for n in [1, 2, 5, 100, 10_000] {
            let boxes = random_boxes(n, n as u64);
            let bvh = Bvh::build(&boxes);
            assert_eq!(check(&bvh, &boxes, 0, 0), n);
            let mut seen = bvh.prims.clone();
            seen.sort_unstable();
            assert_eq!(seen, (0..n as u32).collect::<Vec<_>>());
            assert!(bvh
                .nodes
                .iter()
                .all(|x| x.count as usize <= MAX_LEAF || n <= MAX_LEAF));
        }
    }

    #[test]
    fn identical_primitives_still_split_and_stay_shallow() {
        let b = Aabb {
            min: DVec3::ZERO,
            max: DVec3::ONE,
        };
        let bvh = Bvh::build(&vec![b; 1000]);
        assert_eq!(check(&bvh, &vec![b; 1000], 0, 0), 1000);
        assert!(bvh.depth < MAX_DEPTH);
    }

    #[test]
    fn sah_separates_clusters() {
        // Two far clusters: the root must split them apart.
        let mut boxes = random_boxes(50, 1);
        boxes.extend(random_boxes(50, 2).into_iter().map(|b| Aabb {
            min: b.min + 1e4,
            max: b.max + 1e4,
        }));
        let bvh = Bvh::build(&boxes);
        let root = bvh.nodes[0];
        let (l, r) = (
            bvh.nodes[1].bounds(),
            bvh.nodes[root.index as usize].bounds(),
        );
        assert!(l.max.x < 1e3 && r.min.x > 1e3 || r.max.x < 1e3 && l.min.x > 1e3);
    }

    #[test]
    fn f32_boxes_give_the_same_tree_as_exact_f64_ones() {
        // Boxes exactly representable in f32: both entry points must agree.
        let boxes: Vec<Aabb> = random_boxes(20_000, 7)
            .into_iter()
            .map(|b| Aabb {
                min: b.min.as_vec3().as_dvec3(),
                max: b.max.as_vec3().as_dvec3(),
            })
            .collect();
        let a = Bvh::build(&boxes);
        let b = Bvh::build_f32(boxes.len(), |i| {
            (
                boxes[i].min.as_vec3().to_array(),
                boxes[i].max.as_vec3().to_array(),
            )
        });
        assert_eq!(a, b);
        assert_eq!(check(&b, &boxes, 0, 0), boxes.len());
    }

    #[test]
    fn prim_records_keep_every_index_and_a_normal_float() {
        let b = Box32::outward(&random_boxes(1, 3)[0]);
        for i in [0, 1, 5, 1 << 23, (MAX_PRIMS - 1) as u32] {
            let p = Prim::new(b, i);
            assert_eq!(p.index(), i);
            assert!(p.min.w.is_normal());
        }
    }

    #[test]
    fn f64_boxes_are_rounded_outwards() {
        let b = Aabb {
            min: DVec3::splat(0.1),
            max: DVec3::splat(0.3),
        };
        let r = Box32::outward(&b).to_f64();
        assert!(r.contains(&b));
    }

    #[test]
    fn sah_cost_of_a_known_tree() {
        // Five unit cubes in a row: the median split gives leaves of 2 and 3.
        let boxes: Vec<Aabb> = (0..5)
            .map(|i| Aabb {
                min: DVec3::new(i as f64, 0.0, 0.0),
                max: DVec3::new(i as f64 + 1.0, 1.0, 1.0),
            })
            .collect();
        let bvh = Bvh::build(&boxes);
        assert_eq!(bvh.nodes.len(), 3);
        let expected = 1.0 + (10.0 * 2.0 + 14.0 * 3.0) / 22.0;
        assert!((bvh.sah_cost() - expected).abs() < 1e-12);
        // A single leaf costs its size.
        assert_eq!(Bvh::build(&boxes[..3]).sah_cost(), 3.0);
        assert_eq!(Bvh::default().sah_cost(), 0.0);
    }

    /// Many small boxes on a sphere-like shell plus two huge ground boxes:
    /// the case a sample misses.
    fn shell_and_ground(n: usize) -> Vec<Aabb> {
        let mut boxes: Vec<Aabb> = random_boxes(n, 11)
            .into_iter()
            .map(|b| {
                let c = b.centre().normalize() * 10.0;
                Aabb {
                    min: c - 0.05,
                    max: c + 0.05,
                }
            })
            .collect();
        // A ground quad's two triangles, under the shell.
        let ground = Aabb {
            min: DVec3::new(-1e3, -10.5, -1e3),
            max: DVec3::new(1e3, -10.5, 1e3),
        };
        // Amid the shell: the samples at the ends of the array could take it.
        boxes.splice(n / 3..n / 3, [ground; 2]);
        boxes
    }

    #[test]
    fn sampled_large_build_is_valid_and_deterministic() {
        let boxes = shell_and_ground(150_000);
        assert!(boxes.len() > 2 * SAMPLE_ABOVE);
        let bvh = Bvh::build(&boxes);
        assert_eq!(check(&bvh, &boxes, 0, 0), boxes.len());
        let mut seen = bvh.prims.clone();
        seen.sort_unstable();
        assert_eq!(seen, (0..boxes.len() as u32).collect::<Vec<_>>());
        // The same tree again, and on one thread (renders must not depend
        // on how rayon schedules the build).
        assert_eq!(Bvh::build(&boxes), bvh);
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap()
            .install(|| Bvh::build(&boxes));
        assert_eq!(one, bvh);
    }

    #[test]
    fn large_primitives_get_a_side_of_their_own() {
        // The ground quad under a dense shell: its two triangles are one
        // leaf right under the root (a ray that meets only the ground tests
        // one record), whether the root bins every primitive or a sample.
        for n in [1_000, 20_000, 150_000] {
            let boxes = shell_and_ground(n);
            let bvh = Bvh::build(&boxes);
            let root = bvh.nodes[0];
            assert_eq!(root.count, 0);
            let ground = [n as u32 / 3, n as u32 / 3 + 1];
            let leaf_of = |i: usize| {
                let node = bvh.nodes[i];
                let prims = &bvh.prims[node.index as usize..][..node.count as usize];
                let mut prims = prims.to_vec();
                prims.sort_unstable();
                prims
            };
            assert!(
                leaf_of(1) == ground || leaf_of(root.index as usize) == ground,
                "{n} primitives: the ground is not a child of the root"
            );
        }
    }

    #[test]
    fn sampling_keeps_the_sah_cost() {
        // Without the fallback to binning everything, the shell's tree
        // costs 50 % more: the sample misses the ground.
        for boxes in [shell_and_ground(200_000), random_boxes(200_000, 5)] {
            let b = |i: usize| Box32::outward(&boxes[i]);
            let sampled = Bvh::build_sampled(boxes.len(), b, SAMPLE_ABOVE)
                .flatten()
                .sah_cost();
            let exact = Bvh::build_sampled(boxes.len(), b, usize::MAX)
                .flatten()
                .sah_cost();
            assert!(sampled < exact * 1.01, "{sampled} vs {exact}");
        }
    }

    #[test]
    fn empty_input_gives_an_empty_tree() {
        assert!(Bvh::build(&[]).nodes.is_empty());
    }
}
