//! The framing camera: the view penumbra takes of a glTF file without a
//! camera (or with `--camera framing`), as model viewers frame a model.
//! docs/gltf.md states the rule:
//!
//! - It looks from a front-biased three-quarter direction: glTF's front
//!   is +Z and up +Y, so from 30° to the right of the front and 20° above
//!   it ([`AZIMUTH_DEG`], [`ELEVATION_DEG`]).
//! - A nearly flat scene (its bounding box's thinnest side at most
//!   [`FLAT`] of its longest) is seen face-on from its front side: along
//!   the thin axis, from the side its triangles face (area-weighted, by
//!   their shading normals where the file gives them; within 1 % of a
//!   tie, from the positive side, as glTF's front is +Z).
//! - With a 45° vertical field of view, the camera stands back until the
//!   projected corners of the scene's bounding box span [`FILL`] of the
//!   frame's limiting dimension, and moves sideways until they are centred.

use std::path::Path;

use glam::DVec3;

use crate::scene::{Camera, Mesh, Object, Projection, Shape};
use crate::SceneError;

/// The share of the limiting dimension the bounding box spans.
pub const FILL: f64 = 0.9;
/// Degrees to the right of the front (+Z) the camera looks from.
pub const AZIMUTH_DEG: f64 = 30.0;
/// Degrees above the horizon the camera looks from.
pub const ELEVATION_DEG: f64 = 20.0;
/// Thinnest over longest side of the bounding box, at most, of a flat scene.
pub const FLAT: f64 = 0.05;
/// The vertical field of view, degrees.
pub const VFOV_DEG: f64 = 45.0;

/// The framing camera of these objects for a `width` × `height` image.
pub(super) fn camera(
    path: &Path,
    objects: &[Object],
    width: u32,
    height: u32,
) -> Result<Camera, SceneError> {
    let meshes: Vec<&Mesh> = objects
        .iter()
        .filter_map(|o| match &o.shape {
            Shape::Mesh(m) => Some(m),
            _ => None,
        })
        .collect();
    let (mut lo, mut hi) = meshes
        .iter()
        .filter_map(|m| m.bounds())
        .reduce(|(lo, hi), (l, h)| (lo.min(l), hi.max(h)))
        .unwrap_or((DVec3::ZERO, DVec3::ZERO));
    // A single point has no size; frame a unit box around it.
    if (hi - lo).max_element() <= 0.0 {
        (lo, hi) = (lo - 0.5, hi + 0.5);
    }
    let size = hi - lo;
    let centre = (lo + hi) * 0.5;
    let thin = size.min_position();
    let (from, up) = if size[thin] <= FLAT * size.max_element() {
        let mut axis = DVec3::ZERO;
        let (facing, area) = facing(&meshes, thin);
        // Within 1 % of a tie (a chart with parts facing either way), the
        // positive side: glTF's front is +Z.
        axis[thin] = if facing < -0.01 * area { -1.0 } else { 1.0 };
        // Seen from above or below, the far side of the floor is up.
        let up = if thin == 1 { DVec3::NEG_Z } else { DVec3::Y };
        (axis, up)
    } else {
        let (az, el) = (AZIMUTH_DEG.to_radians(), ELEVATION_DEG.to_radians());
        let from = DVec3::new(az.sin() * el.cos(), el.sin(), az.cos() * el.cos());
        (from, DVec3::Y)
    };
    let orientation = Camera::look_at(centre + from, centre, up)
        .map_err(|e| SceneError::new(path, "", format!("cannot place a framing camera: {e:?}")))?;
    let (right, upv) = (orientation.col(0), orientation.col(1));
    let tan_v = (VFOV_DEG * 0.5).to_radians().tan();
    let tan_h = tan_v * f64::from(width) / f64::from(height);
    let corners: Vec<DVec3> = (0..8)
        .map(|k| {
            let pick = |bit: usize, a: f64, b: f64| if k >> bit & 1 == 0 { a } else { b };
            DVec3::new(
                pick(0, lo.x, hi.x),
                pick(1, lo.y, hi.y),
                pick(2, lo.z, hi.z),
            )
        })
        .collect();
    // The corners' extent in the image plane, as [min x, max x, min y, max
    // y] over the half extents (−1..1 spans the frame), from `eye`.
    let extent = |eye: DVec3| {
        let mut e = [f64::MAX, f64::MIN, f64::MAX, f64::MIN];
        for &c in &corners {
            let v = c - eye;
            let depth = v.dot(-from);
            let (x, y) = (v.dot(right) / depth / tan_h, v.dot(upv) / depth / tan_v);
            e = [e[0].min(x), e[1].max(x), e[2].min(y), e[3].max(y)];
        }
        e
    };
    let fill = |e: [f64; 4]| ((e[1] - e[0]) * 0.5).max((e[3] - e[2]) * 0.5);
    // Every corner in front of the camera from this distance on.
    let nearest = corners
        .iter()
        .map(|c| (*c - centre).dot(from))
        .fold(f64::MIN, f64::max);
    let mut shift = DVec3::ZERO;
    let mut eye = centre;
    let mid = |e: [f64; 4]| ((e[0] + e[1]) * 0.5, (e[2] + e[3]) * 0.5);
    for _ in 0..6 {
        // The fill shrinks as the camera backs away: bisect the distance.
        let at = |d: f64| centre + shift + from * d;
        let (mut near, mut far) = (nearest * (1.0 + 1e-9) + 1e-12, nearest.abs() + 1.0);
        while fill(extent(at(far))) > FILL {
            far *= 2.0;
        }
        for _ in 0..100 {
            let d = 0.5 * (near + far);
            if fill(extent(at(d))) > FILL {
                near = d;
            } else {
                far = d;
            }
        }
        eye = at(far);
        // Centre the box: its offset in the image is piecewise linear in
        // a sideways move of the camera; Newton's steps find the move.
        let h = 1e-6 * size.length();
        for _ in 0..4 {
            let (mx, my) = mid(extent(eye));
            let kx = (mid(extent(eye + right * h)).0 - mx) / h;
            let ky = (mid(extent(eye + upv * h)).1 - my) / h;
            let step = right * if kx != 0.0 { mx / kx } else { 0.0 }
                + upv * if ky != 0.0 { my / ky } else { 0.0 };
            shift -= step;
            eye -= step;
        }
    }
    Ok(Camera {
        position: eye,
        orientation,
        projection: Projection::Perspective { vfov_deg: VFOV_DEG },
        width,
        height,
    })
}

/// Which way a flat scene faces along `axis`, and its area: the sum over
/// its triangles of their areas times their normals' component along it,
/// the file's shading normals (NORMAL) where it has them, which say which
/// side is meant to be seen, else the winding's.
fn facing(meshes: &[&Mesh], axis: usize) -> (f64, f64) {
    let (mut facing, mut area) = (0.0, 0.0);
    for m in meshes {
        for t in &m.indices {
            let [a, b, c] = t.map(|i| m.positions[i as usize]);
            let geometric = (b - a).cross(c - a) * 0.5;
            area += geometric.length();
            facing += match &m.normals {
                Some(n) => {
                    let mean: f64 = t.iter().map(|&i| n[i as usize][axis]).sum::<f64>() / 3.0;
                    geometric.length() * mean
                }
                None => geometric[axis],
            };
        }
    }
    (facing, area)
}
