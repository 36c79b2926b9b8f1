//! The glTF extensions penumbra reads for geometry and images, checked in
//! `extensionsRequired` before the `gltf` crate's own validation (which
//! only says "Unsupported" or, for a file it cannot read without the
//! extension, "Missing data" on some field): an unknown required
//! extension is named first.
//!
//! The material extensions penumbra applies are
//! [`super::material::SUPPORTED_EXTENSIONS`]; this module adds the ones the
//! geometry and image readers apply themselves, which the `gltf` crate does
//! not know (so they are taken out of `extensionsRequired` before its
//! validation).

use gltf::json::Root;

/// Extensions applied by the geometry reader (modules `quantization`,
/// `meshopt`, `draco` and `instancing`, and the node walk).
pub(super) const GEOMETRY: &[&str] = &[
    "KHR_mesh_quantization",
    "EXT_meshopt_compression",
    "EXT_mesh_gpu_instancing",
    "KHR_draco_mesh_compression",
];

/// Extensions applied by the image reader (a texture's KTX2 image,
/// [`crate::loaders::ktx2`]), which the `gltf` crate does not know either.
pub(super) const IMAGES: &[&str] = &[super::material::BASISU];

/// Whether penumbra applies extension `name`.
pub(super) fn supported(name: &str) -> bool {
    GEOMETRY.contains(&name)
        || IMAGES.contains(&name)
        || super::material::SUPPORTED_EXTENSIONS.contains(&name)
}

/// The first required extension penumbra cannot honour, as (field,
/// message); called before the `gltf` crate validates the document.
pub(super) fn check_required(root: &Root) -> Option<(String, String)> {
    for (i, name) in root.extensions_required.iter().enumerate() {
        let field = format!("extensionsRequired[{i}]");
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

/// Takes the extensions of [`GEOMETRY`] and [`IMAGES`] out of
/// `extensionsRequired`: the `gltf` crate would report them unsupported,
/// and this reader applies them.
pub(super) fn hide_geometry(root: &mut Root) {
    root.extensions_required
        .retain(|name| !GEOMETRY.contains(&name.as_str()) && !IMAGES.contains(&name.as_str()));
}
