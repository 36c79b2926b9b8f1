//! The Phong reflection model's coefficients (shared with Blinn-Phong).

use glam::Vec3;

/// Ambient, diffuse and specular reflectances and the shininess exponent.
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
