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
//! [`MAX_LEAF`] primitives per leaf. Subtrees are built in parallel with
//! rayon.
//!
//! The flattened layout is depth-first: a node's left child follows it
//! directly, so an interior node stores only its right child's index.

use glam::DVec3;

/// Primitive references with this bit set are spheres, else triangles.
pub const PRIM_SPHERE: u32 = 1 << 31;

/// Number of SAH bins per axis.
pub const BINS: usize = 16;
/// Largest leaf the builder makes (unless the primitives cannot be split).
pub const MAX_LEAF: usize = 4;
/// Deepest tree the builder makes; the shader's traversal stack holds this
/// many entries, so it can never overflow.
pub const MAX_DEPTH: usize = 64;
/// Below this many primitives a subtree is built on the current thread.
const PARALLEL_THRESHOLD: usize = 4096;
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
}

/// One node of the flattened tree.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Node {
    /// Bounds of everything below.
    pub bounds: Aabb,
    /// Leaf: index of the first primitive reference; interior: index of the
    /// right child (the left child is the next node).
    pub index: u32,
    /// Leaf: number of primitives (≥ 1); interior: 0.
    pub count: u32,
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

enum Tree {
    Leaf {
        bounds: Aabb,
        first: usize,
        count: usize,
    },
    Interior {
        bounds: Aabb,
        children: Box<(Tree, Tree)>,
        size: usize,
    },
}

impl Tree {
    fn size(&self) -> usize {
        match self {
            Tree::Leaf { .. } => 1,
            Tree::Interior { size, .. } => *size,
        }
    }
}

#[derive(Clone, Copy)]
struct Bin {
    bounds: Aabb,
    count: usize,
}

impl Bvh {
    /// Builds the hierarchy over primitives given by their bounds.
    pub fn build(bounds: &[Aabb]) -> Bvh {
        if bounds.is_empty() {
            return Bvh::default();
        }
        let centres: Vec<DVec3> = bounds.iter().map(Aabb::centre).collect();
        let mut order: Vec<u32> = (0..bounds.len() as u32).collect();
        let ctx = Ctx {
            bounds,
            centres: &centres,
        };
        let (tree, depth) = ctx.build(&mut order, 0, 0);
        let mut nodes = Vec::with_capacity(tree.size());
        flatten(&tree, &mut nodes);
        Bvh {
            nodes,
            prims: order,
            depth,
        }
    }

    /// The primitive references of a tree built over `n_triangles` triangle
    /// boxes followed by sphere boxes: triangle `i` stays `i`, sphere `j`
    /// becomes `j | PRIM_SPHERE` (the encoding `shaders/bvh.wgsl` reads).
    pub fn prim_refs(&self, n_triangles: usize) -> Vec<u32> {
        let n = n_triangles as u32;
        self.prims
            .iter()
            .map(|&p| if p < n { p } else { (p - n) | PRIM_SPHERE })
            .collect()
    }

    /// Bytes the GPU copy takes (32 per node, 4 per primitive reference).
    pub fn gpu_bytes(&self) -> usize {
        self.nodes.len() * 32 + self.prims.len() * 4
    }
}

fn flatten(tree: &Tree, out: &mut Vec<Node>) {
    match tree {
        Tree::Leaf {
            bounds,
            first,
            count,
        } => out.push(Node {
            bounds: *bounds,
            index: *first as u32,
            count: *count as u32,
        }),
        Tree::Interior {
            bounds, children, ..
        } => {
            let at = out.len();
            out.push(Node {
                bounds: *bounds,
                index: 0,
                count: 0,
            });
            flatten(&children.0, out);
            out[at].index = out.len() as u32;
            flatten(&children.1, out);
        }
    }
}

struct Ctx<'a> {
    bounds: &'a [Aabb],
    centres: &'a [DVec3],
}

impl Ctx<'_> {
    /// Builds the subtree over `order` (whose first element sits at `first`
    /// in the final reference array); returns it with its depth.
    fn build(&self, order: &mut [u32], first: usize, depth: usize) -> (Tree, usize) {
        let bounds = order
            .iter()
            .fold(Aabb::EMPTY, |b, &i| b.union(self.bounds[i as usize]));
        let leaf = |order: &[u32]| Tree::Leaf {
            bounds,
            first,
            count: order.len(),
        };
        if order.len() <= 1 || depth + 1 >= MAX_DEPTH {
            return (leaf(order), depth);
        }
        let Some(mid) = self.split(order, &bounds) else {
            return (leaf(order), depth);
        };
        let (left, right) = order.split_at_mut(mid);
        let ((l, dl), (r, dr)) = if left.len() + right.len() >= PARALLEL_THRESHOLD {
            rayon::join(
                || self.build(left, first, depth + 1),
                || self.build(right, first + mid, depth + 1),
            )
        } else {
            (
                self.build(left, first, depth + 1),
                self.build(right, first + mid, depth + 1),
            )
        };
        let size = 1 + l.size() + r.size();
        (
            Tree::Interior {
                bounds,
                children: Box::new((l, r)),
                size,
            },
            dl.max(dr),
        )
    }

    /// Partitions `order` by the best binned-SAH split and returns the size of
    /// the left part, or `None` when a leaf is cheaper (and small enough) or
    /// the primitives cannot be separated.
    fn split(&self, order: &mut [u32], bounds: &Aabb) -> Option<usize> {
        let n = order.len();
        let cb = order
            .iter()
            .fold(Aabb::EMPTY, |b, &i| b.grow(self.centres[i as usize]));
        let extent = cb.max - cb.min;
        let mut best: Option<(f64, usize, usize)> = None; // (cost, axis, split bin)
        for axis in 0..3 {
            if extent[axis] <= 0.0 {
                continue;
            }
            let scale = BINS as f64 / extent[axis];
            let bin_of = |i: u32| {
                (((self.centres[i as usize][axis] - cb.min[axis]) * scale) as usize).min(BINS - 1)
            };
            let mut bins = [Bin {
                bounds: Aabb::EMPTY,
                count: 0,
            }; BINS];
            for &i in order.iter() {
                let b = &mut bins[bin_of(i)];
                b.bounds = b.bounds.union(self.bounds[i as usize]);
                b.count += 1;
            }
            // Sweep from the right to get the area and count right of each plane.
            let mut right_area = [0.0; BINS];
            let mut right_count = [0usize; BINS];
            let (mut acc, mut cnt) = (Aabb::EMPTY, 0);
            for k in (1..BINS).rev() {
                acc = acc.union(bins[k].bounds);
                cnt += bins[k].count;
                right_area[k] = acc.area();
                right_count[k] = cnt;
            }
            let (mut acc, mut cnt) = (Aabb::EMPTY, 0);
            for k in 1..BINS {
                acc = acc.union(bins[k - 1].bounds);
                cnt += bins[k - 1].count;
                if cnt == 0 || right_count[k] == 0 {
                    continue;
                }
                let cost = acc.area() * cnt as f64 + right_area[k] * right_count[k] as f64;
                if best.is_none_or(|(c, _, _)| cost < c) {
                    best = Some((cost, axis, k));
                }
            }
        }
        let area = bounds.area();
        let Some((cost, axis, k)) = best else {
            // All centroids coincide: split by count if the leaf is too big.
            return (n > MAX_LEAF).then_some(n / 2);
        };
        let split_cost = C_TRAV + if area > 0.0 { cost / area } else { n as f64 } * C_ISECT;
        if n <= MAX_LEAF && n as f64 * C_ISECT <= split_cost {
            return None;
        }
        let scale = BINS as f64 / extent[axis];
        let goes_left = |i: &u32| {
            ((((self.centres[*i as usize][axis] - cb.min[axis]) * scale) as usize).min(BINS - 1))
                < k
        };
        let mut mid = 0;
        for j in 0..n {
            if goes_left(&order[j]) {
                order.swap(j, mid);
                mid += 1;
            }
        }
        Some(mid)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn random_boxes(n: usize, seed: u64) -> Vec<Aabb> {
        // Small LCG: deterministic, no dependency.
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

    /// Checks the structural invariants and returns the leaves' total size.
    fn check(bvh: &Bvh, boxes: &[Aabb], node: usize, depth: usize) -> usize {
        let n = &bvh.nodes[node];
        assert!(depth < MAX_DEPTH);
        if n.count > 0 {
            for &p in &bvh.prims[n.index as usize..(n.index + n.count) as usize] {
                assert!(n.bounds.contains(&boxes[p as usize]));
            }
            n.count as usize
        } else {
            let (l, r) = (node + 1, n.index as usize);
            assert!(
                n.bounds.contains(&bvh.nodes[l].bounds) && n.bounds.contains(&bvh.nodes[r].bounds)
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
        let (l, r) = (bvh.nodes[1].bounds, bvh.nodes[root.index as usize].bounds);
        assert!(l.max.x < 1e3 && r.min.x > 1e3 || r.max.x < 1e3 && l.min.x > 1e3);
    }

    #[test]
    fn empty_input_gives_an_empty_tree() {
        assert!(Bvh::build(&[]).nodes.is_empty());
    }
}
