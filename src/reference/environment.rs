//! The environment's directions as `shaders/environment.wgsl` draws them, in
//! `f64`: one sample of [`ENVIRONMENT_MIXTURE`] (uniform sphere, cosine
//! around the normal, Phong lobes around the eye's mirror direction),
//! weighted by the radiance over the mixture's density (one-sample multiple
//! importance sampling; docs/materials.md, "Environment"). The same
//! estimator as the GPU's, so the two agree sample by sample up to `f32`.

use std::f64::consts::{PI, TAU};

use glam::DVec3;

use super::lights::LightSample;
use crate::scene::{EnvironmentMixture, ENVIRONMENT_MIXTURE};

/// A unit vector at polar angle θ (`sin²θ = s2`) and azimuth `2π·u` around
/// the unit axis `a` (the orthonormal frame of Duff et al. 2017, "Building
/// an Orthonormal Basis, Revisited").
fn around(a: DVec3, s2: f64, u: f64) -> DVec3 {
    let sign = if a.z >= 0.0 { 1.0 } else { -1.0 };
    let q = -1.0 / (sign + a.z);
    let t = a.x * a.y * q;
    let b1 = DVec3::new(1.0 + sign * a.x * a.x * q, sign * t, -sign * a.x);
    let b2 = DVec3::new(t, sign + a.y * a.y * q, -a.y);
    let (sin_t, cos_t) = (s2.max(0.0).sqrt(), (1.0 - s2).max(0.0).sqrt());
    let phi = TAU * u;
    (cos_t * a + sin_t * (phi.cos() * b1 + phi.sin() * b2)).normalize()
}

/// The normalised Phong lobe `(e+1)/(2π)·cos^e` around `r` at `w`, with
/// `cos^e = exp(e/2 · ln(1 − sin²))` and `sin² = |r × w|²`.
fn phong_pdf(r: DVec3, w: DVec3, e: f64) -> f64 {
    if r.dot(w) <= 0.0 {
        return 0.0;
    }
    let s2 = r.cross(w).length_squared().min(1.0);
    (e + 1.0) / TAU * (0.5 * e * (-s2).ln_1p()).exp()
}

/// The mixture's density at `w` for normal `n` and mirror direction `r`.
pub fn pdf(m: &EnvironmentMixture, n: DVec3, r: DVec3, w: DVec3) -> f64 {
    let lobes: f64 = (0..m.lobes).map(|k| phong_pdf(r, w, m.exponent(k))).sum();
    m.uniform / (4.0 * PI) + m.cosine * n.dot(w).max(0.0) / PI + m.lobe_weight() * lobes
}

/// The mirror direction of the eye direction `v` about the normal `n`.
pub fn mirror(n: DVec3, v: DVec3) -> DVec3 {
    (2.0 * n.dot(v) * n - v).normalize()
}

/// How the reference treats the environment's samples: the mixture they
/// are drawn from (the GPU's is [`ENVIRONMENT_MIXTURE`]; uniform-only, for
/// instance, is the estimator before it) and whether they cast shadow rays
/// (the GPU's never do). For measurements: `tools/measure/environment_bench.rs`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Options {
    /// The mixture the directions are drawn from.
    pub mixture: EnvironmentMixture,
    /// Trace each sample with a shadow ray to infinity.
    pub shadowed: bool,
}

impl Default for Options {
    fn default() -> Options {
        Options {
            mixture: ENVIRONMENT_MIXTURE,
            shadowed: false,
        }
    }
}

/// Sample `uv` of an environment of radiance `radiance(ω)` (the gradient,
/// without the colours) drawn from mixture `m` with `samples` directions
/// per pass, at a point with unit shading normal `n` seen from the unit
/// direction `v`.
pub fn sample(
    m: &EnvironmentMixture,
    radiance: impl Fn(DVec3) -> f64,
    samples: u32,
    n: DVec3,
    v: DVec3,
    uv: [f64; 2],
) -> LightSample {
    let r = mirror(n, v);
    let (wu, wc, wl) = (m.uniform, m.cosine, m.lobe_weight());
    let w = if uv[0] < wu {
        let z = 1.0 - 2.0 * (uv[0] / wu);
        let s = (1.0 - z * z).max(0.0).sqrt();
        let phi = TAU * uv[1];
        DVec3::new(s * phi.cos(), s * phi.sin(), z)
    } else if uv[0] < wu + wc {
        around(n, ((uv[0] - wu) / wc).min(1.0), uv[1])
    } else {
        // Phong lobe k: sin²θ = −expm1(2/(e+1) · ln(1 − u)).
        let t = (uv[0] - wu - wc) / wl;
        let k = (t as u32).min(m.lobes - 1);
        let u = (t - f64::from(k)).min(1.0 - f64::EPSILON);
        let e = m.exponent(k);
        around(r, -(2.0 / (e + 1.0) * (-u).ln_1p()).exp_m1(), uv[1])
    };
    LightSample {
        to_light: w,
        distance: 0.0,
        falloff: radiance(w) / (pdf(m, n, r, w) * f64::from(samples)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The mixture's density integrates to 1 over the sphere (midpoint rule
    /// in (cos θ, φ) about the pole r, fine enough for the 2^20 lobe near it).
    #[test]
    fn the_mixture_density_integrates_to_one() {
        let m = ENVIRONMENT_MIXTURE;
        let n = DVec3::new(0.3, 0.9, 0.1).normalize();
        let v = DVec3::new(-0.5, 0.7, 0.2).normalize();
        let r = mirror(n, v);
        // Cells in y = 1 − cos θ about r on a geometric grid (ratio 1.02
        // from 10⁻¹², with [0, 10⁻¹²] first), which resolves every lobe;
        // 256 azimuths for the cosine lobe about n.
        let w0 = around(r, 1.0, 0.0);
        let (b1, b2) = (w0, r.cross(w0));
        let mut edges = vec![0.0, 1e-12];
        while *edges.last().unwrap() < 2.0 {
            let next = (edges.last().unwrap() * 1.02f64).min(2.0);
            edges.push(next);
        }
        let azimuths = 256;
        let mut total = 0.0;
        for cell in edges.windows(2) {
            let c = 1.0 - 0.5 * (cell[0] + cell[1]);
            let s = (1.0 - c * c).max(0.0).sqrt();
            for j in 0..azimuths {
                let phi = TAU * (j as f64 + 0.5) / azimuths as f64;
                let w = c * r + s * (phi.cos() * b1 + phi.sin() * b2);
                total += pdf(&m, n, r, w) * (cell[1] - cell[0]) * TAU / azimuths as f64;
            }
        }
        assert!((total - 1.0).abs() < 2e-3, "{total}");
    }

    /// Each lobe's samples fall where its density says: the mean of cos θ
    /// about r of lobe k's samples is (e+1)/(e+2), a fact of the density
    /// (e+1)/(2π)·cos^e, computed here from the formula, not the code.
    #[test]
    fn phong_lobe_samples_follow_their_density() {
        let m = ENVIRONMENT_MIXTURE;
        let r = DVec3::new(0.2, -0.4, 0.9).normalize();
        for k in 0..m.lobes {
            let e = m.exponent(k);
            let count = 4096;
            let mut mean_one_minus = 0.0;
            for i in 0..count {
                let u = (i as f64 + 0.5) / count as f64;
                let s2 = -(2.0 / (e + 1.0) * (-u).ln_1p()).exp_m1();
                let w = around(r, s2, 0.37);
                // 1 − cos from sin², precise near the pole.
                let s2w = r.cross(w).length_squared();
                mean_one_minus += s2w / (1.0 + (1.0 - s2w).sqrt());
            }
            mean_one_minus /= count as f64;
            let want = 1.0 / (e + 2.0);
            assert!(
                (mean_one_minus - want).abs() < 1e-3 * want,
                "lobe {k}: {mean_one_minus} vs {want}"
            );
        }
    }
}
