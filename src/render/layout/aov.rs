//! Arbitrary output variables as the hit stage writes them
//! (`shaders/aov.wgsl`).

// The fields mirror the WGSL struct named in each struct's documentation,
// member by member (the test in layout/mod.rs checks them); they need no
// docs of their own.
#![allow(missing_docs)]

use bytemuck::{Pod, Zeroable};

/// Mirrors `Aov` in `shaders/aov.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct Aov {
    pub depth: f32,
    pub normal_x: f32,
    pub normal_y: f32,
    pub normal_z: f32,
    pub u: f32,
    pub v: f32,
    pub object: u32,
    pub primitive: u32,
}
