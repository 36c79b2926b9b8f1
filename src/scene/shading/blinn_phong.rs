//! Blinn-Phong: Phong's coefficients with the half-vector lobe.

use glam::DVec3;

/// Blinn's specular lobe `max(0, h·n)^n_s` with `h = normalize(l + v)`; zero
/// where `l·n ≤ 0`. All vectors unit length.
pub fn lobe(n: DVec3, l: DVec3, v: DVec3, shininess: f64) -> f64 {
    if l.dot(n) <= 0.0 {
        return 0.0;
    }
    let h = (l + v).normalize_or_zero();
    h.dot(n).max(0.0).powf(shininess)
}
