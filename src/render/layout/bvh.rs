//! The BVH as the kernel sees it (`shaders/bvh.wgsl`): quantised records
//! built over the primitives exactly as the GPU holds them.

// The fields mirror the WGSL struct named in each struct's documentation,
// member by member (the test in layout/mod.rs checks them); they need no
// docs of their own.
#![allow(missing_docs)]

use bytemuck::{Pod, Zeroable};
use glam::{DVec3, Vec3};

use super::GpuScene;
use crate::bvh::{Aabb, Bvh, Chunked};

pub use crate::bvh::PRIM_SPHERE;

/// Mirrors `BvhNode` in `shaders/bvh.wgsl`: an interior node's two
/// children, their boxes quantised in the node's frame (see
/// [`crate::render::quantised_bvh`]); 32 bytes, two texels.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct BvhNode {
    /// The frame's lower corner, per axis `k·2^e` in one word: the signed
    /// step count `k` in the upper 24 bits, the step's biased exponent
    /// `e + 127` (as in an `f32`) in the low 8.
    pub origin: [u32; 3],
    /// Child reference: a record index, or `LEAF | first primitive`.
    pub left: u32,
    /// Twelve steps, a byte each: the left child's lower then upper corner
    /// (x, y, z), then the right child's.
    pub quantised: [u32; 3],
    /// The right child's reference.
    pub right: u32,
}

impl GpuScene {
    /// Builds the BVH over the primitives exactly as the GPU sees them (the
    /// rounded `f32` values), with boxes rounded outwards to `f32` and padded
    /// by a few ulps so that no hit the intersection routines report can lie
    /// outside its box ([`node_bounds`]), and encodes it for the kernel
    /// ([`crate::render::quantised_bvh`]).
    pub fn build_bvh(&mut self) {
        let built = self.build_chunked();
        self.encode_bvh(&built);
    }

    /// The second half of [`GpuScene::build_bvh`]: the kernel's primitive
    /// references and records of `built`, from [`GpuScene::build_chunked`].
    pub fn encode_bvh(&mut self, built: &Chunked) {
        let mut prims = built.prim_refs(self.triangles.len());
        self.bvh_nodes = crate::render::quantised_bvh::encode(built, &mut prims);
        self.bvh_prims = crate::render::quantised_bvh::align_leaves(&mut self.bvh_nodes, &prims);
        self.bvh_depth = built.depth;
        self.globals.num_bvh_nodes = self.bvh_nodes.len() as u32;
    }

    /// The host tree [`GpuScene::build_bvh`] encodes, flattened: over the
    /// triangles, then the spheres (the build is deterministic, so calling
    /// this again gives the same tree).
    pub fn build_tree(&self) -> Bvh {
        self.build_chunked().flatten()
    }

    /// The first half of [`GpuScene::build_bvh`]: the host tree as the
    /// builder leaves it (see [`GpuScene::build_tree`]).
    pub fn build_chunked(&self) -> Chunked {
        // Triangle boxes straight from the f32 vertices (exact); sphere
        // boxes computed in f64 and rounded outwards.
        let spheres: Vec<([f32; 3], [f32; 3])> = self
            .spheres
            .iter()
            .map(|s| {
                let c = DVec3::from_array(s.center.map(f64::from));
                let r = DVec3::splat(s.radius as f64);
                node_bounds_f32(Aabb {
                    min: c - r,
                    max: c + r,
                })
            })
            .collect();
        let triangles = &self.triangles;
        Bvh::build_f32_chunked(triangles.len() + spheres.len(), |i| {
            let Some(t) = triangles.get(i) else {
                return spheres[i - triangles.len()];
            };
            let (a, b, c) = (Vec3::from(t.v0), Vec3::from(t.v1), Vec3::from(t.v2));
            (a.min(b).min(c).to_array(), a.max(b).max(c).to_array())
        })
    }
}

/// A box padded by 2⁻²⁰ of its largest coordinate magnitude (a few `f32`
/// ulps), so it contains the rounding error of the ray/primitive tests: the
/// boxes the kernel's BVH records contain.
pub fn node_bounds(b: Aabb) -> Aabb {
    let pad = b.min.abs().max(b.max.abs()).max_element() * (1.0 / (1u64 << 20) as f64);
    Aabb {
        min: b.min - pad,
        max: b.max + pad,
    }
}

/// [`node_bounds`] rounded outwards to `f32`: it contains the `f64` box and
/// the rounding error of the ray/primitive tests.
pub fn node_bounds_f32(b: Aabb) -> ([f32; 3], [f32; 3]) {
    node_bounds(b).outward_f32()
}
