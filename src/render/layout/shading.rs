//! The scene's shaders as the kernel's table (`shaders/shading/shader.wgsl`):
//! checkers with their cells, and leaves whose program and parameters the
//! shade stage's materials fill in (`super::super::shade`).

// The fields mirror the WGSL struct named in each struct's documentation,
// member by member (the test in layout/mod.rs checks them); they need no
// docs of their own.
#![allow(missing_docs)]

use bytemuck::{Pod, Zeroable};
use glam::DVec3;

use super::f3;
use crate::scene::Shader;

/// Mirrors `ShaderNode` in `shaders/shading/shader.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct ShaderNode {
    pub cell_offset: [f32; 3],
    pub inv_size: f32,
    pub kind: u32,
    pub parity: u32,
    pub even: u32,
    pub odd: u32,
    pub program: u32,
    pub params: u32,
    pub _pad0: u32,
    pub _pad1: u32,
}

/// Shader kinds, as in `shaders/shading/shader.wgsl`: a leaf (a shader
/// file with its parameters).
pub const SHADER_LEAF: u32 = 0;
/// Checker shader kind.
pub const SHADER_CHECKER: u32 = 2;

/// The table node of shader `sh`; a checker's cells relative to `eye`.
pub(super) fn node(sh: &Shader, eye: DVec3) -> ShaderNode {
    match sh {
        Shader::Checker(c) => {
            // Split the eye's position in cells into whole cells (whose
            // parity we keep) and a fraction, in f64.
            let cells = eye / c.size;
            let whole = cells.floor();
            let parity = (whole.x + whole.y + whole.z).rem_euclid(2.0) as u32;
            ShaderNode {
                kind: SHADER_CHECKER,
                inv_size: (1.0 / c.size) as f32,
                cell_offset: f3(cells - whole),
                parity,
                even: c.even as u32,
                odd: c.odd as u32,
                ..Default::default()
            }
        }
        _ => ShaderNode {
            kind: SHADER_LEAF,
            ..Default::default()
        },
    }
}
