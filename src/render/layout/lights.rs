//! Lights as the kernel sees them (`shaders/lights.wgsl`).

// The fields mirror the WGSL struct named in each struct's documentation,
// member by member (the test in layout/mod.rs checks them); they need no
// docs of their own.
#![allow(missing_docs)]

use bytemuck::{Pod, Zeroable};
use glam::DVec3;

use super::{c3, f3};
use crate::scene::LightKind;

/// Mirrors `Light` in `shaders/lights.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct Light {
    pub position: [f32; 3],
    pub kind: u32,
    pub direction: [f32; 3],
    pub cone_scale: f32,
    pub ambient: [f32; 3],
    pub cone_offset: f32,
    pub diffuse: [f32; 3],
    pub samples: u32,
    pub specular: [f32; 3],
    pub radius: f32,
    pub edge1: [f32; 3],
    pub intensity: f32,
    pub edge2: [f32; 3],
    pub _pad1: u32,
}

/// The lights that the uniform buffer `light_block` holds (the first ones
/// of the scene; `shaders/lights.wgsl` reads any others from the storage
/// buffer): 128 records of 112 bytes stay within the 16 KiB that Vulkan
/// guarantees a uniform buffer binding.
pub const UNIFORM_LIGHTS: usize = 128;
const _: () = assert!(UNIFORM_LIGHTS * std::mem::size_of::<Light>() <= 16384);

/// The uniform light block: the first [`UNIFORM_LIGHTS`] of `lights`,
/// zeros after them.
pub fn light_block(lights: &[Light]) -> Vec<Light> {
    let mut block = vec![Light::default(); UNIFORM_LIGHTS];
    let n = lights.len().min(UNIFORM_LIGHTS);
    block[..n].copy_from_slice(&lights[..n]);
    block
}

/// Light kinds, as in `shaders/lights.wgsl`.
pub const LIGHT_DIRECTIONAL: u32 = 0;
/// Point light kind.
pub const LIGHT_POINT: u32 = 1;
/// Spot light kind.
pub const LIGHT_SPOT: u32 = 2;
/// Rectangular area light kind.
pub const LIGHT_RECT: u32 = 3;
/// Sphere area light kind.
pub const LIGHT_SPHERE: u32 = 4;
/// Environment kind (sampled before the area kinds in `sample_light`).
pub const LIGHT_ENVIRONMENT: u32 = 5;

/// The kernel's record of light `l`, positions relative to `eye`.
pub(super) fn light(l: &crate::scene::Light, eye: DVec3) -> Light {
    let mut gl = Light {
        ambient: c3(l.ambient),
        diffuse: c3(l.diffuse),
        specular: c3(l.specular),
        intensity: l.intensity,
        samples: 1,
        ..Default::default()
    };
    match l.kind {
        LightKind::Directional { direction } => {
            gl.kind = LIGHT_DIRECTIONAL;
            gl.direction = f3(direction);
        }
        LightKind::Point { position } => {
            gl.kind = LIGHT_POINT;
            gl.position = f3(position - eye);
        }
        LightKind::Spot {
            position,
            direction,
            inner_angle,
            outer_angle,
        } => {
            let (scale, offset) = LightKind::spot_cone_scale_offset(inner_angle, outer_angle);
            gl.kind = LIGHT_SPOT;
            gl.position = f3(position - eye);
            gl.direction = f3(direction);
            gl.cone_scale = scale as f32;
            gl.cone_offset = offset as f32;
        }
        LightKind::Rect {
            corner,
            edge1,
            edge2,
            samples,
        } => {
            gl.kind = LIGHT_RECT;
            gl.position = f3(corner - eye);
            gl.edge1 = f3(edge1);
            gl.edge2 = f3(edge2);
            gl.direction = f3(edge1.cross(edge2).normalize());
            gl.samples = samples;
        }
        LightKind::Sphere {
            center,
            radius,
            samples,
        } => {
            gl.kind = LIGHT_SPHERE;
            gl.position = f3(center - eye);
            gl.radius = radius as f32;
            gl.samples = samples;
        }
        LightKind::Environment { up, samples } => {
            let (a, b) = crate::scene::ENVIRONMENT_GRADIENT;
            gl.kind = LIGHT_ENVIRONMENT;
            gl.direction = f3(up);
            gl.cone_offset = a as f32;
            gl.cone_scale = b as f32;
            gl.samples = samples;
            // The sampling mixture (shaders/environment.wgsl).
            let m = crate::scene::ENVIRONMENT_MIXTURE;
            gl.edge1 = [m.uniform as f32, m.cosine as f32, m.lobe_weight() as f32];
            gl.edge2 = [m.first_exponent as f32, m.ratio as f32, m.lobes as f32];
        }
    }
    gl
}
