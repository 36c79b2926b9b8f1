//! Texture sampling in `f64`, exactly as the contract in
//! [`crate::scene::texture`] writes it: texels decoded from sRGB before
//! filtering, the host's mip chain ([`Texture::mip_chain`]), nearest and
//! bilinear filters, nearest and linear mip selection, the wrap modes,
//! KHR_texture_transform, and the level of detail from ray cones
//! (Akenine-Möller et al., "Texture Level of Detail Strategies for
//! Real-Time Ray Tracing", Ray Tracing Gems, 2019, ch. 20). Also the
//! procedural coordinates of planes and spheres and the normal-map formula.
//!
//! The public functions here are what GPU agreement tests compare against:
//! [`Mips::new`] once per texture, then [`sample`] with a use, a uv and a
//! λ from [`lod`].

use glam::{DVec2, DVec3, DVec4};

use crate::scene::texture::{srgb_to_linear, Filter, MipLevel, Texture, TextureRef};

/// A texture's mip chain, built once (per [`super::World`]), with the
/// table that decodes its 8-bit values to linear.
#[derive(Clone, Debug)]
pub struct Mips {
    /// Level 0 first, down to 1×1 ([`Texture::mip_chain`]).
    pub levels: Vec<MipLevel>,
    /// Linear value of each byte of R, G and B (sRGB-decoded where the
    /// texture is sRGB, else `b/255`).
    rgb: [f64; 256],
}

impl Mips {
    /// The chain of `t` and its decoding table.
    pub fn new(t: &Texture) -> Mips {
        Mips {
            levels: t.mip_chain(),
            rgb: std::array::from_fn(|b| {
                if t.srgb {
                    srgb_to_linear(b as u8)
                } else {
                    b as f64 / 255.0
                }
            }),
        }
    }

    /// Width × height of level 0, the `w·h` of the level of detail.
    pub fn texel_count(&self) -> f64 {
        let l = &self.levels[0];
        f64::from(l.width) * f64::from(l.height)
    }

    /// Texel (`x`, `y`) of `level`, linear RGBA (indices already wrapped).
    pub fn texel(&self, level: usize, x: u32, y: u32) -> DVec4 {
        let l = &self.levels[level];
        let t = l.texels[(y * l.width + x) as usize];
        DVec4::new(
            self.rgb[t[0] as usize],
            self.rgb[t[1] as usize],
            self.rgb[t[2] as usize],
            f64::from(t[3]) / 255.0,
        )
    }
}

/// The filtered colour of one level at (already transformed) `uv`:
/// `Nearest` the texel containing the point, `Linear` bilinear between the
/// four texel centres around it (`x = u·w − ½`), every texel index wrapped
/// by the use's wrap modes.
pub fn sample_level(mips: &Mips, level: usize, filter: Filter, t: &TextureRef, uv: DVec2) -> DVec4 {
    let l = &mips.levels[level];
    let (w, h) = (l.width, l.height);
    let (wu, wv) = (t.sampler.wrap_u, t.sampler.wrap_v);
    let x = uv.x * f64::from(w);
    let y = uv.y * f64::from(h);
    match filter {
        Filter::Nearest => mips.texel(
            level,
            wu.apply(x.floor() as i64, w),
            wv.apply(y.floor() as i64, h),
        ),
        Filter::Linear => {
            let (x, y) = (x - 0.5, y - 0.5);
            let (x0, y0) = (x.floor(), y.floor());
            let (fx, fy) = (x - x0, y - y0);
            let (xa, xb) = (wu.apply(x0 as i64, w), wu.apply(x0 as i64 + 1, w));
            let (ya, yb) = (wv.apply(y0 as i64, h), wv.apply(y0 as i64 + 1, h));
            let top = mips.texel(level, xa, ya) * (1.0 - fx) + mips.texel(level, xb, ya) * fx;
            let bottom = mips.texel(level, xa, yb) * (1.0 - fx) + mips.texel(level, xb, yb) * fx;
            top * (1.0 - fy) + bottom * fy
        }
    }
}

/// Which levels a minified lookup at `lambda` reads and with what weight
/// on the second: `(k, k + 1, f)` blends level `k` by `1 − f` with level
/// `k + 1` by `f` (both clamped to the chain of `count` levels).
/// `mip = None` reads level 0, `Nearest` level `round(λ)` (ties to even,
/// as WGSL's `round`), `Linear` `⌊λ⌋` and `⌊λ⌋ + 1` by `fract(λ)`.
pub fn mip_levels(mip: Option<Filter>, lambda: f64, count: usize) -> (usize, usize, f64) {
    let last = count - 1;
    let clamp = |k: f64| (k.max(0.0) as usize).min(last);
    match mip {
        None => (0, 0, 0.0),
        Some(Filter::Nearest) => {
            let k = clamp(lambda.round_ties_even());
            (k, k, 0.0)
        }
        Some(Filter::Linear) => {
            let k = lambda.floor();
            (clamp(k), clamp(k + 1.0), lambda - k)
        }
    }
}

/// The texture use `t` at texture coordinates `uv` (before its transform)
/// and level of detail `lambda`, as linear RGBA: the transform applied,
/// then `λ ≤ 0` (or NaN) magnifies level 0 with the mag filter, `λ > 0`
/// minifies with the min filter on the levels [`mip_levels`] chooses.
pub fn sample(mips: &Mips, t: &TextureRef, uv: DVec2, lambda: f64) -> DVec4 {
    let uv = t.transform.apply(uv);
    if lambda.is_nan() || lambda <= 0.0 {
        return sample_level(mips, 0, t.sampler.mag, t, uv);
    }
    let (a, b, f) = mip_levels(t.sampler.mip, lambda, mips.levels.len());
    let ca = sample_level(mips, a, t.sampler.min, t, uv);
    if b == a || f == 0.0 {
        return ca;
    }
    ca * (1.0 - f) + sample_level(mips, b, t.sampler.min, t, uv) * f
}

/// The use-independent part of a primary hit's level of detail, for one
/// uv set: `log2(W / |n·d|) + ½·log2(A_uv / A_world)` with `W` the ray
/// cone's width at the hit, `n·d` the cosine between the geometric normal
/// and the ray (magnitude clamped to ≥ 1e-6) and `uv_per_world` the ratio
/// of uv area to world area (Ray Tracing Gems ch. 20, eq. 20.5's terms
/// without the texture's size).
pub fn lod_base(cone_width: f64, cos: f64, uv_per_world: f64) -> f64 {
    (cone_width / cos.abs().max(1e-6)).log2() + 0.5 * uv_per_world.log2()
}

/// λ of use `t` of a texture with chain `mips` at a hit with
/// [`lod_base`] `base`: `base + ½·log2(w·h) + log2(s)`, `s` the
/// transform's uv scale.
pub fn lod(base: f64, mips: &Mips, t: &TextureRef) -> f64 {
    base + 0.5 * mips.texel_count().log2() + t.transform.lod_bias()
}

/// The ray cone's width at distance `t` for a camera whose pixel spans
/// `spread` (perspective: the angle `2·tan(vfov/2)/height`, so `W = t·α`;
/// orthographic: the pixel's world height `2·half_height/height`, `W` that
/// height at any distance).
pub fn cone_width(spread: f64, orthographic: bool, t: f64) -> f64 {
    if orthographic {
        spread
    } else {
        spread * t
    }
}

/// Planar coordinates of world point `p` on a plane with unit normal `n`:
/// `(p·e_u, p·e_v)` with `e_u = normalize(a × n)`, `e_v = e_u × n`, `a`
/// `(0, 0, −1)` where `|n_y| > 0.999` else `(0, 1, 0)`. (Uv area per world
/// area is 1.)
pub fn plane_uv(n: DVec3, p: DVec3) -> DVec2 {
    let a = if n.y.abs() > 0.999 {
        DVec3::new(0.0, 0.0, -1.0)
    } else {
        DVec3::Y
    };
    let eu = a.cross(n).normalize();
    let ev = eu.cross(n);
    DVec2::new(p.dot(eu), p.dot(ev))
}

/// Latitude-longitude coordinates of point `p` on a sphere, and the uv
/// area per world area there: with `d = (p − centre)/r`,
/// `u = ½ − atan2(d_z, d_x)/(2π)`, `v = acos(d_y)/π`, and
/// `1/(2π² r² sin θ)` with `sin θ = max(sqrt(1 − d_y²), 1e-4)`.
pub fn sphere_uv(center: DVec3, radius: f64, p: DVec3) -> (DVec2, f64) {
    use std::f64::consts::PI;
    let d = (p - center) / radius;
    let dy = d.y.clamp(-1.0, 1.0);
    let uv = DVec2::new(0.5 - d.z.atan2(d.x) / (2.0 * PI), dy.acos() / PI);
    let sin = (1.0 - dy * dy).max(0.0).sqrt().max(1e-4);
    (uv, 1.0 / (2.0 * PI * PI * radius * radius * sin))
}

/// The normal a normal-map texel `rgb` (linear, in [0, 1]) with glTF's
/// `scale` gives at a point with shading normal `n` (before it faces the
/// viewer) and tangent `tangent` (xyz and the bitangent sign in w):
/// `t = normalize((2r − 1)·s, (2g − 1)·s, 2b − 1)`,
/// `T' = normalize(T − n(n·T))`, `B = w·(n × T')`, and
/// `normalize(t_x·T' + t_y·B + t_z·n)`. Returns `n` where there is no
/// tangent direction (`|T − n(n·T)|² ≤ 1e-20`: a zero tangent, as
/// generated for a mesh without uvs, or one along `n`), and where the
/// tilted normal is zero.
pub fn normal_mapped(n: DVec3, tangent: DVec4, rgb: DVec3, scale: f64) -> DVec3 {
    let t = 2.0 * rgb - DVec3::ONE;
    let t = DVec3::new(t.x * scale, t.y * scale, t.z).normalize_or_zero();
    let tan = tangent.truncate();
    let tn = tan - n * n.dot(tan);
    let len2 = tn.dot(tn);
    if len2.is_nan() || len2 <= 1e-20 {
        return n;
    }
    let tp = tn / len2.sqrt();
    let b = tangent.w * n.cross(tp);
    let m = (t.x * tp + t.y * b + t.z * n).normalize_or_zero();
    if m == DVec3::ZERO {
        n
    } else {
        m
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Sampler, UvTransform, Wrap};

    fn tex(width: u32, height: u32, texels: Vec<[u8; 4]>, srgb: bool) -> Mips {
        Mips::new(&Texture {
            label: "t".into(),
            file: None,
            width,
            height,
            texels,
            srgb,
        })
    }

    fn use_of(filter: Filter, wrap: Wrap) -> TextureRef {
        TextureRef {
            sampler: Sampler {
                mag: filter,
                min: filter,
                mip: None,
                wrap_u: wrap,
                wrap_v: wrap,
            },
            ..TextureRef::new(0)
        }
    }

    /// sRGB decoding written out (IEC 61966-2-1).
    fn decode(b: u8) -> f64 {
        let c = f64::from(b) / 255.0;
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    }

    fn close(a: DVec4, b: DVec4) {
        assert!((a - b).abs().max_element() < 1e-12, "{a} != {b}");
    }

    /// 2×2 sRGB: black, white / grey 188, dark 10 (sRGB's linear segment);
    /// alphas 0, 255, 51, 102.
    fn two_by_two() -> Mips {
        tex(
            2,
            2,
            vec![
                [0, 0, 0, 0],
                [255, 255, 255, 255],
                [188, 188, 188, 51],
                [10, 10, 10, 102],
            ],
            true,
        )
    }

    #[test]
    fn nearest_reads_the_texel_containing_the_point_decoded() {
        let m = two_by_two();
        let t = use_of(Filter::Nearest, Wrap::Repeat);
        let g = decode(188);
        close(sample(&m, &t, DVec2::new(0.25, 0.25), 0.0), DVec4::ZERO);
        close(sample(&m, &t, DVec2::new(0.99, 0.01), 0.0), DVec4::ONE);
        close(
            sample(&m, &t, DVec2::new(0.3, 0.8), 0.0),
            DVec4::new(g, g, g, 0.2),
        );
        // v = 1 is the bottom row: (0.9, 0.6) is texel (1, 1).
        let d = 10.0 / 255.0 / 12.92;
        close(
            sample(&m, &t, DVec2::new(0.9, 0.6), 0.0),
            DVec4::new(d, d, d, 0.4),
        );
        // Texel boundaries belong to the texel on their right / below.
        close(sample(&m, &t, DVec2::new(0.5, 0.0), 0.0), DVec4::ONE);
    }

    #[test]
    fn bilinear_filters_linear_values() {
        let m = two_by_two();
        let t = use_of(Filter::Linear, Wrap::ClampToEdge);
        // Halfway between the black and white texel centres: linear 0.5
        // (not sRGB's 0.5 grey, which would be 0.214).
        close(
            sample(&m, &t, DVec2::new(0.5, 0.25), 0.0),
            DVec4::splat(0.5),
        );
        // (0.375, 0.625): x = 0.25, y = 0.75 in texel-centre units.
        let (g, d) = (decode(188), decode(10));
        let top = 0.75 * 0.0 + 0.25 * 1.0;
        let bottom = 0.75 * g + 0.25 * d;
        let a = 0.25 * (0.75 * 0.0 + 0.25 * 1.0) + 0.75 * (0.75 * 0.2 + 0.25 * 0.4);
        let rgb = 0.25 * top + 0.75 * bottom;
        close(
            sample(&m, &t, DVec2::new(0.375, 0.625), 0.0),
            DVec4::new(rgb, rgb, rgb, a),
        );
        // At a texel centre bilinear is that texel.
        close(
            sample(&m, &t, DVec2::new(0.25, 0.75), 0.0),
            DVec4::new(g, g, g, 0.2),
        );
    }

    /// A 4×1 linear ramp: red 0, 85, 170, 255.
    fn ramp() -> Mips {
        tex(
            4,
            1,
            [0u8, 85, 170, 255].map(|r| [r, 0, 0, 255]).to_vec(),
            false,
        )
    }

    fn red(m: &Mips, t: &TextureRef, u: f64) -> f64 {
        sample(m, t, DVec2::new(u, 0.5), 0.0).x
    }

    #[test]
    fn wrap_modes_read_the_tiles_they_promise() {
        let m = ramp();
        let r = |k: u8| f64::from(k) / 255.0;
        let (n, l) = (Filter::Nearest, Filter::Linear);
        // u = −0.125 is texel −1; u = 1.125 is texel 4.
        assert_eq!(red(&m, &use_of(n, Wrap::Repeat), -0.125), r(255));
        assert_eq!(red(&m, &use_of(n, Wrap::Repeat), 1.125), r(0));
        assert_eq!(red(&m, &use_of(n, Wrap::Repeat), 2.375), r(85));
        assert_eq!(red(&m, &use_of(n, Wrap::MirroredRepeat), -0.125), r(0));
        assert_eq!(red(&m, &use_of(n, Wrap::MirroredRepeat), -0.375), r(85));
        assert_eq!(red(&m, &use_of(n, Wrap::MirroredRepeat), 1.125), r(255));
        assert_eq!(red(&m, &use_of(n, Wrap::MirroredRepeat), 1.875), r(0));
        assert_eq!(red(&m, &use_of(n, Wrap::ClampToEdge), -3.0), r(0));
        assert_eq!(red(&m, &use_of(n, Wrap::ClampToEdge), 7.5), r(255));
        // Bilinear at u = 0 blends texel −1 and texel 0 half and half.
        assert_eq!(
            red(&m, &use_of(l, Wrap::Repeat), 0.0),
            0.5 * (r(255) + r(0))
        );
        assert_eq!(red(&m, &use_of(l, Wrap::MirroredRepeat), 0.0), r(0));
        assert_eq!(red(&m, &use_of(l, Wrap::ClampToEdge), 1.0), r(255));
        // v wraps on its own: the same ramp standing up (1×4), sampled
        // at v = −0.125, with u clamped and v repeating.
        let col = tex(
            1,
            4,
            [0u8, 85, 170, 255].map(|g| [0, g, 0, 255]).to_vec(),
            false,
        );
        let mut t = use_of(n, Wrap::ClampToEdge);
        t.sampler.wrap_v = Wrap::Repeat;
        assert_eq!(sample(&col, &t, DVec2::new(-5.0, -0.125), 0.0).y, r(255));
        t.sampler.wrap_v = Wrap::MirroredRepeat;
        assert_eq!(sample(&col, &t, DVec2::new(-5.0, -0.125), 0.0).y, r(0));
    }

    #[test]
    fn transform_moves_uv_before_the_lookup() {
        let m = ramp();
        let r = |k: u8| f64::from(k) / 255.0;
        let mut t = use_of(Filter::Nearest, Wrap::Repeat);
        // S·uv = (0.2, 0.5), + T = (0.45, 0.5): texel 1.
        t.transform = UvTransform {
            offset: DVec2::new(0.25, 0.0),
            rotation: 0.0,
            scale: DVec2::new(2.0, 1.0),
        };
        assert_eq!(red(&m, &t, 0.1), r(85));
        // A quarter turn maps (u, v) to (v, −u): (0.1, 0.6) reads u = 0.6,
        // texel 2.
        t.transform = UvTransform {
            offset: DVec2::ZERO,
            rotation: std::f64::consts::FRAC_PI_2,
            scale: DVec2::ONE,
        };
        assert_eq!(sample(&m, &t, DVec2::new(0.1, 0.6), 0.0).x, r(170));
    }

    #[test]
    fn mip_level_choice() {
        use Filter::{Linear, Nearest};
        assert_eq!(mip_levels(None, 3.7, 5), (0, 0, 0.0));
        assert_eq!(mip_levels(Some(Nearest), 1.4, 5), (1, 1, 0.0));
        assert_eq!(mip_levels(Some(Nearest), 1.6, 5), (2, 2, 0.0));
        // Ties to even, as WGSL's round.
        assert_eq!(mip_levels(Some(Nearest), 1.5, 5), (2, 2, 0.0));
        assert_eq!(mip_levels(Some(Nearest), 2.5, 5), (2, 2, 0.0));
        assert_eq!(mip_levels(Some(Nearest), 9.0, 5), (4, 4, 0.0));
        assert_eq!(mip_levels(Some(Linear), 1.25, 5), (1, 2, 0.25));
        assert_eq!(mip_levels(Some(Linear), 3.5, 5), (3, 4, 0.5));
        assert_eq!(mip_levels(Some(Linear), 6.0, 5), (4, 4, 0.0));

        // A 4×4 checker of alpha 0 and 255: level 0 has alpha 0 at texel
        // (0, 0); level 1 (2×2) and 2 (1×1) are the mean, 127.5 rounded to
        // 128.
        let texels = (0..16)
            .map(|i| [0, 0, 0, if (i % 4 + i / 4) % 2 == 0 { 0 } else { 255 }])
            .collect();
        let m = tex(4, 4, texels, false);
        let mean = ((0.0 + 1.0 + 0.0 + 1.0) / 4.0 * 255.0_f64).round() / 255.0;
        let at = DVec2::new(0.125, 0.125); // texel (0, 0)'s centre
        let mut t = use_of(Filter::Linear, Wrap::Repeat);
        t.sampler.mip = Some(Linear);
        assert_eq!(sample(&m, &t, at, 0.0).w, 0.0);
        assert!((sample(&m, &t, at, 0.25).w - 0.25 * mean).abs() < 1e-15);
        assert!((sample(&m, &t, at, 1.5).w - mean).abs() < 1e-15);
        t.sampler.mip = Some(Nearest);
        assert_eq!(sample(&m, &t, at, 0.4).w, 0.0);
        assert!((sample(&m, &t, at, 0.6).w - mean).abs() < 1e-15);
        t.sampler.mip = None;
        assert_eq!(sample(&m, &t, at, 5.0).w, 0.0);
        // Minified with nearest min filter on level 0: texel (1, 0).
        t.sampler.min = Filter::Nearest;
        assert_eq!(sample(&m, &t, DVec2::new(0.3, 0.1), 2.0).w, 1.0);
    }

    #[test]
    fn level_of_detail_terms() {
        // W / cos = 0.1 / 0.5, uv per world 1/4, a 64×64 texture scaled 4×
        // in uv (log2 s = 2): log2(0.2) − 1 + 6 + 2.
        let m = tex(64, 64, vec![[0; 4]; 64 * 64], false);
        let mut t = TextureRef::new(0);
        t.transform.scale = DVec2::new(4.0, 4.0);
        let want = 0.2f64.log2() - 1.0 + 6.0 + 2.0;
        let got = lod(lod_base(0.1, -0.5, 0.25), &m, &t);
        assert!((got - want).abs() < 1e-12, "{got} {want}");
        // Grazing: the cosine is clamped to 1e-6.
        assert!((lod_base(1.0, 0.0, 1.0) - 1e6f64.log2()).abs() < 1e-9);
        assert!((cone_width(0.01, false, 30.0) - 0.3).abs() < 1e-15);
        assert_eq!(cone_width(0.01, true, 30.0), 0.01);
    }

    #[test]
    fn plane_and_sphere_uv_conventions() {
        let p = DVec3::new(2.0, 0.0, 3.0);
        // The ground: u = x, v = z (either side).
        assert!((plane_uv(DVec3::Y, p) - DVec2::new(2.0, 3.0)).length() < 1e-15);
        assert!((plane_uv(-DVec3::Y, p) - DVec2::new(-2.0, 3.0)).length() < 1e-15);
        // A wall facing +Z: u = x, v = −y.
        let w = DVec3::new(2.0, 3.0, 0.0);
        assert!((plane_uv(DVec3::Z, w) - DVec2::new(2.0, -3.0)).length() < 1e-15);

        use std::f64::consts::PI;
        let c = DVec3::new(1.0, 2.0, 3.0);
        let r = 2.0;
        let uv = |d: DVec3| sphere_uv(c, r, c + r * d);
        // +X on the equator: u = ½, v = ½; +Z is a quarter to the left of
        // it seen from outside, −Z a quarter to the right.
        assert!((uv(DVec3::X).0 - DVec2::new(0.5, 0.5)).length() < 1e-15);
        assert!((uv(DVec3::Z).0 - DVec2::new(0.25, 0.5)).length() < 1e-15);
        assert!((uv(-DVec3::Z).0 - DVec2::new(0.75, 0.5)).length() < 1e-15);
        // The +Y pole is v = 0, −Y v = 1; the seam is at −X.
        assert!(uv(DVec3::Y).0.y.abs() < 1e-15);
        assert!((uv(-DVec3::Y).0.y - 1.0).abs() < 1e-15);
        let e = 1e-9;
        assert!(uv(DVec3::new(-1.0, 0.0, e).normalize()).0.x < 1e-9);
        assert!(uv(DVec3::new(-1.0, 0.0, -e).normalize()).0.x > 1.0 - 1e-9);
        // Uv area per world area: 1/(2π² r² sin θ), θ from +Y.
        assert!((uv(DVec3::X).1 - 1.0 / (2.0 * PI * PI * r * r)).abs() < 1e-15);
        let d = DVec3::new(0.6, 0.8, 0.0);
        assert!((uv(d).1 - 1.0 / (2.0 * PI * PI * r * r * 0.6)).abs() < 1e-12);
        assert!((uv(d).0.y - 0.8f64.acos() / PI).abs() < 1e-15);
    }

    #[test]
    fn normal_map_tilts_by_the_texel_angle() {
        let n = DVec3::Z;
        let th = 0.3f64;
        let rgb = (DVec3::new(th.sin(), 0.0, th.cos()) + 1.0) * 0.5;
        // Tangent +X: the tilt is towards +X by θ.
        let m = normal_mapped(n, DVec4::new(1.0, 0.0, 0.0, 1.0), rgb, 1.0);
        assert!((m - DVec3::new(th.sin(), 0.0, th.cos())).length() < 1e-12);
        // A tangent not orthogonal to n is made so first.
        let m = normal_mapped(n, DVec4::new(2.0, 0.0, 5.0, 1.0), rgb, 1.0);
        assert!((m - DVec3::new(th.sin(), 0.0, th.cos())).length() < 1e-12);
        // Scale 2 doubles the tangent-plane part: tan θ' = 2 tan θ.
        let m = normal_mapped(n, DVec4::new(1.0, 0.0, 0.0, 1.0), rgb, 2.0);
        assert!((m.x.atan2(m.z) - (2.0 * th.tan()).atan()).abs() < 1e-12);
        // Green tilts along B = w·(n × T) = +Y for w = 1, −Y for w = −1.
        let green = (DVec3::new(0.0, th.sin(), th.cos()) + 1.0) * 0.5;
        let m = normal_mapped(n, DVec4::new(1.0, 0.0, 0.0, 1.0), green, 1.0);
        assert!((m - DVec3::new(0.0, th.sin(), th.cos())).length() < 1e-12);
        let m = normal_mapped(n, DVec4::new(1.0, 0.0, 0.0, -1.0), green, 1.0);
        assert!((m - DVec3::new(0.0, -th.sin(), th.cos())).length() < 1e-12);
        // No tangent (zeros, or along n): n stays.
        assert_eq!(normal_mapped(n, DVec4::ZERO, rgb, 1.0), n);
        assert_eq!(
            normal_mapped(n, DVec4::new(0.0, 0.0, 3.0, 1.0), rgb, 1.0),
            n
        );
        // The flat texel (½, ½, 1) leaves n.
        let m = normal_mapped(
            n,
            DVec4::new(1.0, 0.0, 0.0, 1.0),
            DVec3::new(0.5, 0.5, 1.0),
            1.0,
        );
        assert!((m - n).length() < 1e-15);
    }
}
