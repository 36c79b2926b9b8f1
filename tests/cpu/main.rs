//! The tests of library code that needs no Vulkan device and starts no
//! process: the BRDFs' known truths and the glTF and WGSL-shader loaders,
//! and textures in JSON scenes; and the docs against the repository (`docs`:
//! the paths, binaries and test modules that README.md and docs/*.md name).
//! One test binary, one module per concept.
//!
//! One concept: `cargo test --test cpu gltf_loader::` (docs/tests.md).

#[path = "../base64/mod.rs"]
mod base64;
mod brdf;
mod docs;
mod gltf_draco;
mod gltf_extensions;
mod gltf_ktx2;
mod gltf_loader;
mod json_textures;
mod kinds;
mod wgsl_shaders;
