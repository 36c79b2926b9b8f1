//! Lights: directional, point and spot, and the area lights (rectangle and
//! sphere), each with an intensity and the three colours of the Phong model.
//! The diffuse and specular colours are scaled by the intensity (and by the
//! falloff); the ambient colour is not.
//!
//! An area light of intensity `I` is the limit of N → ∞ point lights of
//! intensity `I/N` spread uniformly over its surface, for the rectangle each
//! weighted by the emitter's cosine `max(0, n_light · (−l))`. The renderer
//! takes `samples` of them per pass (stratified, each with its own shadow
//! ray); the ambient term is counted once per light, not per sample.

use glam::{DVec3, Vec3};

/// Where the light comes from and how it falls off.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightKind {
    /// Parallel light travelling along `direction` (unit); equal everywhere,
    /// no falloff, never occluded beyond the scene.
    Directional {
        /// Direction the light travels in (from the light into the scene).
        direction: DVec3,
    },
    /// Light emitted equally in all directions from `position`; inverse-square
    /// falloff.
    Point {
        /// Position, world units.
        position: DVec3,
    },
    /// Point light restricted to a cone around `direction`, with the smooth
    /// falloff of glTF's KHR_lights_punctual between the inner and outer cone
    /// angles, and inverse-square falloff.
    Spot {
        /// Position, world units.
        position: DVec3,
        /// Cone axis (unit), pointing away from the light.
        direction: DVec3,
        /// Angle from the axis (radians) inside which the cone is at full
        /// strength; 0 ≤ inner < outer.
        inner_angle: f64,
        /// Angle from the axis (radians) outside which there is no light;
        /// outer ≤ π/2.
        outer_angle: f64,
    },
    /// One-sided rectangle `corner + s·edge1 + t·edge2` (s, t in [0, 1]),
    /// emitting on the side of `edge1 × edge2`.
    Rect {
        /// One corner.
        corner: DVec3,
        /// First edge from the corner.
        edge1: DVec3,
        /// Second edge from the corner.
        edge2: DVec3,
        /// Light samples per pass, in 1..=[`MAX_LIGHT_SAMPLES`].
        samples: u32,
    },
    /// Sphere of point lights (emitting in all directions, no emitter
    /// cosine; the light is not an occluder).
    Sphere {
        /// Centre.
        center: DVec3,
        /// Radius, > 0.
        radius: f64,
        /// Light samples per pass, in 1..=[`MAX_LIGHT_SAMPLES`].
        samples: u32,
    },
    /// Light from every direction at infinity (docs/materials.md,
    /// "Environment"): radiance `L(ω) = intensity · diffuse · g(ω·up)` with
    /// `g(u) = ENVIRONMENT_GRADIENT.0 + ENVIRONMENT_GRADIENT.1 · u`, a
    /// studio sky over a darker ground. Evaluated without visibility: its
    /// samples cast no shadow rays, so geometry enclosing the scene (a sky
    /// box) does not block it.
    Environment {
        /// Unit world up (the sky's zenith).
        up: DVec3,
        /// Directions sampled per pass (from [`ENVIRONMENT_MIXTURE`]), in
        /// 1..=[`MAX_LIGHT_SAMPLES`].
        samples: u32,
    },
}

/// The environment's gradient `g(u) = a + b·u` of the up-component `u` of
/// a direction, as `(a, b)`: 1 at the zenith, 0.6 at the horizon, 0.2 at the
/// nadir. The one source of the coefficients: the GPU light gets them from
/// here (`render::layout`), the reference and the tests too.
pub const ENVIRONMENT_GRADIENT: (f64, f64) = (0.6, 0.4);

/// The mixture of direction densities the environment's samples are drawn
/// from (docs/materials.md, "Environment"): with probability `uniform`
/// uniform on the sphere, with `cosine` a cosine lobe around the shading
/// normal, and with the rest split evenly over `lobes` Phong lobes
/// `cos^e` around the mirror direction of the eye, of exponents
/// `e = first_exponent · ratio^k`, k = 0..lobes. Each sample weighs the
/// radiance over the mixture's density (one-sample multiple importance
/// sampling), so the estimate is unbiased for any shader.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EnvironmentMixture {
    /// Weight of the uniform-sphere density.
    pub uniform: f64,
    /// Weight of the cosine lobe around the normal.
    pub cosine: f64,
    /// Number of Phong lobes around the mirror direction.
    pub lobes: u32,
    /// Exponent of the widest Phong lobe.
    pub first_exponent: f64,
    /// Ratio of each lobe's exponent to the one before.
    pub ratio: f64,
}

impl EnvironmentMixture {
    /// Weight of each Phong lobe.
    pub fn lobe_weight(&self) -> f64 {
        (1.0 - self.uniform - self.cosine) / f64::from(self.lobes)
    }

    /// Exponent of Phong lobe `k`.
    pub fn exponent(&self, k: u32) -> f64 {
        self.first_exponent * self.ratio.powi(k as i32)
    }
}

/// The environment's mixture: 1/8 uniform, 3/8 cosine, and five Phong lobes
/// of exponents 16, 256, 4096, 65536 and 2^20 (1/10 each). The one source of
/// these values: the GPU light gets them from here (`render::layout`), the
/// reference too.
pub const ENVIRONMENT_MIXTURE: EnvironmentMixture = EnvironmentMixture {
    uniform: 0.125,
    cosine: 0.375,
    lobes: 5,
    first_exponent: 16.0,
    ratio: 16.0,
};

/// Directions the environment samples per pass unless told otherwise.
pub const ENVIRONMENT_SAMPLES: u32 = 64;

/// Most light samples per area light and pass.
pub const MAX_LIGHT_SAMPLES: u32 = 4096;

/// A light of the Phong model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Light {
    /// Directional, point or spot.
    pub kind: LightKind,
    /// Scales the diffuse and specular colours; ≥ 0.
    pub intensity: f32,
    /// Ambient colour `I_a`, added unconditionally (also in shadow).
    pub ambient: Vec3,
    /// Diffuse colour `I_d` (before intensity and falloff).
    pub diffuse: Vec3,
    /// Specular colour `I_s` (before intensity and falloff).
    pub specular: Vec3,
}

impl LightKind {
    /// Whether this is an area light (sampled).
    pub fn is_area(&self) -> bool {
        self.samples().is_some()
    }

    /// The sample count of an area light; `None` for a punctual one. The
    /// one exhaustive `match` that says which kinds are area lights.
    pub fn samples(&self) -> Option<u32> {
        match self {
            LightKind::Rect { samples, .. }
            | LightKind::Sphere { samples, .. }
            | LightKind::Environment { samples, .. } => Some(*samples),
            LightKind::Directional { .. } | LightKind::Point { .. } | LightKind::Spot { .. } => {
                None
            }
        }
    }

    /// Overrides the sample count of an area light (no effect on others).
    pub fn set_samples(&mut self, n: u32) {
        match self {
            LightKind::Rect { samples, .. }
            | LightKind::Sphere { samples, .. }
            | LightKind::Environment { samples, .. } => *samples = n,
            LightKind::Directional { .. } | LightKind::Point { .. } | LightKind::Spot { .. } => {}
        }
    }

    /// The kind's `"type"` in a JSON scene (scenes/README.md): every kind
    /// has one, and [`LightKind::TYPES`] lists them.
    pub fn type_name(&self) -> &'static str {
        match self {
            LightKind::Directional { .. } => "directional",
            LightKind::Point { .. } => "point",
            LightKind::Spot { .. } => "spot",
            LightKind::Rect { .. } => "rect",
            LightKind::Sphere { .. } => "sphere",
            LightKind::Environment { .. } => "environment",
        }
    }

    /// Every kind's [`LightKind::type_name`], for the tests that each kind
    /// is covered (tests/cpu/kinds.rs).
    pub const TYPES: [&'static str; 6] = [
        "directional",
        "point",
        "spot",
        "rect",
        "sphere",
        "environment",
    ];

    /// The KHR_lights_punctual cone attenuation for a spot light at
    /// `cos_angle` = cos of the angle between the cone axis and the direction
    /// from the light to the point: smoothstep-like
    /// `clamp((cos θ − cos outer) / (cos inner − cos outer), 0, 1)²`.
    pub fn spot_cone(cos_angle: f64, inner_angle: f64, outer_angle: f64) -> f64 {
        let (scale, offset) = Self::spot_cone_scale_offset(inner_angle, outer_angle);
        let a = (cos_angle * scale + offset).clamp(0.0, 1.0);
        a * a
    }

    /// The cone attenuation as `clamp(cos θ · scale + offset, 0, 1)²`, the
    /// form KHR_lights_punctual suggests for shaders (the difference of the
    /// cosines is kept above 10⁻³ so equal angles cannot divide by zero).
    pub fn spot_cone_scale_offset(inner_angle: f64, outer_angle: f64) -> (f64, f64) {
        let (ci, co) = (inner_angle.cos(), outer_angle.cos());
        let scale = 1.0 / (ci - co).max(1e-3);
        (scale, -co * scale)
    }
}

/// Lambert's formula for the form factor from a differential area at `p`
/// with unit normal `n` to a planar polygon (vertices in order):
/// `F = 1/(2π) Σᵢ βᵢ · n·ĝᵢ`, with βᵢ the angle edge i subtends at `p` and ĝᵢ
/// the unit normal of the plane through `p` and that edge. For a rectangle
/// light of area A and intensity I (unoccluded, fully above the horizon),
/// the diffuse term converges to `k_d·I_d·I·π·F/A`.
pub fn polygon_form_factor(p: DVec3, n: DVec3, polygon: &[DVec3]) -> f64 {
    let mut sum = 0.0;
    for k in 0..polygon.len() {
        let a = (polygon[k] - p).normalize();
        let b = (polygon[(k + 1) % polygon.len()] - p).normalize();
        let beta = a.dot(b).clamp(-1.0, 1.0).acos();
        sum += beta * n.dot(a.cross(b).normalize_or_zero());
    }
    (sum / (2.0 * std::f64::consts::PI)).abs()
}
