//! The Phong reflection model's coefficients (shared with Blinn-Phong).

use glam::Vec3;

use crate::scene::texture::TextureRef;

/// Ambient, diffuse and specular reflectances and the shininess exponent.
/// Each reflectance may be scaled by a texture ([`PhongTextures`]), and
/// the diffuse one by the surface's vertex colours, as glTF's base colour
/// is (`baseColorFactor × baseColorTexture × COLOR_0`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Phong {
    /// `k_a`, multiplies each light's ambient colour.
    pub ambient: Vec3,
    /// `k_d`, multiplies each light's diffuse colour and `max(0, l·n)`.
    pub diffuse: Vec3,
    /// `k_s`, multiplies each light's specular colour and the lobe.
    pub specular: Vec3,
    /// `n_s` ≥ 0, the lobe's exponent.
    pub shininess: f32,
    /// Textures that multiply the reflectances.
    pub textures: PhongTextures,
}

/// The textures (sRGB colour) that multiply [`Phong`]'s reflectances; `None`
/// leaves a reflectance as it is.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PhongTextures {
    /// Multiplies `k_a`.
    pub ambient: Option<TextureRef>,
    /// Multiplies `k_d` (glTF's base colour texture).
    pub diffuse: Option<TextureRef>,
    /// Multiplies `k_s`.
    pub specular: Option<TextureRef>,
}

/// Phong's specular lobe `max(0, r·v)^n_s` with `r` the mirror of `l` about
/// `n`; zero where `l·n ≤ 0`. All vectors unit length.
pub fn lobe(n: glam::DVec3, l: glam::DVec3, v: glam::DVec3, shininess: f64) -> f64 {
    let ln = l.dot(n);
    if ln <= 0.0 {
        return 0.0;
    }
    let r = 2.0 * ln * n - l;
    r.dot(v).max(0.0).powf(shininess)
}
