//! The glTF extensions penumbra reads for geometry, and those it refuses
//! with a way out, checked in `extensionsRequired` before the `gltf`
//! crate's own validation (which only says "Unsupported" or, for a file it
//! cannot read without the extension, "Missing data" on some field).
//!
//! The material extensions penumbra applies are
//! [`super::material::SUPPORTED_EXTENSIONS`]; this module adds the ones the
//! geometry reader applies itself, which the `gltf` crate does not know
//! (so they are taken out of `extensionsRequired` before its validation).

use gltf::json::Root;

/// Extensions applied by the geometry reader (modules `quantization`,
/// `meshopt` and `instancing`, and the node walk).
pub(super) const GEOMETRY: &[&str] = &[
    "KHR_mesh_quantization",
    "EXT_meshopt_compression",
    "EXT_mesh_gpu_instancing",
];

/// Extensions penumbra cannot decode (no well-kept decoder builds here),
/// each with what the user can do instead.
pub(super) const REFUSED: &[(&str, &str)] = &[
    (
        "KHR_draco_mesh_compression",
        "Draco-compressed meshes are not supported; use an uncompressed variant of the \
         file, or re-encode it without Draco with a glTF tool (e.g. gltf-transform or \
         Blender; EXT_meshopt_compression, as `gltfpack -c` writes, is supported)",
    ),
    (
        "KHR_texture_basisu",
        "KTX2/Basis Universal textures are not supported; use a PNG/JPEG variant of \
         the file, or convert its KTX2 images to PNG (e.g. KTX-Software's `ktx extract`) \
         and point the textures' `source` at them",
    ),
];

/// Whether penumbra applies extension `name`.
pub(super) fn supported(name: &str) -> bool {
    GEOMETRY.contains(&name) || super::material::SUPPORTED_EXTENSIONS.contains(&name)
}

/// The first required extension penumbra cannot honour, as (field,
/// message); called before the `gltf` crate validates the document.
pub(super) fn check_required(root: &Root) -> Option<(String, String)> {
    for (i, name) in root.extensions_required.iter().enumerate() {
        let field = format!("extensionsRequired[{i}]");
        if let Some((_, what_to_do)) = REFUSED.iter().find(|(n, _)| n == name) {
            return Some((field, format!("requires {name}: {what_to_do}")));
        }
        if !supported(name) {
            let message = format!(
                "requires extension {name}, which penumbra does not support; \
                 re-export the file without it"
            );
            return Some((field, message));
        }
    }
    None
}

/// Takes the extensions of [`GEOMETRY`] out of `extensionsRequired`: the
/// `gltf` crate would report them unsupported, and this reader applies them.
pub(super) fn hide_geometry(root: &mut Root) {
    root.extensions_required
        .retain(|name| !GEOMETRY.contains(&name.as_str()));
}
