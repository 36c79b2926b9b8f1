//! glTF's KHR_materials_pbrSpecularGlossiness material
//! (`shaders/shading/specular_glossiness.wgsl`): its parameters and its
//! BRDF in `f64`. The extension defines the BRDF inputs
//!
//! ```text
//! c_diff = diffuse.rgb·(1 − max(specular.r, specular.g, specular.b))
//! F0     = specular
//! α      = (1 − glossiness)²
//! ```
//!
//! and refers to the glTF 2.0 specification's Appendix B for the BRDF:
//! `f = (1 − F)·c_diff/π + F·V·D`, `F = F0 + (1 − F0)(1 − |v·h|)⁵`, with D
//! and V of [`super::metallic_roughness`].

use glam::{DVec3, Vec3};

use crate::scene::texture::TextureRef;

/// The parameters of KHR_materials_pbrSpecularGlossiness.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpecularGlossiness {
    /// `diffuseFactor.rgb`, linear.
    pub diffuse: Vec3,
    /// `specularFactor`, linear: F0.
    pub specular: Vec3,
    /// `glossinessFactor`, in `[0, 1]`.
    pub glossiness: f32,
    /// Textures that multiply the factors.
    pub textures: SpecularGlossinessTextures,
}

/// The textures of [`SpecularGlossiness`]; `None` leaves a factor as it is.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SpecularGlossinessTextures {
    /// sRGB colour: multiplies the diffuse factor (with the vertex colour).
    pub diffuse: Option<TextureRef>,
    /// sRGB RGB multiplies the specular factor, linear A the glossiness.
    pub specular_glossiness: Option<TextureRef>,
}

/// The BRDF split as [`super::metallic_roughness::brdf`]: the part that
/// takes a light's diffuse colour and the part that takes its specular one.
pub fn brdf(
    n: DVec3,
    l: DVec3,
    v: DVec3,
    diffuse: DVec3,
    specular: DVec3,
    glossiness: f64,
) -> (DVec3, DVec3) {
    let roughness = 1.0 - glossiness;
    let (vd, vh) = super::metallic_roughness::microfacet(n, l, v, roughness);
    let f = specular + (DVec3::ONE - specular) * (1.0 - vh.abs()).powi(5);
    let c_diff = diffuse * (1.0 - specular.max_element());
    let diffuse_part = (DVec3::ONE - f) * c_diff / std::f64::consts::PI;
    (diffuse_part, f * vd)
}
