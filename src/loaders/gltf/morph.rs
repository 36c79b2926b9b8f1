//! Static morph target weights: a primitive's POSITION and NORMAL plus
//! each target's displacement times its weight (glTF 2.0 §3.7.2.2, "Morph
//! Targets"), with the weights of the node (`node.weights`) or else of
//! the mesh (`mesh.weights`), missing ones 0. Animated weights are not
//! applied: the file's static pose.

use gltf::accessor::Dimensions;

use super::quantization::Attribute;
use super::{Reader, Result};

/// The static weights of a node's mesh: the node's if it has them, else
/// the mesh's, else none (all targets weigh 0).
pub(super) fn weights(node: &gltf::Node, mesh: &gltf::Mesh) -> Vec<f64> {
    node.weights()
        .or(mesh.weights())
        .unwrap_or_default()
        .iter()
        .map(|&w| f64::from(w))
        .collect()
}

impl Reader<'_> {
    /// Adds the weighted POSITION (`normal` false) or NORMAL displacements
    /// of `prim`'s morph targets to `raw`, its local `count` × 3 values;
    /// `field` is the primitive's.
    pub(super) fn morph(
        &self,
        prim: &gltf::Primitive,
        weights: &[f64],
        raw: &mut [f64],
        normal: bool,
        field: &str,
    ) -> Result<()> {
        let count = raw.len() / 3;
        for (t, target) in prim.morph_targets().enumerate() {
            let w = weights.get(t).copied().unwrap_or(0.0);
            if !w.is_finite() {
                return self.fail(format!("{field}.targets[{t}]"), "weight must be finite");
            }
            let (acc, name, kind) = match normal {
                false => (target.positions(), "POSITION", Attribute::PositionDelta),
                true => (target.normals(), "NORMAL", Attribute::NormalDelta),
            };
            let Some(acc) = acc.filter(|_| w != 0.0) else {
                continue;
            };
            let at = format!("{field}.targets[{t}].{name}");
            let delta = self.attribute(&acc, &at, Dimensions::Vec3, kind)?;
            self.check_attribute(&acc, &delta, 3, count, &at)?;
            for (x, d) in raw.iter_mut().zip(&delta) {
                *x += w * d;
            }
        }
        Ok(())
    }
}
