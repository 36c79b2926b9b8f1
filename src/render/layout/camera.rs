//! The camera as the kernel sees it (`shaders/camera.wgsl`): the view
//! frustum's axes, pre-scaled by the image plane's half extents.

// The fields mirror the WGSL struct named in each struct's documentation,
// member by member (the test in layout/mod.rs checks them); they need no
// docs of their own.
#![allow(missing_docs)]

use bytemuck::{Pod, Zeroable};

use super::f3;
use crate::scene::Projection;

/// Mirrors `Camera` in `shaders/camera.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct Camera {
    pub right: [f32; 3],
    pub orthographic: u32,
    pub up: [f32; 3],
    pub _pad0: u32,
    pub forward: [f32; 3],
    pub _pad1: u32,
}

/// The kernel's camera: at the origin (positions are camera-relative), its
/// right and up axes scaled by the half extents of the image plane at
/// distance 1 (perspective) or of the window (orthographic).
pub(super) fn camera(cam: &crate::scene::Camera) -> Camera {
    let (hw, hh) = cam.half_extent();
    Camera {
        right: f3(cam.orientation.x_axis * hw),
        orthographic: matches!(cam.projection, Projection::Orthographic { .. }) as u32,
        up: f3(cam.orientation.y_axis * hh),
        _pad0: 0,
        forward: f3(-cam.orientation.z_axis),
        _pad1: 0,
    }
}
