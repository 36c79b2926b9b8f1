//! EXT_mesh_gpu_instancing: a node's mesh drawn once per instance, each
//! placed by the node's world transform times the instance's own
//! translation, rotation and scale (Khronos glTF extension registry,
//! `EXT_mesh_gpu_instancing/README.md`: attributes TRANSLATION and SCALE
//! VEC3, ROTATION a VEC4 quaternion, all with the same count; the instance
//! transform is T · R · S, applied before the node's). penumbra expands
//! the instances into meshes of their own, charged against the memory
//! budget before any is read.

use glam::{DMat4, DQuat, DVec3, DVec4};
use gltf::accessor::{Accessor, Dimensions};

use super::quantization::Attribute;
use super::{Reader, Result};

/// The name of the extension, as in the file.
pub(super) const NAME: &str = "EXT_mesh_gpu_instancing";

/// The attributes, their shape and their kind of value.
const ATTRIBUTES: [(&str, Dimensions, Attribute); 3] = [
    ("TRANSLATION", Dimensions::Vec3, Attribute::InstanceVector),
    ("ROTATION", Dimensions::Vec4, Attribute::InstanceRotation),
    ("SCALE", Dimensions::Vec3, Attribute::InstanceVector),
];

impl Reader<'_> {
    /// The node's instancing accessors (one per attribute, `None` where
    /// absent) and their common count; `None` for a node without the
    /// extension.
    #[allow(clippy::type_complexity)]
    fn instancing(&self, node: &gltf::Node) -> Result<Option<([Option<Accessor<'_>>; 3], usize)>> {
        let ext = &self.raw_json()["nodes"][node.index()]["extensions"][NAME];
        if ext.is_null() {
            return Ok(None);
        }
        let at = format!("nodes[{}].extensions.{NAME}.attributes", node.index());
        let mut accessors = [None, None, None];
        let mut count = None;
        for (k, (name, _, _)) in ATTRIBUTES.iter().enumerate() {
            let v = &ext["attributes"][name];
            if v.is_null() {
                continue;
            }
            let field = format!("{at}.{name}");
            let Some(acc) = v
                .as_u64()
                .and_then(|i| self.document.accessors().nth(usize::try_from(i).ok()?))
            else {
                return self.fail(field, format!("{v} is not an accessor of the file"));
            };
            if count.is_some_and(|c| c != acc.count()) {
                let message = format!(
                    "has {} instances, the other attributes {}",
                    acc.count(),
                    count.unwrap_or(0)
                );
                return self.fail(field, message);
            }
            count = Some(acc.count());
            accessors[k] = Some(acc);
        }
        let Some(count) = count else {
            return self.fail(at, "names none of TRANSLATION, ROTATION and SCALE");
        };
        Ok(Some((accessors, count)))
    }

    /// How many instances the node draws its mesh with; `None` without the
    /// extension. Reads no accessor data.
    pub(super) fn instance_count(&self, node: &gltf::Node) -> Result<Option<usize>> {
        Ok(self.instancing(node)?.map(|(_, count)| count))
    }

    /// Each instance's transform, local to the node; `None` without the
    /// extension.
    pub(super) fn instances(&self, node: &gltf::Node) -> Result<Option<Vec<DMat4>>> {
        let Some((accessors, count)) = self.instancing(node)? else {
            return Ok(None);
        };
        let at = format!("nodes[{}].extensions.{NAME}.attributes", node.index());
        let mut columns: [Option<Vec<f64>>; 3] = [None, None, None];
        for (k, acc) in accessors.iter().enumerate() {
            let Some(acc) = acc else { continue };
            let (name, dims, kind) = ATTRIBUTES[k];
            let field = format!("{at}.{name}");
            let raw = self.attribute(acc, &field, dims, kind)?;
            self.check_attribute(acc, &raw, dims.multiplicity(), count, &field)?;
            columns[k] = Some(raw);
        }
        let mut out = Vec::with_capacity(count);
        for i in 0..count {
            let v3 = |c: &Option<Vec<f64>>, d: DVec3| {
                c.as_ref()
                    .map_or(d, |c| DVec3::from_slice(&c[3 * i..3 * i + 3]))
            };
            let translation = v3(&columns[0], DVec3::ZERO);
            let scale = v3(&columns[2], DVec3::ONE);
            let rotation = match &columns[1] {
                Some(c) => {
                    let q = DVec4::from_slice(&c[4 * i..4 * i + 4]);
                    let Some(q) = q.try_normalize() else {
                        let field = format!("{at}.ROTATION");
                        return self.fail(field, format!("instance {i} is not a unit quaternion"));
                    };
                    DQuat::from_vec4(q)
                }
                None => DQuat::IDENTITY,
            };
            out.push(DMat4::from_scale_rotation_translation(
                scale,
                rotation,
                translation,
            ));
        }
        Ok(Some(out))
    }
}
