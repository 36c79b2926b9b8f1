//! glTF 2.0's metallic-roughness material (`shaders/shading/metallic_roughness.wgsl`):
//! its parameters and its BRDF in `f64`, as the glTF 2.0 specification's
//! Appendix B ("BRDF Implementation") defines it.
//!
//! ```text
//! α = roughness²
//! D = α²·χ⁺(n·h) / (π·((n·h)²(α²−1)+1)²)
//! V = χ⁺(h·l)·χ⁺(h·v) / ((|n·l| + √(α²+(1−α²)(n·l)²))·(|n·v| + √(α²+(1−α²)(n·v)²)))
//! metal      = V·D·(c + (1−c)(1−|v·h|)⁵)
//! dielectric = mix(c/π, V·D, 0.04 + 0.96(1−|v·h|)⁵)
//! f          = mix(dielectric, metal, metallic)
//! ```
//!
//! A light sample adds `f·(colour × intensity × falloff)·(n·l)`
//! (KHR_lights_punctual's units). Where the formulas divide zero by zero
//! (`D` at `α = 0`, `V` with both denominator sums 0) the value is 0, as in
//! the shader.

use glam::{DVec3, Vec3};

use crate::scene::texture::TextureRef;

/// The parameters of glTF's `pbrMetallicRoughness`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MetallicRoughness {
    /// Linear base colour `c` (glTF's `baseColorFactor.rgb`); each channel in `[0, 1]`.
    pub base_colour: Vec3,
    /// `metallicFactor`, in `[0, 1]`.
    pub metallic: f32,
    /// `roughnessFactor`, in `[0, 1]`.
    pub roughness: f32,
    /// Textures that multiply the factors.
    pub textures: MetallicRoughnessTextures,
}

/// The textures of [`MetallicRoughness`]; `None` leaves a factor as it is.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MetallicRoughnessTextures {
    /// sRGB colour: multiplies the base colour (with the vertex colour).
    pub base_colour: Option<TextureRef>,
    /// Linear: its B channel multiplies metallic, its G channel roughness.
    pub metallic_roughness: Option<TextureRef>,
}

/// The BRDF `f(l, v)` split into the part that takes a light's diffuse
/// colour (the dielectric's `c/π` term) and the part that takes its
/// specular colour (the rest). `n`, `l`, `v` are unit vectors; `c` the base
/// colour.
pub fn brdf(
    n: DVec3,
    l: DVec3,
    v: DVec3,
    c: DVec3,
    metallic: f64,
    roughness: f64,
) -> (DVec3, DVec3) {
    let pi = std::f64::consts::PI;
    let (specular, vh) = microfacet(n, l, v, roughness);
    let schlick = (1.0 - vh.abs()).powi(5);
    let metal = specular * (c + (DVec3::ONE - c) * schlick);
    let fresnel = 0.04 + 0.96 * schlick;
    let diffuse_part = (1.0 - metallic) * (1.0 - fresnel) * c / pi;
    let specular_part = (1.0 - metallic) * fresnel * specular + metallic * metal;
    (diffuse_part, specular_part)
}

/// Appendix B's specular microfacet term `V·D` at `roughness` (`α =
/// roughness²`), and `v·h`.
pub fn microfacet(n: DVec3, l: DVec3, v: DVec3, roughness: f64) -> (f64, f64) {
    let pi = std::f64::consts::PI;
    let (nl, nv) = (n.dot(l), n.dot(v));
    let h = (l + v).normalize_or_zero();
    let (nh, vh, lh) = (n.dot(h), v.dot(h), l.dot(h));
    let chi = |x: f64| if x > 0.0 { 1.0 } else { 0.0 };
    let alpha = roughness * roughness;
    let a2 = alpha * alpha;
    let dd = nh * nh * (a2 - 1.0) + 1.0;
    let d = if a2 > 0.0 && nh > 0.0 {
        a2 / (pi * dd * dd)
    } else {
        0.0
    };
    let vis_l = nl.abs() + (a2 + (1.0 - a2) * nl * nl).sqrt();
    let vis_v = nv.abs() + (a2 + (1.0 - a2) * nv * nv).sqrt();
    let vis = if vis_l * vis_v > 0.0 {
        chi(lh) * chi(vh) / (vis_l * vis_v)
    } else {
        0.0
    };
    (vis * d, vh)
}
