//! The flags of how a render looks, shared by `render`, `render --batch`,
//! `watch`, `farm slurm` and `merge`: the lighting added to the scene
//! (`--environment`, `--background`; docs/materials.md, "Environment") and
//! how the PNG output shows the linear image (`--exposure`, `--tonemap`).

use penumbra::loaders::lighting::Lighting;
use penumbra::tonemap::{Display, ToneMap};

/// `--environment` and `--background`.
#[derive(clap::Args, Clone, Copy, Debug, Default)]
pub struct LightingArgs {
    /// Add the environment light of this intensity (a studio sky over a
    /// darker ground, unshadowed; docs/materials.md, "Environment"); a glTF
    /// file without lights gets it instead of its default environment.
    #[arg(long, value_name = "INTENSITY", allow_hyphen_values = true,
          value_parser = parse_environment)]
    pub environment: Option<f32>,
    /// Colour where camera rays miss, linear R,G,B (default: the scene's;
    /// grey for a glTF file without lights).
    #[arg(long, value_name = "R,G,B", value_parser = parse_background)]
    pub background: Option<[f32; 3]>,
}

impl LightingArgs {
    /// What the loader applies.
    pub fn lighting(&self) -> Lighting {
        Lighting {
            environment: self.environment,
            background: self.background,
        }
    }

    /// The flags again, for a command line that forwards them (`farm slurm`).
    pub fn forwarded(&self) -> Vec<String> {
        let mut args = Vec::new();
        if let Some(e) = self.environment {
            args.push(format!("--environment={e}"));
        }
        if let Some([r, g, b]) = self.background {
            args.push(format!("--background={r},{g},{b}"));
        }
        args
    }
}

/// `--exposure` and `--tonemap`.
#[derive(clap::Args, Clone, Copy, Debug, Default)]
pub struct DisplayArgs {
    /// Exposure in stops: the PNG output's linear values are scaled by 2^EV
    /// before tone mapping (EXR output stays linear and untouched).
    #[arg(long, value_name = "EV", default_value_t = 0.0, allow_hyphen_values = true,
          value_parser = parse_exposure)]
    pub exposure: f32,
    /// Tone mapping of the PNG output: `none` (clamp to [0, 1]) or
    /// `pbr-neutral` (Khronos PBR Neutral; docs/materials.md). Default:
    /// `pbr-neutral` for a glTF file lit by the default environment, else
    /// `none`. EXR output stays linear and untouched.
    #[arg(long, value_name = "MAP", value_parser = |s: &str| s.parse::<ToneMap>())]
    pub tonemap: Option<ToneMap>,
}

impl DisplayArgs {
    /// The library's settings.
    pub fn display(&self) -> Display {
        Display {
            exposure: self.exposure,
            tonemap: self.tonemap,
        }
    }

    /// The flags again, as given, for a command line that forwards them.
    pub fn forwarded(&self) -> Vec<String> {
        let mut args = vec![format!("--exposure={}", self.exposure)];
        if let Some(t) = self.tonemap {
            args.push(format!("--tonemap={t}"));
        }
        args
    }

    /// The flags for a merge of parts, which knows no scene: the tone
    /// mapping resolved for the scene (`lit_by_default`).
    pub fn forwarded_to_merge(&self, lit_by_default: bool) -> Vec<String> {
        vec![
            format!("--exposure={}", self.exposure),
            format!("--tonemap={}", self.display().tonemap_for(lit_by_default)),
        ]
    }
}

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

/// `--exposure`: a finite number of stops in [-64, 64].
pub fn parse_exposure(s: &str) -> Result<f32, String> {
    match s.parse::<f32>() {
        Ok(ev) if ev.is_finite() && (-64.0..=64.0).contains(&ev) => Ok(ev),
        _ => Err("expected a finite number of stops in [-64, 64]".into()),
    }
}
