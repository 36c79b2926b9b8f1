//! Shading models ("shaders" in the seminar): Phong, Blinn-Phong, glTF's
//! metallic-roughness BRDF ([`metallic_roughness`]), the 3D
//! checkerboard made of two sub-shaders, and shaders written as WGSL files
//! ([`wgsl`]; what such a file declares is read by [`crate::wgsl`]). The
//! GPU versions of the built-in ones live in `shaders/shading/` under the
//! same names.
//!
//! For each light the colour at a point is
//! `k_a·I_a + [light visible]·(k_d·I_d·max(0, l·n) + k_s·I_s·max(0, r·v)^n_s)`
//! (Blinn-Phong: `h·n` instead of `r·v`), where the specular term is zero
//! wherever `l·n ≤ 0`.

pub mod blinn_phong;
pub mod checker;
pub mod metallic_roughness;
pub mod phong;
pub mod specular_glossiness;
pub mod wgsl;

pub use checker::Checker;
pub use metallic_roughness::{MetallicRoughness, MetallicRoughnessTextures};
pub use phong::{Phong, PhongTextures};
pub use specular_glossiness::{SpecularGlossiness, SpecularGlossinessTextures};
pub use wgsl::{ParamField, ParamType, ParamValue, WgslShader};

/// Index into [`crate::scene::Scene::shaders`].
pub type ShaderId = usize;

/// One shading model.
#[derive(Clone, Debug, PartialEq)]
pub enum Shader {
    /// Phong: specular lobe around the mirror direction `r`.
    Phong(Phong),
    /// Blinn-Phong: specular lobe of the half vector `h` around `n`.
    BlinnPhong(Phong),
    /// glTF 2.0's metallic-roughness BRDF.
    MetallicRoughness(MetallicRoughness),
    /// glTF's KHR_materials_pbrSpecularGlossiness.
    SpecularGlossiness(SpecularGlossiness),
    /// 3D checkerboard of two sub-shaders.
    Checker(Checker),
    /// A shader written as a WGSL file, with its `Params` values.
    Wgsl(WgslShader),
}

impl Shader {
    /// The shader's `"type"` in a JSON scene (scenes/README.md): one
    /// exhaustive `match`, and [`Shader::TYPES`] lists them.
    pub fn type_name(&self) -> &'static str {
        match self {
            Shader::Phong(_) => "phong",
            Shader::BlinnPhong(_) => "blinn_phong",
            Shader::MetallicRoughness(_) => "metallic_roughness",
            Shader::SpecularGlossiness(_) => "specular_glossiness",
            Shader::Checker(_) => "checker",
            Shader::Wgsl(_) => "wgsl",
        }
    }

    /// Every kind's [`Shader::type_name`], for the tests that each kind is
    /// covered (tests/cpu/kinds.rs).
    pub const TYPES: [&'static str; 6] = [
        "phong",
        "blinn_phong",
        "metallic_roughness",
        "specular_glossiness",
        "checker",
        "wgsl",
    ];
}
