//! Ray queries' rays and hits (`shaders/queries.wgsl`).

// The fields mirror the WGSL struct named in each struct's documentation,
// member by member (the test in layout/mod.rs checks them); they need no
// docs of their own.
#![allow(missing_docs)]

use bytemuck::{Pod, Zeroable};

/// Mirrors `QueryRay` in `shaders/queries.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct QueryRay {
    pub origin: [f32; 3],
    pub _pad0: u32,
    pub dir: [f32; 3],
    pub _pad1: u32,
}

/// Mirrors `QueryHit` in `shaders/queries.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct QueryHit {
    pub t: f32,
    pub kind: u32,
    pub index: u32,
    pub u: f32,
    pub v: f32,
    pub _pad0: u32,
    pub _pad1: u32,
    pub _pad2: u32,
}
