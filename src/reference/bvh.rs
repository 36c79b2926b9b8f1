//! The reference's bounding volume hierarchy: the host builder
//! ([`crate::bvh::Bvh`], binned SAH) over the `f64` primitives, and a plain
//! stack traversal in `f64` (nearest child first for the closest hit, any
//! order for shadow rays), as `shaders/bvh.wgsl` does in `f32`. It only
//! speeds the search up: the hits found are those of testing every
//! primitive, so it does not change the image.

use glam::DVec3;

use super::intersect::{Ray, Triangle};
use super::Sphere;
use crate::bvh::{Aabb, Bvh};

/// `prims` entries with this bit set are spheres, else triangles (as on the GPU).
pub use crate::bvh::PRIM_SPHERE;

/// One node, depth-first: an interior node's left child is the next node and
/// `index` its right child; a leaf's `index..index + count` range of `prims`.
#[derive(Clone, Copy, Debug)]
struct Node {
    min: DVec3,
    max: DVec3,
    index: u32,
    count: u32,
}

/// The hierarchy over a scene's triangles and spheres.
#[derive(Clone, Debug, Default)]
pub struct Accel {
    nodes: Vec<Node>,
    prims: Vec<u32>,
    /// Deepest leaf (root = 0).
    pub depth: usize,
}

/// Deeper than any tree the builder makes ([`crate::bvh::MAX_DEPTH`]).
const STACK: usize = crate::bvh::MAX_DEPTH + 2;

/// Widening of a box's far distance: 1 + 2γ₃ in `f64` (γ₃ = 3u/(1 − 3u),
/// u = 2⁻⁵³), rounded up, so rounding in the slab test never loses a hit
/// (Ize, "Robust BVH Ray Traversal", JCGT 2013).
const EXIT_SCALE: f64 = 1.0 + 4.0 * f64::EPSILON;

impl Accel {
    /// Builds the hierarchy; primitive `i < triangles.len()` is triangle `i`,
    /// the others spheres.
    pub fn build(triangles: &[Triangle], spheres: &[Sphere]) -> Accel {
        let mut boxes: Vec<Aabb> = triangles.iter().map(|t| Aabb::of_points(&t.v)).collect();
        boxes.extend(spheres.iter().map(|s| {
            let r = DVec3::splat(s.radius);
            Aabb {
                min: s.center - r,
                max: s.center + r,
            }
        }));
        if boxes.is_empty() {
            return Accel::default();
        }
        let bvh = Bvh::build(&boxes);
        let prims = bvh.prim_refs(triangles.len());
        let nodes = bvh
            .nodes
            .iter()
            .map(|n| {
                // A few thousand ulps of padding: hits computed with rounding
                // error stay inside their boxes.
                let b = n.bounds();
                let pad = b.min.abs().max(b.max.abs()).max_element() * (1.0 / (1u64 << 40) as f64);
                Node {
                    min: b.min - DVec3::splat(pad),
                    max: b.max + DVec3::splat(pad),
                    index: n.index,
                    count: n.count,
                }
            })
            .collect();
        Accel {
            nodes,
            prims,
            depth: bvh.depth,
        }
    }

    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Distance at which the ray enters node `i`'s box (not before 0), or
    /// +∞ when it misses it or enters after `t_max`.
    fn entry(&self, i: usize, ray: &Ray, t_max: f64) -> f64 {
        let n = &self.nodes[i];
        let t0 = (n.min - ray.origin) * ray.inv_dir;
        let t1 = (n.max - ray.origin) * ray.inv_dir;
        let near = t0.min(t1);
        let far = t0.max(t1);
        let enter = near.max_element().max(0.0);
        let exit = far.min_element() * EXIT_SCALE;
        if enter <= exit.min(t_max) {
            enter
        } else {
            f64::INFINITY
        }
    }

    /// Calls `test(prim)` for every primitive whose leaf the ray reaches
    /// before `*t_max`, nearest leaf first; `test` returns the new nearest
    /// distance (or `*t_max` unchanged), which prunes the rest.
    pub fn closest(&self, ray: &Ray, t_max: f64, mut test: impl FnMut(u32, f64) -> f64) {
        if self.nodes.is_empty() {
            return;
        }
        let mut t_best = t_max;
        let mut stack = [(0u32, 0.0f64); STACK];
        let mut sp = 0;
        let mut node = 0usize;
        let mut node_t = self.entry(0, ray, t_best);
        loop {
            if node_t < t_best {
                let n = self.nodes[node];
                if n.count == 0 {
                    let (left, right) = (node + 1, n.index as usize);
                    let tl = self.entry(left, ray, t_best);
                    let tr = self.entry(right, ray, t_best);
                    let (near, near_t, far, far_t) = if tl <= tr {
                        (left, tl, right, tr)
                    } else {
                        (right, tr, left, tl)
                    };
                    if far_t < f64::INFINITY {
                        stack[sp] = (far as u32, far_t);
                        sp += 1;
                    }
                    node = near;
                    node_t = near_t;
                    continue;
                }
                for &p in &self.prims[n.index as usize..(n.index + n.count) as usize] {
                    t_best = test(p, t_best);
                }
            }
            if sp == 0 {
                return;
            }
            sp -= 1;
            node = stack[sp].0 as usize;
            node_t = stack[sp].1;
        }
    }

    /// Whether `blocks(prim)` holds for some primitive whose leaf the ray
    /// reaches before `t_max` (stops at the first).
    pub fn any(&self, ray: &Ray, t_max: f64, mut blocks: impl FnMut(u32) -> bool) -> bool {
        if self.nodes.is_empty() || self.entry(0, ray, t_max) == f64::INFINITY {
            return false;
        }
        let mut stack = [0u32; STACK];
        let mut sp = 0;
        let mut node = 0usize;
        loop {
            let n = self.nodes[node];
            if n.count == 0 {
                let (left, right) = (node + 1, n.index as usize);
                let hit_left = self.entry(left, ray, t_max) < f64::INFINITY;
                let hit_right = self.entry(right, ray, t_max) < f64::INFINITY;
                if hit_left || hit_right {
                    if hit_left && hit_right {
                        stack[sp] = right as u32;
                        sp += 1;
                    }
                    node = if hit_left { left } else { right };
                    continue;
                }
            } else {
                for &p in &self.prims[n.index as usize..(n.index + n.count) as usize] {
                    if blocks(p) {
                        return true;
                    }
                }
            }
            if sp == 0 {
                return false;
            }
            sp -= 1;
            node = stack[sp] as usize;
        }
    }
}
