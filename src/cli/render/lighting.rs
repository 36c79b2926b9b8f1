//! `--environment` and `--background`: the environment light
//! (docs/materials.md, "Environment") and the colour where camera rays miss,
//! added to a loaded scene.

use glam::{DVec3, Vec3};
use penumbra::scene::{Light, LightKind, Scene, ENVIRONMENT_SAMPLES};

/// `--environment`: the environment's intensity, a finite number in
/// [0, 1e6] (its radiance at the zenith; white).
pub fn parse_environment(s: &str) -> Result<f32, String> {
    match s.parse::<f32>() {
        Ok(v) if v.is_finite() && (0.0..=1e6).contains(&v) => Ok(v),
        _ => Err("must be a finite intensity in [0, 1e6]".to_string()),
    }
}

/// `--background R,G,B`: three finite linear values in [0, 1e6].
pub fn parse_background(s: &str) -> Result<[f32; 3], String> {
    let bad = || "must be R,G,B: three finite linear values in [0, 1e6]".to_string();
    let parts: Vec<&str> = s.split(',').collect();
    if parts.len() != 3 {
        return Err(bad());
    }
    let mut rgb = [0.0f32; 3];
    for (c, p) in rgb.iter_mut().zip(parts) {
        match p.trim().parse::<f32>() {
            Ok(v) if v.is_finite() && (0.0..=1e6).contains(&v) => *c = v,
            _ => return Err(bad()),
        }
    }
    Ok(rgb)
}

/// Adds the environment of `intensity` (world +y up, white) to `scene`'s
/// lights, and sets its background.
pub fn apply(scene: &mut Scene, environment: Option<f32>, background: Option<[f32; 3]>) {
    if let Some(intensity) = environment {
        scene.lights.push(Light {
            kind: LightKind::Environment {
                up: DVec3::Y,
                samples: ENVIRONMENT_SAMPLES,
            },
            intensity,
            ambient: Vec3::ZERO,
            diffuse: Vec3::ONE,
            specular: Vec3::ONE,
        });
    }
    if let Some(rgb) = background {
        scene.background = Vec3::from(rgb);
    }
}
