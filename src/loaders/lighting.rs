//! The lighting a scene gets beyond its file's: the default environment of a
//! glTF file without lights, and `--environment` and `--background` for any
//! file (docs/materials.md, "Environment" and "Default lighting").

use glam::{DVec3, Vec3};

use super::Loaded;
use crate::scene::{Light, LightKind, Scene, ENVIRONMENT_SAMPLES};

/// The intensity of the environment that lights a glTF file without lights
/// (its radiance at the zenith): a white Lambert surface facing up returns
/// `0.87` of it, one facing sideways `0.6` (docs/materials.md).
pub const DEFAULT_ENVIRONMENT: f32 = 1.0;

/// The background of a glTF file lit by the default environment: a neutral
/// grey (linear), lighter than dark materials and darker than white ones, so
/// that both stand out from it.
pub const DEFAULT_BACKGROUND: [f32; 3] = [0.25, 0.25, 0.25];

/// `--environment` and `--background`, as the loader applies them.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Lighting {
    /// Add an environment of this intensity; a file lit by the default
    /// environment gets this one instead.
    pub environment: Option<f32>,
    /// The colour where camera rays miss (linear).
    pub background: Option<[f32; 3]>,
}

/// A white environment of `intensity` around world `+y`.
pub fn environment(intensity: f32) -> Light {
    Light {
        kind: LightKind::Environment {
            up: DVec3::Y,
            samples: ENVIRONMENT_SAMPLES,
        },
        intensity,
        ambient: Vec3::ZERO,
        diffuse: Vec3::ONE,
        specular: Vec3::ONE,
    }
}

/// Lights a scene without lights as a model viewer does: the default
/// environment alone (unshadowed, so that geometry enclosing the scene does
/// not block it) over a neutral background.
pub fn light_by_default(scene: &mut Scene) {
    scene.lights.push(environment(DEFAULT_ENVIRONMENT));
    scene.background = Vec3::from(DEFAULT_BACKGROUND);
}

/// Applies `lighting` to a loaded scene: the asked environment replaces the
/// default one, or joins the file's own lights.
pub fn apply(loaded: &mut Loaded, lighting: &Lighting) {
    if let Some(intensity) = lighting.environment {
        let lights = &mut loaded.scene.lights;
        if loaded.lit_by_default {
            lights.retain(|l| !matches!(l.kind, LightKind::Environment { .. }));
        }
        lights.push(environment(intensity));
    }
    if let Some(rgb) = lighting.background {
        loaded.scene.background = Vec3::from(rgb);
    }
}
