//! BRDFs as functions `f(ω_i, ω_o)` on the hemisphere around the normal
//! `n = +Z`, and numerical checks of the three properties the seminar asks of
//! a BRDF: positivity, Helmholtz reciprocity and energy conservation.
//!
//! Conventions: both directions are unit vectors pointing *away* from the
//! surface, `ω_i` towards the light and `ω_o` towards the viewer; `θ` is the
//! angle from `n`, `φ` the azimuth. Reflected radiance is
//! `L_o(ω_o) = ∫ f(ω_i, ω_o) L_i(ω_i) cos θ_i dω_i`.
//!
//! # Which BRDF the seminar's shading formula is
//!
//! The renderer's built-in shading files (`shaders/shading/phong.wgsl`, and
//! `shaders/shading/blinn_phong.wgsl` for Blinn-Phong) add, per point light,
//!
//! ```text
//! colour = falloff · (k_d·I_d·max(0, l·n) + k_s·I_s·max(0, r·v)^n_s)     (Phong)
//! ```
//!
//! with `falloff = 1/d²` and `r` the mirror image of `l` about `n`
//! (Blinn-Phong uses `max(0, n·h)^n_s`). A point light of intensity `I` at
//! distance `d` is a delta in the incident radiance whose irradiance on a
//! surface facing it is `E⊥ = I/d²`, so the integral above collapses to
//! `L_o = f(l, v)·E⊥·cos θ_i`. Matching term by term (`l·n = cos θ_i`):
//!
//! ```text
//! f_seminar(l, v) = k_d + k_s·max(0, r·v)^n_s / cos θ_i
//! ```
//!
//! The specular term is
//! multiplied by the light but not by `cos θ_i`, so as a BRDF it carries a
//! `1/cos θ_i` — which is what breaks reciprocity (`f(ω_i, ω_o)/f(ω_o, ω_i) =
//! cos θ_o / cos θ_i`) and makes the reflected energy diverge at grazing
//! incidence. In the renderer's own units (`E⊥ = I/d²`, no `π` anywhere) the
//! diffuse part `k_d` is a Lambertian BRDF of albedo `π·k_d`; reading the light
//! intensity instead as `π ×` the irradiance it gives (the real-time graphics
//! convention, in which `k_d` is the albedo) divides the whole BRDF by `π`.
//! [`Units`] selects one of the two; the `1/cos θ_i` is there in both.
//!
//! Consequences, found by the lab: the seminar's form is not reciprocal for
//! any parameters, and does not conserve energy. In renderer units even its
//! albedo is too large (`a(0) = π·k_d + k_s·2π/(n+1)`); divided by `π` the
//! albedo `a(ω_o)` stays `≤ k_d + k_s·2/(n+1) ≤ 1`, but the reflectance
//! `R(ω_i)` (below) grows like `1/cos θ_i` towards grazing incidence, past 1
//! for every `k_s > 0` and `n`.
//!
//! # The models
//!
//! | [`Model`] | `f(ω_i, ω_o)` |
//! |---|---|
//! | `Lambert` | `ρ_d/π` |
//! | `Phong` (textbook, unnormalised) | `ρ_d/π + k_s·cos^n α` |
//! | `SeminarPhong` | `(k_d + k_s·cos^n α / cos θ_i)·u` |
//! | `BlinnPhong` (textbook, unnormalised) | `ρ_d/π + k_s·(n·h)^n` |
//! | `SeminarBlinnPhong` | `(k_d + k_s·(n·h)^n / cos θ_i)·u` |
//! | `ModifiedPhong` (Lafortune and Willems 1994) | `ρ_d/π + ρ_s·(n+2)/(2π)·cos^n α` |
//! | `NormalisedBlinnPhong` (Akenine-Möller et al., *Real-Time Rendering* 3rd ed., 2008) | `ρ_d/π + ρ_s·(n+8)/(8π)·(n·h)^n` |
//! | `GiesenBlinnPhong` (F. Giesen, "Derivation of Phong and Blinn-Phong BRDF normalization factors", 2009) | `ρ_d/π + ρ_s·(n+2)(n+4)/(8π(2^(−n/2)+n))·(n·h)^n` |
//! | `GltfMetal`, `GltfDielectric` (glTF 2.0, Appendix B) | `mix(dielectric, metal, metallic)` of `crate::scene::shading::metallic_roughness`, base colour `c` = [`Brdf::diffuse`], roughness = [`Brdf::shininess`] |
//!
//! with `cos α = max(0, r(ω_i)·ω_o)`, `r(ω) = 2(n·ω)n − ω` (symmetric:
//! `r(ω_i)·ω_o = r(ω_o)·ω_i`), `h = (ω_i+ω_o)/|ω_i+ω_o|`, and `u = 1` or `1/π`
//! ([`Units`]). The diffuse weight of every form is [`Brdf::diffuse`], the
//! specular weight [`Brdf::specular`], the exponent [`Brdf::shininess`].
//!
//! What the normalised forms conserve:
//!
//! * modified Phong: the lobe `(n+2)/(2π)·cos^n α` times `cos θ_i` integrates
//!   to exactly `ρ_s·cos θ_r` when the whole lobe lies above the horizon
//!   (`∫ cos^n α (ω·n) dω = (r·n)·2π/(n+2)`), hence to `ρ_s` at normal
//!   incidence and to at most `ρ_s` elsewhere: `a ≤ ρ_d + ρ_s ≤ 1`, exactly.
//! * normalised Blinn-Phong: `(n+8)/(8π)` is only an approximation. The factor
//!   that makes the normal-incidence albedo exactly `ρ_s` is Giesen's
//!   `(n+2)(n+4)/(8π(2^(−n/2)+n))`, and `(n+8)/(8π)` is larger than it for every
//!   `n > 0`: the normal-incidence albedo of the `(n+8)/(8π)` form is
//!   `ρ_s·(n+8)(n+2^(−n/2))/((n+2)(n+4))`, up to 7.5 % above `ρ_s` (near
//!   `n = 10`) and `≈ ρ_s·(1 + 2/n)` for large `n`. So it conserves energy only
//!   approximately; `docs/brdf.md` (from `cargo run -p penumbra-tools --bin brdf_lab`) has the
//!   numbers. (What *is* exactly normalised is the microfacet distribution
//!   `D(h) = (n+2)/(2π)·(n·h)^n`, with `∫ D(h)(n·h) dω_h = 1`.)
//!
//! # The checks
//!
//! * Positivity: the minimum of `f` over a grid of direction pairs ([`DirGrid`]).
//! * Reciprocity: the largest relative difference
//!   `|f(a,b) − f(b,a)| / max(f(a,b), f(b,a))` over the same pairs.
//! * Energy conservation, in both directions: the directional albedo
//!   `a(ω_o) = ∫ f(ω_i, ω_o) cos θ_i dω_i` (pbrt's `ρ_hd`) and the directional
//!   reflectance `R(ω_i) = ∫ f(ω_i, ω_o) cos θ_o dω_o` (the fraction of the
//!   power arriving from `ω_i` that is reflected — the physical statement of
//!   energy conservation). They are equal for a reciprocal BRDF; for the
//!   seminar's form they are not, and it is `R` that diverges at grazing
//!   incidence. Both must be `≤ 1` everywhere.
//!
//! The models are isotropic (they depend on dot products with `n` and between
//! the directions only), so `a` and `R` depend on the polar angle alone; they
//! are evaluated at `φ = 0` for the polar angles of [`ENERGY_ANGLES_DEG`].
//!
//! **Quadrature** ([`Quadrature`]): a product rule over the hemisphere in
//! `(θ, φ)`: Gauss–Legendre in `θ ∈ [0, π/2]` (weight `sin θ` included) and the
//! midpoint rule in `φ ∈ [0, 2π)` (spectrally accurate for the smooth periodic
//! integrand), with `n_φ = 4·n_θ` so the spacing at the horizon matches the
//! spacing in `θ`. [`Quadrature::for_shininess`] picks
//! `n_θ = max(32, ⌈12·√n⌉)`: a lobe `cos^n α` has angular width
//! `σ ≈ 1/√n`, so there are at least ~8 nodes per `σ` in either direction.
//! The error is estimated a posteriori as `|I(n_θ) − I(n_θ/2)|` (the error of
//! the coarser rule, which bounds that of the finer one as long as the rule
//! converges, as it does here); [`Estimate::error`] carries it, and the
//! closed forms at normal incidence (`ρ_d + ρ_s` for modified Phong, `2π/(n+2)`
//! and `2π/(n+1)` for the unnormalised Phong lobes, `ρ_d` for Lambert) check
//! it in `tests/cpu/brdf.rs`.

use rayon::prelude::*;
use std::f64::consts::PI;

/// A direction (unit vector) in the frame where the normal is `+Z`.
pub type Vec3 = [f64; 3];

/// The unit vector at polar angle `theta` from `+Z` and azimuth `phi` (radians).
pub fn dir(theta: f64, phi: f64) -> Vec3 {
    let (st, ct) = theta.sin_cos();
    let (sp, cp) = phi.sin_cos();
    [st * cp, st * sp, ct]
}

fn dot(a: Vec3, b: Vec3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// `max(0, x)^n`, with `0^0 = 1` as in the renderer's `spec_pow`.
fn lobe_pow(x: f64, n: f64) -> f64 {
    let x = x.max(0.0);
    if n == 0.0 {
        1.0
    } else {
        x.powf(n)
    }
}

/// `cos α = r(ω_i)·ω_o`, the Phong lobe's argument.
fn cos_alpha(wi: Vec3, wo: Vec3) -> f64 {
    // r(ω_i) = 2(n·ω_i)n − ω_i = (−x, −y, z) for n = +Z.
    -wi[0] * wo[0] - wi[1] * wo[1] + wi[2] * wo[2]
}

/// `n·h`, the Blinn-Phong lobe's argument (0 when `ω_i = −ω_o`).
fn cos_half(wi: Vec3, wo: Vec3) -> f64 {
    let s = [wi[0] + wo[0], wi[1] + wo[1], wi[2] + wo[2]];
    let len = dot(s, s).sqrt();
    if len > 0.0 {
        s[2] / len
    } else {
        0.0
    }
}

/// How the seminar's light intensity relates to irradiance (see the module
/// documentation).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Units {
    /// The renderer's units: `E⊥ = I/d²`, `f = k_d + k_s·lobe/cos θ_i`.
    Renderer,
    /// `E⊥ = π·I/d²`: the same BRDF divided by `π` (`k_d` is then the albedo).
    PerPi,
}

impl Units {
    fn scale(self) -> f64 {
        match self {
            Units::Renderer => 1.0,
            Units::PerPi => 1.0 / PI,
        }
    }
}

/// The BRDF models of the lab (formulas in the module documentation).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Model {
    /// `ρ_d/π`.
    Lambert,
    /// Textbook Phong as a BRDF, unnormalised: `ρ_d/π + k_s·cos^n α`.
    Phong,
    /// The seminar's Phong: `(k_d + k_s·cos^n α / cos θ_i)·u`.
    SeminarPhong(Units),
    /// Textbook Blinn-Phong as a BRDF, unnormalised: `ρ_d/π + k_s·(n·h)^n`.
    BlinnPhong,
    /// The seminar's Blinn-Phong: `(k_d + k_s·(n·h)^n / cos θ_i)·u`.
    SeminarBlinnPhong(Units),
    /// Lafortune and Willems' modified Phong: `ρ_d/π + ρ_s·(n+2)/(2π)·cos^n α`.
    ModifiedPhong,
    /// Normalised Blinn-Phong: `ρ_d/π + ρ_s·(n+8)/(8π)·(n·h)^n`.
    NormalisedBlinnPhong,
    /// Blinn-Phong with Giesen's exact normal-incidence normalisation:
    /// `ρ_d/π + ρ_s·(n+2)(n+4)/(8π(2^(−n/2)+n))·(n·h)^n`.
    GiesenBlinnPhong,
    /// glTF 2.0's metallic-roughness BRDF with metallic 1
    /// (`crate::scene::shading::metallic_roughness`): base colour `c` =
    /// [`Brdf::diffuse`], roughness = [`Brdf::shininess`].
    GltfMetal,
    /// The same with metallic 0 (a dielectric).
    GltfDielectric,
}

impl Model {
    /// Every model, in the order of the lab's table.
    pub const ALL: [Model; 12] = [
        Model::Lambert,
        Model::Phong,
        Model::SeminarPhong(Units::Renderer),
        Model::SeminarPhong(Units::PerPi),
        Model::BlinnPhong,
        Model::SeminarBlinnPhong(Units::Renderer),
        Model::SeminarBlinnPhong(Units::PerPi),
        Model::ModifiedPhong,
        Model::NormalisedBlinnPhong,
        Model::GiesenBlinnPhong,
        Model::GltfMetal,
        Model::GltfDielectric,
    ];

    /// A short name for tables.
    pub fn name(self) -> &'static str {
        match self {
            Model::Lambert => "Lambert ρ/π",
            Model::Phong => "Phong k_s·cos^n α (textbook)",
            Model::SeminarPhong(Units::Renderer) => "seminar Phong k_s·cos^n α/cos θ_i",
            Model::SeminarPhong(Units::PerPi) => "seminar Phong, ÷π",
            Model::BlinnPhong => "Blinn-Phong k_s·(n·h)^n (textbook)",
            Model::SeminarBlinnPhong(Units::Renderer) => "seminar Blinn-Phong k_s·(n·h)^n/cos θ_i",
            Model::SeminarBlinnPhong(Units::PerPi) => "seminar Blinn-Phong, ÷π",
            Model::ModifiedPhong => "modified Phong (n+2)/(2π)",
            Model::NormalisedBlinnPhong => "normalised Blinn-Phong (n+8)/(8π)",
            Model::GiesenBlinnPhong => "Blinn-Phong, Giesen's exact factor",
            Model::GltfMetal => "glTF metal (metallic 1), c = 1",
            Model::GltfDielectric => "glTF dielectric (metallic 0), c = 1",
        }
    }

    /// Whether the model is glTF's, whose [`Brdf::shininess`] is the
    /// roughness (in the lab: [`ROUGHNESS`]).
    pub fn is_gltf(self) -> bool {
        matches!(self, Model::GltfMetal | Model::GltfDielectric)
    }

    /// Whether the model has a specular lobe (and so a shininess).
    pub fn has_lobe(self) -> bool {
        self != Model::Lambert
    }
}

/// A BRDF: a model with its weights and exponent.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Brdf {
    /// Which formula.
    pub model: Model,
    /// Diffuse weight: `ρ_d` (albedo), or the seminar's `k_d`.
    pub diffuse: f64,
    /// Specular weight: `k_s` or `ρ_s`.
    pub specular: f64,
    /// The lobe exponent `n` (ignored by Lambert); for glTF's models the
    /// roughness.
    pub shininess: f64,
}

impl Brdf {
    /// Lambert with albedo `rho`.
    pub fn lambert(rho: f64) -> Brdf {
        Brdf {
            model: Model::Lambert,
            diffuse: rho,
            specular: 0.0,
            shininess: 0.0,
        }
    }

    /// `model`'s specular lobe alone (diffuse 0, specular 1) — the worst case
    /// for energy under `ρ_d + ρ_s ≤ 1`: the albedo is linear in the weights
    /// and the diffuse part's is `ρ_d`, so its maximum over the simplex is at
    /// `(1, 0)` (Lambert, albedo 1) or `(0, 1)`. For the seminar's form in
    /// renderer units the diffuse part's albedo is `π·k_d` instead (checked
    /// separately).
    pub fn lobe(model: Model, shininess: f64) -> Brdf {
        match model {
            Model::Lambert => Brdf::lambert(1.0),
            // Base colour 1: the most a metal's Fresnel and a dielectric's
            // diffuse part reflect.
            Model::GltfMetal | Model::GltfDielectric => Brdf {
                model,
                diffuse: 1.0,
                specular: 0.0,
                shininess,
            },
            _ => Brdf {
                model,
                diffuse: 0.0,
                specular: 1.0,
                shininess,
            },
        }
    }

    /// `f(ω_i, ω_o)`; 0 when either direction is on or below the horizon.
    pub fn eval(&self, wi: Vec3, wo: Vec3) -> f64 {
        let (ci, co) = (wi[2], wo[2]);
        if ci <= 0.0 || co <= 0.0 {
            return 0.0;
        }
        let (kd, ks, n) = (self.diffuse, self.specular, self.shininess);
        match self.model {
            Model::Lambert => kd / PI,
            Model::Phong => kd / PI + ks * lobe_pow(cos_alpha(wi, wo), n),
            Model::SeminarPhong(u) => (kd + ks * lobe_pow(cos_alpha(wi, wo), n) / ci) * u.scale(),
            Model::BlinnPhong => kd / PI + ks * lobe_pow(cos_half(wi, wo), n),
            Model::SeminarBlinnPhong(u) => {
                (kd + ks * lobe_pow(cos_half(wi, wo), n) / ci) * u.scale()
            }
            Model::ModifiedPhong => {
                kd / PI + ks * (n + 2.0) / (2.0 * PI) * lobe_pow(cos_alpha(wi, wo), n)
            }
            Model::NormalisedBlinnPhong => {
                kd / PI + ks * (n + 8.0) / (8.0 * PI) * lobe_pow(cos_half(wi, wo), n)
            }
            Model::GiesenBlinnPhong => {
                kd / PI + ks * giesen_factor(n) * lobe_pow(cos_half(wi, wo), n)
            }
            Model::GltfMetal | Model::GltfDielectric => {
                let metallic = if self.model == Model::GltfMetal {
                    1.0
                } else {
                    0.0
                };
                let (d, s) = crate::scene::shading::metallic_roughness::brdf(
                    glam::DVec3::Z,
                    glam::DVec3::from(wi),
                    glam::DVec3::from(wo),
                    glam::DVec3::splat(kd),
                    metallic,
                    n,
                );
                d.x + s.x
            }
        }
    }

    /// The quadrature rule for this BRDF: [`Quadrature::for_shininess`] of
    /// its exponent, or for glTF's models of the Phong exponent whose lobe
    /// is about as wide as the microfacet lobe of width `α = roughness²`,
    /// `n = 2/α² − 2` (the Beckmann–Phong correspondence of Walter et al.,
    /// "Microfacet Models for Refraction", EGSR 2007, section 5.2; the
    /// error estimate checks that the rule suffices).
    pub fn quadrature(&self) -> Quadrature {
        if self.model.is_gltf() {
            let alpha = self.shininess * self.shininess;
            return Quadrature::for_shininess(2.0 / (alpha * alpha).max(1e-12) - 2.0);
        }
        Quadrature::for_shininess(self.shininess)
    }
}

/// Giesen's exact normalisation of the Blinn-Phong BRDF at normal incidence:
/// `(n+2)(n+4) / (8π(2^(−n/2) + n))`. (With `ω_o = n`, `θ_h = θ_i/2`, and
/// `2π ∫ cos^n(θ/2) cos θ sin θ dθ = 8π(n + 2^(−n/2))/((n+2)(n+4))`.)
pub fn giesen_factor(n: f64) -> f64 {
    (n + 2.0) * (n + 4.0) / (8.0 * PI * ((-n / 2.0).exp2() + n))
}

/// The normal-incidence albedo of the lobe `(n+8)/(8π)·(n·h)^n` (weight 1):
/// `(n+8)(n+2^(−n/2))/((n+2)(n+4))`.
pub fn normalised_blinn_phong_normal_albedo(n: f64) -> f64 {
    (n + 8.0) / (8.0 * PI) / giesen_factor(n)
}

/// Gauss–Legendre nodes and weights on `[-1, 1]` (Newton's method on the
/// Legendre polynomial, from the usual Chebyshev-like initial guesses).
fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        let mut x = (PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            // P_n(x) and P_n'(x) by the three-term recurrence.
            let (mut p0, mut p1) = (1.0, x);
            for k in 2..=n {
                let k = k as f64;
                let p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
                p0 = p1;
                p1 = p2;
            }
            let pn = if n == 0 { 1.0 } else { p1 };
            let pn1 = if n == 0 { 0.0 } else { p0 };
            dp = n as f64 * (x * pn - pn1) / (x * x - 1.0);
            let dx = pn / dp;
            x -= dx;
            if dx.abs() < 1e-15 {
                break;
            }
        }
        out.push((x, 2.0 / ((1.0 - x * x) * dp * dp)));
    }
    out
}

/// A product quadrature rule over the upper hemisphere (see the module
/// documentation): Gauss–Legendre in `θ`, midpoint in `φ`.
#[derive(Clone, Debug)]
pub struct Quadrature {
    /// `(direction, weight)` for every node; the weights include the solid
    /// angle's `sin θ` and sum to `2π`.
    nodes: Vec<(Vec3, f64)>,
    n_theta: usize,
    n_phi: usize,
}

impl Quadrature {
    /// `n_theta` Gauss–Legendre nodes in `θ`, `n_phi` midpoints in `φ`.
    pub fn new(n_theta: usize, n_phi: usize) -> Quadrature {
        let half = PI / 4.0; // θ = π/4·(x + 1) maps [−1, 1] to [0, π/2]
        let dphi = 2.0 * PI / n_phi as f64;
        let mut nodes = Vec::with_capacity(n_theta * n_phi);
        for (x, w) in gauss_legendre(n_theta) {
            let theta = half * (x + 1.0);
            let wt = w * half * theta.sin() * dphi;
            for j in 0..n_phi {
                nodes.push((dir(theta, (j as f64 + 0.5) * dphi), wt));
            }
        }
        Quadrature {
            nodes,
            n_theta,
            n_phi,
        }
    }

    /// The rule for a lobe of exponent `n`: `n_θ = max(32, ⌈12·√n⌉)` (even),
    /// `n_φ = 4·n_θ`.
    pub fn for_shininess(n: f64) -> Quadrature {
        let nt = ((12.0 * n.max(0.0).sqrt()).ceil() as usize).max(32);
        let nt = nt + nt % 2;
        Quadrature::new(nt, 4 * nt)
    }

    /// The same kind of rule with half the nodes in each direction (for the
    /// error estimate).
    pub fn coarser(&self) -> Quadrature {
        Quadrature::new((self.n_theta / 2).max(1), (self.n_phi / 2).max(1))
    }

    /// `(n_θ, n_φ)`.
    pub fn size(&self) -> (usize, usize) {
        (self.n_theta, self.n_phi)
    }

    /// `∫ g(ω) dω` over the upper hemisphere.
    pub fn integrate(&self, g: impl Fn(Vec3) -> f64) -> f64 {
        self.nodes.iter().map(|&(w, wt)| g(w) * wt).sum()
    }
}

/// An integral with its a-posteriori error estimate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate {
    /// The value from the finer rule.
    pub value: f64,
    /// `|fine − coarse|`.
    pub error: f64,
}

/// `a(ω_o) = ∫ f(ω_i, ω_o) cos θ_i dω_i` on `q`, without error estimate.
pub fn albedo_with(brdf: &Brdf, wo: Vec3, q: &Quadrature) -> f64 {
    q.integrate(|wi| brdf.eval(wi, wo) * wi[2])
}

/// `R(ω_i) = ∫ f(ω_i, ω_o) cos θ_o dω_o` on `q`, without error estimate.
pub fn reflectance_with(brdf: &Brdf, wi: Vec3, q: &Quadrature) -> f64 {
    q.integrate(|wo| brdf.eval(wi, wo) * wo[2])
}

/// The directional albedo `a(ω_o)` at polar angle `theta_o` (radians), with
/// the rule for the BRDF's shininess and its error estimate.
pub fn albedo(brdf: &Brdf, theta_o: f64) -> Estimate {
    let q = brdf.quadrature();
    estimate(&q, |q| albedo_with(brdf, dir(theta_o, 0.0), q))
}

/// The directional reflectance `R(ω_i)` at polar angle `theta_i` (radians),
/// with the rule for the BRDF's shininess and its error estimate.
pub fn reflectance(brdf: &Brdf, theta_i: f64) -> Estimate {
    let q = brdf.quadrature();
    estimate(&q, |q| reflectance_with(brdf, dir(theta_i, 0.0), q))
}

fn estimate(q: &Quadrature, f: impl Fn(&Quadrature) -> f64) -> Estimate {
    let fine = f(q);
    let coarse = f(&q.coarser());
    Estimate {
        value: fine,
        error: (fine - coarse).abs(),
    }
}

/// The polar angles (degrees) at which `a` and `R` are evaluated: every 5°
/// from 0 to 85, then closer and closer to grazing (the seminar's `1/cos θ_i`
/// shows there, the sooner the broader the lobe).
pub const ENERGY_ANGLES_DEG: [f64; 24] = [
    0.0, 5.0, 10.0, 15.0, 20.0, 25.0, 30.0, 35.0, 40.0, 45.0, 50.0, 55.0, 60.0, 65.0, 70.0, 75.0,
    80.0, 85.0, 88.0, 89.0, 89.5, 89.9, 89.99, 89.999,
];

/// A grid of directions for the pointwise checks: polar angles at the
/// midpoints of `n_theta` equal steps of `[0°, 90°)` plus the normal itself,
/// azimuths at `n_phi` equal steps from 0.
#[derive(Clone, Debug)]
pub struct DirGrid {
    /// `(θ, φ)` in radians.
    pub angles: Vec<(f64, f64)>,
}

impl DirGrid {
    /// The grid described above.
    pub fn new(n_theta: usize, n_phi: usize) -> DirGrid {
        let mut angles = vec![(0.0, 0.0)];
        for i in 0..n_theta {
            let theta = (i as f64 + 0.5) * (PI / 2.0) / n_theta as f64;
            for j in 0..n_phi {
                angles.push((theta, j as f64 * 2.0 * PI / n_phi as f64));
            }
        }
        DirGrid { angles }
    }
}

impl Default for DirGrid {
    /// 18 polar angles (every 5°, from 2.5° to 87.5°) × 24 azimuths (every
    /// 15°), plus the normal: 433 directions, 187 489 ordered pairs.
    fn default() -> DirGrid {
        DirGrid::new(18, 24)
    }
}

/// Where an extreme was found: `(θ_i, φ_i, θ_o, φ_o)` in degrees (for the
/// energy checks only the one polar angle that varies is meaningful, the
/// others are 0).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Extreme {
    /// The extreme value.
    pub value: f64,
    /// `(θ_i, φ_i, θ_o, φ_o)`, degrees.
    pub at: [f64; 4],
}

/// The minimum of `f` over all ordered pairs of the grid.
pub fn positivity(brdf: &Brdf, grid: &DirGrid) -> Extreme {
    pairs_extreme(grid, |wi, wo| -brdf.eval(wi, wo)).map_value(|v| -v)
}

/// The largest relative reciprocity error
/// `|f(a,b) − f(b,a)| / max(|f(a,b)|, |f(b,a)|)` over all pairs of the grid
/// (pairs where both values are 0 count as 0).
pub fn reciprocity(brdf: &Brdf, grid: &DirGrid) -> Extreme {
    pairs_extreme(grid, |a, b| {
        let (x, y) = (brdf.eval(a, b), brdf.eval(b, a));
        let m = x.abs().max(y.abs());
        if m > 0.0 {
            (x - y).abs() / m
        } else {
            0.0
        }
    })
}

impl Extreme {
    fn map_value(self, f: impl Fn(f64) -> f64) -> Extreme {
        Extreme {
            value: f(self.value),
            at: self.at,
        }
    }
}

/// The maximum of `g(ω_i, ω_o)` over the ordered pairs of the grid.
fn pairs_extreme(grid: &DirGrid, g: impl Fn(Vec3, Vec3) -> f64 + Sync) -> Extreme {
    let dirs: Vec<Vec3> = grid.angles.iter().map(|&(t, p)| dir(t, p)).collect();
    let (value, i, o) = (0..dirs.len())
        .into_par_iter()
        .map(|i| {
            let mut best = (f64::NEG_INFINITY, i, 0);
            for (o, &wo) in dirs.iter().enumerate() {
                let v = g(dirs[i], wo);
                if v > best.0 {
                    best = (v, i, o);
                }
            }
            best
        })
        .reduce(
            || (f64::NEG_INFINITY, 0, 0),
            |a, b| if b.0 > a.0 { b } else { a },
        );
    let deg = |(t, p): (f64, f64)| (t.to_degrees(), p.to_degrees());
    let (ti, pi) = deg(grid.angles[i]);
    let (to, po) = deg(grid.angles[o]);
    Extreme {
        value,
        at: [ti, pi, to, po],
    }
}

/// The energy check of one BRDF: the largest albedo and reflectance over
/// [`ENERGY_ANGLES_DEG`], each with its error estimate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Energy {
    /// `max a(ω_o)`; `at[2]` is `θ_o`.
    pub albedo: Extreme,
    /// The error estimate of that albedo.
    pub albedo_error: f64,
    /// `max R(ω_i)`; `at[0]` is `θ_i`.
    pub reflectance: Extreme,
    /// The error estimate of that reflectance.
    pub reflectance_error: f64,
    /// The quadrature rule used, `(n_θ, n_φ)`.
    pub rule: (usize, usize),
}

impl Energy {
    /// Whether both maxima are at most 1 within their error estimates.
    pub fn conserves(&self) -> bool {
        self.albedo.value <= 1.0 + self.albedo_error + 1e-12
            && self.reflectance.value <= 1.0 + self.reflectance_error + 1e-12
    }
}

/// Evaluates `a` and `R` at every angle of `angles_deg` (in parallel) and
/// keeps the largest of each.
pub fn energy(brdf: &Brdf, angles_deg: &[f64]) -> Energy {
    let fine = brdf.quadrature();
    let coarse = fine.coarser();
    let results: Vec<(f64, Estimate, Estimate)> = angles_deg
        .par_iter()
        .map(|&deg| {
            let w = dir(deg.to_radians(), 0.0);
            let est = |f: &dyn Fn(&Quadrature) -> f64| {
                let v = f(&fine);
                Estimate {
                    value: v,
                    error: (v - f(&coarse)).abs(),
                }
            };
            let a = est(&|q| albedo_with(brdf, w, q));
            let r = est(&|q| reflectance_with(brdf, w, q));
            (deg, a, r)
        })
        .collect();
    let pick = |which: fn(&(f64, Estimate, Estimate)) -> Estimate| {
        results
            .iter()
            .map(|r| (r.0, which(r)))
            .fold((0.0, None::<Estimate>), |best, (deg, e)| match best.1 {
                Some(b) if b.value >= e.value => best,
                _ => (deg, Some(e)),
            })
    };
    let (a_deg, a) = pick(|r| r.1);
    let (r_deg, r) = pick(|r| r.2);
    let (a, r) = (a.unwrap_or(NAN_EST), r.unwrap_or(NAN_EST));
    Energy {
        albedo: Extreme {
            value: a.value,
            at: [0.0, 0.0, a_deg, 0.0],
        },
        albedo_error: a.error,
        reflectance: Extreme {
            value: r.value,
            at: [r_deg, 0.0, 0.0, 0.0],
        },
        reflectance_error: r.error,
        rule: fine.size(),
    }
}

const NAN_EST: Estimate = Estimate {
    value: f64::NAN,
    error: f64::NAN,
};

/// The three properties of one BRDF.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Properties {
    /// Minimum of `f` over the grid.
    pub positivity: Extreme,
    /// Largest relative reciprocity error over the grid.
    pub reciprocity: Extreme,
    /// Largest albedo and reflectance.
    pub energy: Energy,
}

/// Relative reciprocity errors below this are rounding (the forms are
/// evaluated in `f64`; the symmetric ones agree to a few ULPs).
pub const RECIPROCITY_TOLERANCE: f64 = 1e-9;

impl Properties {
    /// `f ≥ 0` on the grid.
    pub fn positive(&self) -> bool {
        self.positivity.value >= 0.0
    }

    /// Reciprocal within [`RECIPROCITY_TOLERANCE`] on the grid.
    pub fn reciprocal(&self) -> bool {
        self.reciprocity.value <= RECIPROCITY_TOLERANCE
    }
}

/// Runs all three checks on the default grids.
pub fn check(brdf: &Brdf) -> Properties {
    let grid = DirGrid::default();
    Properties {
        positivity: positivity(brdf, &grid),
        reciprocity: reciprocity(brdf, &grid),
        energy: energy(brdf, &ENERGY_ANGLES_DEG),
    }
}

/// The roughness values of the lab for glTF's models (`α` from 0.04 to 1).
pub const ROUGHNESS: [f64; 5] = [0.2, 0.3, 0.5, 0.7, 1.0];

/// The shininess values of the lab.
pub const SHININESS: [f64; 8] = [1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0, 200.0];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gauss_legendre_integrates_polynomials_exactly() {
        let rule = gauss_legendre(5);
        // Degree ≤ 9 is exact: ∫ x^8 = 2/9.
        let s: f64 = rule.iter().map(|&(x, w)| w * x.powi(8)).sum();
        assert!((s - 2.0 / 9.0).abs() < 1e-14, "{s}");
        let w: f64 = rule.iter().map(|&(_, w)| w).sum();
        assert!((w - 2.0).abs() < 1e-14);
    }

    #[test]
    fn hemisphere_has_solid_angle_two_pi() {
        let q = Quadrature::new(16, 64);
        assert!((q.integrate(|_| 1.0) - 2.0 * PI).abs() < 1e-12);
        // ∫ cos θ dω = π.
        assert!((q.integrate(|w| w[2]) - PI).abs() < 1e-12);
    }

    #[test]
    fn lobe_arguments_are_symmetric() {
        let (a, b) = (dir(0.3, 0.2), dir(1.1, 2.5));
        assert!((cos_alpha(a, b) - cos_alpha(b, a)).abs() < 1e-15);
        assert!((cos_half(a, b) - cos_half(b, a)).abs() < 1e-15);
        // Mirror direction: cos α = 1.
        assert!((cos_alpha(dir(0.7, 0.0), dir(0.7, PI)) - 1.0).abs() < 1e-15);
    }
}
