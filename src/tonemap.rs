//! Exposure and tone mapping of an image for display (`render --exposure`,
//! `--tonemap`): applied to the PNG output only; EXR output stays linear.
//!
//! `PbrNeutral` is the Khronos PBR Neutral tone mapper, from its
//! specification (KhronosGroup/ToneMapping, `PBR_Neutral/README.md`,
//! "PBR Neutral Specification"), with `F90 = 0.04`, `K_s = 0.8 − F90`,
//! `K_d = 0.15`, for non-negative linear Rec. 709 colour `c`:
//!
//! ```text
//! x   = min(R, G, B)
//! f   = x − x²/(4·F90) if x ≤ 2·F90, else F90
//! p   = max(R − f, G − f, B − f)
//! p_n = 1 − (1 − K_s)²/(p + 1 − 2·K_s)
//! g   = 1/(K_d·(p − p_n) + 1)
//! out = c − f                                     if p ≤ K_s
//!       (c − f)·(p_n/p)·g + (p_n, p_n, p_n)·(1 − g)  otherwise
//! ```

use crate::frame::Image;
use crate::output::Format;

/// The tone mapping of `--tonemap`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ToneMap {
    /// None: the PNG encoder clamps to [0, 1] (the default for scenes with
    /// lights of their own).
    #[default]
    None,
    /// Khronos PBR Neutral.
    PbrNeutral,
}

impl std::str::FromStr for ToneMap {
    type Err = String;

    /// `none` or `pbr-neutral`.
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "none" => Ok(ToneMap::None),
            "pbr-neutral" => Ok(ToneMap::PbrNeutral),
            _ => Err("expected `none` or `pbr-neutral`".into()),
        }
    }
}

impl std::fmt::Display for ToneMap {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            ToneMap::None => "none",
            ToneMap::PbrNeutral => "pbr-neutral",
        })
    }
}

/// How an image is shown in a PNG file: `--exposure` and `--tonemap`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Display {
    /// Stops: linear values are scaled by `2^exposure`.
    pub exposure: f32,
    /// The tone mapping asked for; `None`: the scene's default
    /// ([`Display::tonemap_for`]).
    pub tonemap: Option<ToneMap>,
}

impl Display {
    /// The tone mapping of a scene: the one asked for, else PBR Neutral for a
    /// scene lit by the default environment (shown as model viewers show
    /// models) and none for a scene with lights of its own (its contract).
    pub fn tonemap_for(&self, lit_by_default: bool) -> ToneMap {
        self.tonemap.unwrap_or(match lit_by_default {
            true => ToneMap::PbrNeutral,
            false => ToneMap::None,
        })
    }

    /// `image` as a file of `format` holds it: exposed and tone-mapped in a
    /// PNG file, linear and untouched in an EXR file (borrowed when nothing
    /// changes).
    pub fn for_format<'a>(
        &self,
        image: &'a Image,
        format: Format,
        lit_by_default: bool,
    ) -> std::borrow::Cow<'a, Image> {
        let tonemap = self.tonemap_for(lit_by_default);
        if format == Format::Exr || (self.exposure == 0.0 && tonemap == ToneMap::None) {
            return std::borrow::Cow::Borrowed(image);
        }
        std::borrow::Cow::Owned(apply(image, self.exposure, tonemap))
    }
}

/// Khronos PBR Neutral of one linear colour (module documentation).
pub fn pbr_neutral(c: [f32; 3]) -> [f32; 3] {
    const F90: f32 = 0.04;
    const KS: f32 = 0.8 - F90;
    const KD: f32 = 0.15;
    let x = c[0].min(c[1]).min(c[2]);
    let f = if x <= 2.0 * F90 {
        x - x * x / (4.0 * F90)
    } else {
        F90
    };
    let d = c.map(|v| v - f);
    let p = d[0].max(d[1]).max(d[2]);
    if p <= KS {
        return d;
    }
    let pn = 1.0 - (1.0 - KS) * (1.0 - KS) / (p + 1.0 - 2.0 * KS);
    let g = 1.0 / (KD * (p - pn) + 1.0);
    d.map(|v| v * (pn / p) * g + pn * (1.0 - g))
}

/// `image` scaled by `2^exposure` and tone mapped (alpha as it is).
pub fn apply(image: &Image, exposure: f32, tonemap: ToneMap) -> Image {
    let scale = exposure.exp2();
    let pixels = image
        .pixels
        .iter()
        .map(|p| {
            let c = map([p[0], p[1], p[2]], scale, tonemap);
            [c[0], c[1], c[2], p[3]]
        })
        .collect();
    Image {
        width: image.width,
        height: image.height,
        pixels,
    }
}

/// One linear colour scaled by `scale` (`2^exposure`) and tone mapped.
pub fn map(c: [f32; 3], scale: f32, tonemap: ToneMap) -> [f32; 3] {
    let c = c.map(|v| v * scale);
    match tonemap {
        ToneMap::None => c,
        ToneMap::PbrNeutral => pbr_neutral(c.map(|v| v.max(0.0))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Values from the specification's cases, worked by hand.
    #[test]
    fn pbr_neutral_follows_its_specification() {
        // Below the compression (p ≤ 0.76): c − f, f = 0.04 for x > 0.08.
        let out = pbr_neutral([0.5, 0.3, 0.2]);
        for (o, want) in out.iter().zip([0.46, 0.26, 0.16]) {
            assert!((o - want).abs() < 1e-6, "{out:?}");
        }
        // x = 0.05 ≤ 0.08: f = 0.05 − 0.05²/0.16 = 0.034375.
        let out = pbr_neutral([0.05, 0.05, 0.05]);
        assert!((out[0] - 0.015625).abs() < 1e-7, "{out:?}");
        // White: p = 0.96, p_n = 1 − 0.24²/(0.96 + 1 − 1.52) = 1 − 0.0576/0.44;
        // a grey stays grey at p_n.
        let pn = 1.0 - 0.0576 / 0.44;
        for o in pbr_neutral([1.0; 3]) {
            assert!((o - pn).abs() < 1e-6, "{o} vs {pn}");
        }
        // Bright colours compress below 1 and desaturate towards p_n.
        let out = pbr_neutral([40.0, 10.0, 1.0]);
        assert!(out.iter().all(|&o| (0.0..1.0).contains(&o)), "{out:?}");
        assert!(out[0] - out[2] < 40.0 - 1.0);
    }

    #[test]
    fn exposure_scales_by_two_to_the_ev_and_keeps_alpha() {
        let image = Image {
            width: 1,
            height: 1,
            pixels: vec![[0.25, 0.5, 0.125, 0.5]],
        };
        let out = apply(&image, 2.0, ToneMap::None);
        assert_eq!(out.pixels, vec![[1.0, 2.0, 0.5, 0.5]]);
        let out = apply(&image, -1.0, ToneMap::PbrNeutral);
        assert_eq!(out.pixels[0][3], 0.5);
        let want = pbr_neutral([0.125, 0.25, 0.0625]);
        assert_eq!(&out.pixels[0][..3], &want);
    }
}
