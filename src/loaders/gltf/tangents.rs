//! Tangents for normal maps: glTF's TANGENT in world space, or, where a
//! primitive has none, MikkTSpace tangents (the method glTF prescribes),
//! generated with the `mikktspace` crate.
//!
//! Conventions ([`Mesh::tangents`]): unit world-space `xyz`, and in `w`
//! the sign (±1) that makes the bitangent `w·(n × t)`. A mirroring node
//! transform flips that sign, as it flips the handedness of the frame
//! (the loader also swaps the winding, so the triangles keep the side the
//! file meant).
//!
//! glTF's texture coordinates have `v` growing down the image while a
//! normal map's green channel points up it, so the sign MikkTSpace gives
//! (its bitangent along increasing `v`) is negated, as three.js does for
//! glTF: a quad mapped upright gets `w = +1`, as Blender exports it.
//!
//! MikkTSpace works on face corners and may give a shared vertex different
//! tangents in different faces (at uv seams, or on a mesh without normals,
//! whose flat normals differ face by face). Such a vertex is split: one
//! copy per distinct tangent, with the same position, normal, uvs and
//! colour, so each triangle interpolates exactly the tangents MikkTSpace
//! gave its corners.

use std::collections::HashMap;

use glam::{DMat3, DVec3, DVec4};

use crate::scene::Mesh;

/// World-space tangents from TANGENT values `raw` (`x, y, z, w` per vertex)
/// of a node with linear part `m`: `xyz` by `m`, normalised; `w` its sign,
/// flipped by a mirroring `m`. A tangent that the transform collapses (or a
/// zero one in the file) is replaced by one perpendicular to the vertex
/// normal, so that the frame stays defined.
pub(super) fn from_attribute(raw: &[f64], m: DMat3, normals: Option<&[DVec3]>) -> Vec<DVec4> {
    let flip = if m.determinant() < 0.0 { -1.0 } else { 1.0 };
    raw.chunks_exact(4)
        .enumerate()
        .map(|(i, t)| {
            let n = normals.and_then(|n| n.get(i)).copied();
            let xyz = (m * DVec3::new(t[0], t[1], t[2])).normalize_or_zero();
            let xyz = if xyz == DVec3::ZERO {
                perpendicular(n.unwrap_or(DVec3::Z))
            } else {
                xyz
            };
            let w = if t[3] < 0.0 { -1.0 } else { 1.0 } * flip;
            xyz.extend(w)
        })
        .collect()
}

/// A unit vector perpendicular to the unit `n`.
fn perpendicular(n: DVec3) -> DVec3 {
    n.any_orthonormal_vector()
}

/// The geometry MikkTSpace reads, with the tangent it writes per corner.
struct Geometry<'m> {
    mesh: &'m Mesh,
    /// Texture coordinate set of the normal map.
    set: usize,
    /// Subtracted from positions before they are rounded to `f32`.
    origin: DVec3,
    /// Flat normals per face, for a mesh without vertex normals.
    flat: Vec<DVec3>,
    /// Output: per face corner.
    corners: Vec<Option<[f32; 4]>>,
}

impl Geometry<'_> {
    fn vertex(&self, face: usize, vert: usize) -> usize {
        self.mesh.indices[face][vert] as usize
    }
}

impl mikktspace::Geometry for Geometry<'_> {
    fn num_faces(&self) -> usize {
        self.mesh.indices.len()
    }

    fn num_vertices_of_face(&self, _face: usize) -> usize {
        3
    }

    fn position(&self, face: usize, vert: usize) -> [f32; 3] {
        (self.mesh.positions[self.vertex(face, vert)] - self.origin)
            .as_vec3()
            .to_array()
    }

    fn normal(&self, face: usize, vert: usize) -> [f32; 3] {
        let n = match &self.mesh.normals {
            Some(n) => n[self.vertex(face, vert)],
            None => self.flat[face],
        };
        n.as_vec3().to_array()
    }

    fn tex_coord(&self, face: usize, vert: usize) -> [f32; 2] {
        let uv = self
            .mesh
            .uvs
            .get(self.set)
            .map(|s| s[self.vertex(face, vert)]);
        uv.unwrap_or_default().as_vec2().to_array()
    }

    fn set_tangent_encoded(&mut self, tangent: [f32; 4], face: usize, vert: usize) {
        self.corners[face * 3 + vert] = Some(tangent);
    }
}

/// Generates MikkTSpace tangents for `mesh` from uv set `set` (zeros if it
/// has none), splitting vertices whose corners got different tangents.
/// Degenerate input (zero-area faces, collapsed uvs) gets tangents
/// perpendicular to the normal rather than none.
pub(super) fn generate(mesh: &mut Mesh, set: usize) {
    let origin = mesh
        .bounds()
        .map_or(DVec3::ZERO, |(lo, hi)| (lo + hi) * 0.5);
    let flat = match mesh.normals {
        Some(_) => Vec::new(),
        None => (0..mesh.indices.len())
            .map(|f| {
                let t = mesh.triangle(f).vertices;
                let n = (t[1] - t[0]).cross(t[2] - t[0]).normalize_or_zero();
                if n == DVec3::ZERO {
                    DVec3::Z
                } else {
                    n
                }
            })
            .collect(),
    };
    let mut g = Geometry {
        mesh,
        set,
        origin,
        corners: vec![None; mesh.indices.len() * 3],
        flat,
    };
    // `false` for unsuitable geometry: every corner then takes the fallback.
    let _ = mikktspace::generate_tangents(&mut g);
    let Geometry { corners, flat, .. } = g;

    // The tangent of each corner, as exactly representable bits for grouping.
    let normal_at = |mesh: &Mesh, face: usize, v: usize| match &mesh.normals {
        Some(n) => n[v],
        None => flat[face],
    };
    let mut tangents: Vec<Option<DVec4>> = vec![None; mesh.positions.len()];
    let mut copies: HashMap<(u32, [u64; 4]), u32> = HashMap::new();
    for face in 0..mesh.indices.len() {
        for vert in 0..3 {
            let v = mesh.indices[face][vert];
            let n = normal_at(mesh, face, v as usize);
            let t = corners[face * 3 + vert]
                .map(|t| (DVec3::new(t[0].into(), t[1].into(), t[2].into()), t[3]))
                .and_then(|(xyz, w)| {
                    let xyz = xyz.normalize_or_zero();
                    (xyz != DVec3::ZERO && xyz.is_finite() && w.is_finite())
                        // Negated: glTF's v runs down the image (module docs).
                        .then(|| xyz.extend(if w < 0.0 { 1.0 } else { -1.0 }))
                })
                .unwrap_or_else(|| perpendicular(n).extend(1.0));
            match tangents[v as usize] {
                None => tangents[v as usize] = Some(t),
                Some(have) if have == t => {}
                Some(_) => {
                    let key = (v, t.to_array().map(f64::to_bits));
                    let copy = *copies.entry(key).or_insert_with(|| {
                        let new = split(mesh, v as usize);
                        tangents.push(Some(t));
                        new
                    });
                    mesh.indices[face][vert] = copy;
                }
            }
        }
    }
    // Vertices no face uses keep a defined tangent too.
    let normals = mesh.normals.clone();
    mesh.tangents = Some(
        tangents
            .into_iter()
            .enumerate()
            .map(|(i, t)| {
                t.unwrap_or_else(|| {
                    let n = normals.as_ref().map_or(DVec3::Z, |n| n[i]);
                    perpendicular(n).extend(1.0)
                })
            })
            .collect(),
    );
}

/// Appends a copy of vertex `v` (position, normal, uvs, colour) and
/// returns its index.
fn split(mesh: &mut Mesh, v: usize) -> u32 {
    mesh.positions.push(mesh.positions[v]);
    if let Some(n) = &mut mesh.normals {
        n.push(n[v]);
    }
    for set in &mut mesh.uvs {
        set.push(set[v]);
    }
    if let Some(c) = &mut mesh.colours {
        c.push(c[v]);
    }
    (mesh.positions.len() - 1) as u32
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec2;

    /// A unit quad in the xy plane facing +z, u along +x and v along −y
    /// (glTF's v grows downwards in the image).
    fn quad(normals: bool) -> Mesh {
        Mesh {
            positions: vec![
                DVec3::new(0.0, 0.0, 0.0),
                DVec3::new(1.0, 0.0, 0.0),
                DVec3::new(1.0, 1.0, 0.0),
                DVec3::new(0.0, 1.0, 0.0),
            ],
            normals: normals.then(|| vec![DVec3::Z; 4]),
            indices: vec![[0, 1, 2], [0, 2, 3]],
            uvs: vec![vec![
                DVec2::new(0.0, 1.0),
                DVec2::new(1.0, 1.0),
                DVec2::new(1.0, 0.0),
                DVec2::new(0.0, 0.0),
            ]],
            colours: None,
            tangents: None,
        }
    }

    #[test]
    fn a_flat_quad_gets_u_as_tangent_and_its_bitangent_up_the_image() {
        for normals in [true, false] {
            let mut m = quad(normals);
            generate(&mut m, 0);
            let t = m.tangents.as_ref().unwrap();
            assert_eq!(t.len(), 4, "no split on a flat quad");
            for t in t {
                assert!((t.truncate() - DVec3::X).length() < 1e-6, "{t}");
                // Bitangent w·(n × t) = w·(z × x) = w·y must point up the
                // image (decreasing v), which is +y here: w = +1.
                assert_eq!(t.w, 1.0, "{t}");
            }
        }
    }

    #[test]
    fn a_seam_splits_the_shared_vertices() {
        // The second triangle's uvs are mirrored in u: its tangent is −x.
        let mut m = quad(true);
        m.positions
            .extend([DVec3::new(2.0, 0.0, 0.0), DVec3::new(2.0, 1.0, 0.0)]);
        m.normals.as_mut().unwrap().extend([DVec3::Z; 2]);
        m.uvs[0].extend([DVec2::new(0.0, 1.0), DVec2::new(0.0, 0.0)]);
        m.indices.extend([[1, 4, 5], [1, 5, 2]]);
        generate(&mut m, 0);
        let t = m.tangents.as_ref().unwrap();
        assert!(t.len() > 6, "vertices 1 and 2 are split: {}", t.len());
        assert_eq!(t.len(), m.positions.len());
        assert_eq!(m.uvs[0].len(), m.positions.len());
        for tri in &m.indices[2..] {
            for &v in tri {
                assert!((t[v as usize].truncate() + DVec3::X).length() < 1e-6);
            }
        }
        for tri in &m.indices[..2] {
            for &v in tri {
                assert!((t[v as usize].truncate() - DVec3::X).length() < 1e-6);
            }
        }
    }

    #[test]
    fn attribute_tangents_follow_the_node_and_mirroring_flips_w() {
        let raw = [1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, -1.0];
        let t = from_attribute(&raw, DMat3::from_diagonal(DVec3::new(3.0, 1.0, 1.0)), None);
        assert_eq!(t[0], DVec4::new(1.0, 0.0, 0.0, 1.0));
        assert_eq!(t[1].w, -1.0);
        assert!((t[1].truncate().length() - 1.0).abs() < 1e-12);
        let mirror = DMat3::from_diagonal(DVec3::new(-1.0, 1.0, 1.0));
        let t = from_attribute(&raw, mirror, None);
        assert_eq!(t[0], DVec4::new(-1.0, 0.0, 0.0, -1.0));
        assert_eq!(t[1].w, 1.0);
    }
}
