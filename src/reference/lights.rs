//! Lights as `shaders/lights.wgsl` sees them, in `f64`: the diffuse and
//! specular colours premultiplied by the intensity (the ambient colour not),
//! the spot cone as KHR_lights_punctual's scale and offset, and the rectangle
//! light's unit emitting normal, as `render::layout::GpuScene::new` lays them
//! out.
//!
//! An area light of intensity I is the limit of N point lights of I/N spread
//! uniformly over its surface (the rectangle's each weighted by the emitter's
//! cosine); each pass takes `samples` of them.

use glam::DVec3;

use super::intersect::FAR;
use crate::scene::{EnvironmentMixture, Light as SceneLight, LightKind, ENVIRONMENT_MIXTURE};

/// Where a light's samples come from. (Each variant's docs name its
/// fields.)
#[allow(missing_docs)]
#[derive(Clone, Copy, Debug)]
pub enum Kind {
    /// Parallel light travelling along the unit `direction`.
    Directional { direction: DVec3 },
    /// Point light.
    Point { position: DVec3 },
    /// Spot light: attenuation `clamp(cos · scale + offset, 0, 1)²` with
    /// `cos` the cosine from the unit `axis`.
    Spot {
        position: DVec3,
        axis: DVec3,
        scale: f64,
        offset: f64,
    },
    /// One-sided rectangle `corner + s·edge1 + t·edge2`, emitting along
    /// the unit `normal` = normalize(edge1 × edge2).
    Rect {
        corner: DVec3,
        edge1: DVec3,
        edge2: DVec3,
        normal: DVec3,
    },
    /// Sphere of point lights (uniform on the surface; not an occluder).
    Sphere { center: DVec3, radius: f64 },
    /// Environment: radiance `g(ω·up)` (times the colours), `g(u) = a + b·u`,
    /// its directions drawn from `mixture`.
    Environment {
        up: DVec3,
        a: f64,
        b: f64,
        mixture: EnvironmentMixture,
    },
}

/// A light ready for shading.
#[derive(Clone, Copy, Debug)]
pub struct Light {
    /// Geometry.
    pub kind: Kind,
    /// Ambient colour (not scaled by the intensity).
    pub ambient: DVec3,
    /// Diffuse colour times intensity.
    pub diffuse: DVec3,
    /// Specular colour times intensity.
    pub specular: DVec3,
    /// Samples per pass (1 for punctual lights).
    pub samples: u32,
}

impl Light {
    /// From the scene model.
    pub fn new(l: &SceneLight) -> Light {
        let intensity = l.intensity as f64;
        let mut samples = 1;
        let kind = match l.kind {
            LightKind::Directional { direction } => Kind::Directional { direction },
            LightKind::Point { position } => Kind::Point { position },
            LightKind::Spot {
                position,
                direction,
                inner_angle,
                outer_angle,
            } => {
                let (scale, offset) = LightKind::spot_cone_scale_offset(inner_angle, outer_angle);
                Kind::Spot {
                    position,
                    axis: direction,
                    scale,
                    offset,
                }
            }
            LightKind::Rect {
                corner,
                edge1,
                edge2,
                samples: n,
            } => {
                samples = n;
                Kind::Rect {
                    corner,
                    edge1,
                    edge2,
                    normal: edge1.cross(edge2).normalize(),
                }
            }
            LightKind::Sphere {
                center,
                radius,
                samples: n,
            } => {
                samples = n;
                Kind::Sphere { center, radius }
            }
            LightKind::Environment { up, samples: n } => {
                samples = n;
                let (a, b) = crate::scene::ENVIRONMENT_GRADIENT;
                Kind::Environment {
                    up,
                    a,
                    b,
                    mixture: ENVIRONMENT_MIXTURE,
                }
            }
        };
        Light {
            kind,
            ambient: l.ambient.as_dvec3(),
            diffuse: l.diffuse.as_dvec3() * intensity,
            specular: l.specular.as_dvec3() * intensity,
            samples,
        }
    }
}

/// What a light sample delivers at a point: the unit direction towards it,
/// the distance a shadow ray must cover, and the falloff factor.
#[derive(Clone, Copy, Debug)]
pub struct LightSample {
    /// Unit vector from the point towards the light sample.
    pub to_light: DVec3,
    /// Shadow-ray length ([`FAR`] for directional lights).
    pub distance: f64,
    /// Falloff, including the 1/N of each of an area light's N points.
    pub falloff: f64,
}

const NONE: LightSample = LightSample {
    to_light: DVec3::Z,
    distance: 0.0,
    falloff: 0.0,
};

/// Sample `uv` ∈ [0, 1)² of `light` seen from `p` (`sample_light`), a point
/// with unit shading normal `n` seen from the unit direction `v` (towards
/// the eye; only the environment's samples depend on the two:
/// [`super::environment`]).
pub fn sample_light(light: &Light, p: DVec3, n: DVec3, v: DVec3, uv: [f64; 2]) -> LightSample {
    let (x, falloff_scale, cone) = match light.kind {
        Kind::Directional { direction } => {
            return LightSample {
                to_light: -direction,
                distance: FAR,
                falloff: 1.0,
            }
        }
        Kind::Environment { up, a, b, mixture } => {
            return super::environment::sample(
                &mixture,
                |w| a + b * w.dot(up),
                light.samples,
                n,
                v,
                uv,
            );
        }
        Kind::Point { position } => (position, 1.0, None),
        Kind::Spot {
            position,
            axis,
            scale,
            offset,
        } => (position, 1.0, Some((axis, scale, offset))),
        Kind::Rect {
            corner,
            edge1,
            edge2,
            ..
        } => (
            corner + uv[0] * edge1 + uv[1] * edge2,
            1.0 / light.samples as f64,
            None,
        ),
        Kind::Sphere { center, radius } => {
            // Uniform on the sphere: z uniform in [−1, 1], azimuth uniform.
            // (The kernel's 2π is the f32 6.2831855; this is the exact one.)
            let z = 1.0 - 2.0 * uv[0];
            let r = (1.0 - z * z).max(0.0).sqrt();
            let phi = std::f64::consts::TAU * uv[1];
            (
                center + radius * DVec3::new(r * phi.cos(), r * phi.sin(), z),
                1.0 / light.samples as f64,
                None,
            )
        }
    };
    let d = x - p;
    let dist2 = d.dot(d);
    // A point exactly at the light gets none.
    if dist2 == 0.0 {
        return NONE;
    }
    let dist = dist2.sqrt();
    let l = d / dist;
    let mut falloff = falloff_scale / dist2;
    if let Kind::Rect { normal, .. } = light.kind {
        falloff *= normal.dot(-l).max(0.0);
    }
    if let Some((axis, scale, offset)) = cone {
        let a = (axis.dot(-l) * scale + offset).clamp(0.0, 1.0);
        falloff *= a * a;
    }
    LightSample {
        to_light: l,
        distance: dist,
        falloff,
    }
}
