//! The scene's validation errors of a glTF file, named by the file's own
//! fields.
//!
//! [`crate::scene::Scene::validate`] names the scene penumbra built
//! (`objects[3].uvs[0][17]`, `shaders[0].textures.diffuse.transform`),
//! which a glTF file does not have. The loader checks what it can itself
//! while it reads; whatever still reaches the validation is renamed here:
//! an object's attribute becomes its primitive's accessor
//! (`meshes[0].primitives[1].attributes.TEXCOORD_0`, the vertex in the
//! message), its maps and its shader the primitive's material
//! (`materials[2]`), with penumbra's own name kept in the message.

/// Where a scene object came from: its primitive's field
/// (`meshes[0].primitives[1]`) and material index.
#[derive(Clone, Debug)]
pub(super) struct Origin {
    /// `meshes[M].primitives[P]`.
    pub primitive: String,
    /// The primitive's `material`, if it has one.
    pub material: Option<usize>,
}

/// The file's field and the message for a validation error at the scene's
/// `field`, for objects from `origins` whose shader indices are `shaders`.
pub(super) fn file_field(
    field: &str,
    message: &str,
    origins: &[Origin],
    shaders: &[usize],
) -> (String, String) {
    let unchanged = || (field.to_string(), message.to_string());
    let penumbras = |at: &str| format!("{message} (penumbra's {at})");
    if let Some((i, rest)) = indexed(field, "objects") {
        let Some(origin) = origins.get(i) else {
            return unchanged();
        };
        if let Some((attribute, vertex)) = attribute(rest) {
            let field = format!("{}.{attribute}", origin.primitive);
            let mut message = match vertex {
                Some(k) => format!("vertex {k}: {message}"),
                None => message.to_string(),
            };
            if attribute.ends_with("POSITION") {
                message += " (in world space: with its nodes' transforms)";
            }
            return (field, message);
        }
        return match (rest.strip_prefix("maps"), origin.material) {
            (Some(_), Some(m)) => (format!("materials[{m}]"), penumbras(field)),
            _ => (origin.primitive.clone(), penumbras(field)),
        };
    }
    if let Some((s, _)) = indexed(field, "shaders") {
        let material = shaders
            .iter()
            .zip(origins)
            .find(|(&shader, _)| shader == s)
            .and_then(|(_, o)| o.material);
        if let Some(m) = material {
            return (format!("materials[{m}]"), penumbras(field));
        }
    }
    unchanged()
}

/// `name[i].rest` as `(i, rest)`.
fn indexed<'f>(field: &'f str, name: &str) -> Option<(usize, &'f str)> {
    let rest = field.strip_prefix(name)?.strip_prefix('[')?;
    let (i, rest) = rest.split_once(']')?;
    Some((i.parse().ok()?, rest.strip_prefix('.').unwrap_or(rest)))
}

/// A mesh attribute of the scene (`positions[5]`, `uvs[1][5]`,
/// `indices[2]`) as the primitive's field and the vertex (or triangle) it
/// names.
fn attribute(rest: &str) -> Option<(String, Option<usize>)> {
    let element =
        |s: &str| -> Option<usize> { s.strip_prefix('[')?.strip_suffix(']')?.parse().ok() };
    let (head, tail) = match rest.find('[') {
        Some(at) => rest.split_at(at),
        None => (rest, ""),
    };
    let named = |name: &str| Some((format!("attributes.{name}"), element(tail)));
    match head {
        "positions" => named("POSITION"),
        "normals" => named("NORMAL"),
        "colours" => named("COLOR_0"),
        "tangents" => named("TANGENT"),
        "indices" => Some(("indices".to_string(), None)),
        "uvs" => {
            let (set, vertex) = tail.strip_prefix('[')?.split_once(']')?;
            let set: usize = set.parse().ok()?;
            Some((format!("attributes.TEXCOORD_{set}"), element(vertex)))
        }
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn origins() -> Vec<Origin> {
        vec![
            Origin {
                primitive: "meshes[0].primitives[0]".into(),
                material: None,
            },
            Origin {
                primitive: "meshes[2].primitives[1]".into(),
                material: Some(3),
            },
        ]
    }

    #[test]
    fn attributes_become_the_primitives_accessors() {
        let o = origins();
        let (f, m) = file_field("objects[1].uvs[1][17]", "must be finite", &o, &[0, 1]);
        assert_eq!(f, "meshes[2].primitives[1].attributes.TEXCOORD_1");
        assert_eq!(m, "vertex 17: must be finite");
        let (f, _) = file_field("objects[0].positions[4]", "too far", &o, &[0, 1]);
        assert_eq!(f, "meshes[0].primitives[0].attributes.POSITION");
        let (f, m) = file_field("objects[0].normals", "need one", &o, &[0, 1]);
        assert_eq!(
            (f.as_str(), m.as_str()),
            ("meshes[0].primitives[0].attributes.NORMAL", "need one")
        );
    }

    #[test]
    fn maps_and_shaders_become_the_material() {
        let o = origins();
        let (f, m) = file_field("objects[1].maps.normal.scale", "bad", &o, &[0, 1]);
        assert_eq!(f, "materials[3]");
        assert_eq!(m, "bad (penumbra's objects[1].maps.normal.scale)");
        let (f, _) = file_field("shaders[1].textures.diffuse.transform", "bad", &o, &[0, 1]);
        assert_eq!(f, "materials[3]");
        // A shader no object with a material uses, and other fields, stay.
        let (f, _) = file_field("shaders[0].diffuse", "bad", &o, &[0, 1]);
        assert_eq!(f, "shaders[0].diffuse");
        let (f, _) = file_field("camera.width", "bad", &o, &[0, 1]);
        assert_eq!(f, "camera.width");
    }
}
