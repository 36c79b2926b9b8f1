//! Planes, spheres and triangles as the kernel sees them
//! (`shaders/primitives/`), camera-relative.

// The fields mirror the WGSL struct named in each struct's documentation,
// member by member (the test in layout/mod.rs checks them); they need no
// docs of their own.
#![allow(missing_docs)]

use bytemuck::{Pod, Zeroable};
use glam::DVec3;

use super::{f3, n4, GpuScene};
use crate::scene::{Object, Shape};

/// Mirrors `Plane` in `shaders/primitives/plane.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct Plane {
    pub point: [f32; 3],
    pub shader: u32,
    pub normal: [f32; 3],
    pub object: u32,
    pub uv_origin: [f32; 2],
    pub _pad: [u32; 2],
}

/// Mirrors `Sphere` in `shaders/primitives/sphere.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct Sphere {
    pub center: [f32; 3],
    pub radius: f32,
    pub shader: u32,
    pub object: u32,
    pub _pad: [u32; 2],
}

/// Mirrors `Triangle` in `shaders/primitives/triangle.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct Triangle {
    pub v0: [f32; 3],
    pub shader: u32,
    pub v1: [f32; 3],
    pub object: u32,
    pub v2: [f32; 3],
    pub normals: u32,
}

/// `Triangle::normals` value for flat-shaded triangles.
pub const NO_NORMALS: u32 = u32::MAX;

/// Mirrors `VertexNormals` in `shaders/primitives/triangle.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct VertexNormals {
    pub n0: [f32; 4],
    pub n1: [f32; 4],
    pub n2: [f32; 4],
}

/// Appends object number `object` to the primitives of `g`, relative to
/// `eye` (computed in `f64`, then rounded).
pub(super) fn push_object(g: &mut GpuScene, o: &Object, object: u32, eye: DVec3) {
    let shader = o.shader as u32;
    let push_triangle = |v: [DVec3; 3], normals: Option<[DVec3; 3]>, g: &mut GpuScene| {
        let normals = match normals {
            Some([a, b, c]) => {
                g.vertex_normals.push(VertexNormals {
                    n0: n4(a),
                    n1: n4(b),
                    n2: n4(c),
                });
                g.vertex_normals.len() as u32 - 1
            }
            None => NO_NORMALS,
        };
        // Camera-relative in f64, then rounded: a vertex shared by
        // several triangles gets the same bits in each (watertight).
        g.triangles.push(Triangle {
            v0: f3(v[0] - eye),
            shader,
            v1: f3(v[1] - eye),
            object,
            v2: f3(v[2] - eye),
            normals,
        });
    };
    match &o.shape {
        Shape::Plane(p) => {
            let q = closest_point_to(p.point, p.normal, eye);
            let (e_u, e_v) = plane_axes(p.normal);
            g.planes.push(Plane {
                point: f3(q - eye),
                shader,
                normal: f3(p.normal),
                object,
                uv_origin: [q.dot(e_u) as f32, q.dot(e_v) as f32],
                _pad: [0; 2],
            })
        }
        Shape::Sphere(s) => g.spheres.push(Sphere {
            center: f3(s.center - eye),
            radius: s.radius as f32,
            shader,
            object,
            _pad: [0; 2],
        }),
        Shape::Triangle(t) => push_triangle(t.vertices, None, g),
        Shape::Mesh(m) => {
            for (i, idx) in m.indices.iter().enumerate() {
                let normals = m.normals.as_ref().map(|n| idx.map(|k| n[k as usize]));
                push_triangle(m.triangle(i).vertices, normals, g);
            }
        }
    }
}

/// A plane's planar texture axes `(e_u, e_v)` from its unit normal, as
/// `crate::scene::texture` defines them (and `shaders/surface.wgsl`).
pub fn plane_axes(n: DVec3) -> (DVec3, DVec3) {
    let a = if n.y.abs() > 0.999 {
        DVec3::new(0.0, 0.0, -1.0)
    } else {
        DVec3::Y
    };
    let e_u = a.cross(n).normalize();
    (e_u, e_u.cross(n))
}

/// The point of a plane nearest to `eye`: a far-away `point` on the plane
/// would lose precision when rounded; this one is as close as the plane gets.
fn closest_point_to(point: DVec3, normal: DVec3, eye: DVec3) -> DVec3 {
    eye - normal * normal.dot(eye - point)
}
