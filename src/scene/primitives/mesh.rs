//! Indexed triangle mesh, as loaded from glTF (node transforms already
//! applied, so positions are in world space).

use glam::{DVec2, DVec3, DVec4, Vec4};

use super::Triangle;

/// World-space triangle mesh with optional per-vertex normals.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions, world space.
    pub positions: Vec<DVec3>,
    /// Unit vertex normals, world space, one per position; `None` shades
    /// with the geometric normal of each triangle.
    pub normals: Option<Vec<DVec3>>,
    /// Vertex indices, three per triangle.
    pub indices: Vec<[u32; 3]>,
    /// Texture coordinate sets (`uvs[n]` is glTF's TEXCOORD_n), one entry
    /// per position each; empty without any.
    pub uvs: Vec<Vec<DVec2>>,
    /// Linear RGBA vertex colours (glTF's COLOR_0), one per position.
    pub colours: Option<Vec<Vec4>>,
    /// World-space unit tangents with the bitangent's sign in `w` (glTF's
    /// TANGENT, or generated with MikkTSpace), one per position; present
    /// where a normal map needs them.
    pub tangents: Option<Vec<DVec4>>,
}

impl Mesh {
    /// The `i`-th triangle.
    pub fn triangle(&self, i: usize) -> Triangle {
        let [a, b, c] = self.indices[i];
        Triangle {
            vertices: [
                self.positions[a as usize],
                self.positions[b as usize],
                self.positions[c as usize],
            ],
        }
    }

    /// Axis-aligned bounds (min, max) of the vertices, `None` when empty.
    pub fn bounds(&self) -> Option<(DVec3, DVec3)> {
        let first = *self.positions.first()?;
        Some(
            self.positions
                .iter()
                .fold((first, first), |(lo, hi), p| (lo.min(*p), hi.max(*p))),
        )
    }
}
