//! Textures: images that scale a material's colours, give a surface its
//! alpha, tilt its normal or make it glow, and how a surface point looks one
//! up (its sampler, texture coordinates and their transform).
//!
//! This module is the one definition of texture sampling; the GPU
//! (`shaders/textures.wgsl`) and the f64 reference (`crate::reference`)
//! implement exactly what is written here:
//!
//! - **Texels.** A texture is RGBA8, row 0 at the top: texture coordinate
//!   `v = 0` is the top edge, `v = 1` the bottom (glTF's convention), `u = 0`
//!   the left edge. Texel `(x, y)` covers `[x, x+1) × [y, y+1)` in texel
//!   units, so its centre is at `((x + ½)/w, (y + ½)/h)` in uv.
//! - **Colour space.** Where [`Texture::srgb`] is set (colour textures:
//!   base colour, diffuse, emission) the RGB of each texel is decoded from
//!   sRGB to linear ([`srgb_to_linear`]) *before* filtering; alpha and
//!   non-colour textures (normal maps) are linear.
//! - **Mip-maps** ([`Texture::mip_chain`]): level `k + 1` is
//!   `max(1, ⌊w_k/2⌋) × max(1, ⌊h_k/2⌋)`; each of its texels is the mean of
//!   the 2×2 texels `(2x..2x+1, 2y..2y+1)` of level `k` (clamped to level
//!   `k`'s last row and column), averaged in linear space and re-encoded to
//!   8 bits (sRGB textures: to sRGB) with rounding to nearest.
//! - **Level of detail** λ comes from ray cones (Akenine-Möller et al.,
//!   "Texture Level of Detail Strategies for Real-Time Ray Tracing", Ray
//!   Tracing Gems 2019, ch. 20) for primary hits:
//!   `λ = log2(W / |n·d|) + ½·log2(A_uv / A_world) + ½·log2(w·h) + log2(s)`
//!   with `W` the cone's width at the hit: `t·α` for a perspective camera,
//!   `t` the distance along the unit ray and `α = 2·tan(vfov/2)/height` the
//!   angle one pixel spans (the small-angle form); the pixel's world height
//!   `2·half_height/height` for an orthographic one. `n·d` is the cosine
//!   between the geometric normal and the ray (its magnitude clamped to at
//!   least 1e-6), `A_uv/A_world` the ratio of
//!   the primitive's uv area to its world area in the use's uv set, before
//!   the transform (a triangle's
//!   `|(uv₁ − uv₀) × (uv₂ − uv₀)| / |(p₁ − p₀) × (p₂ − p₀)|`; zero uv area
//!   gives λ = −∞, magnification), `w·h` the level-0 size and
//!   `s` the uv scale of the transform (`sqrt|det|` of its 2×2 part).
//!   Every texture of a primary hit (Phong textures, normal map, emission)
//!   is sampled at that hit's λ; traversal (alpha tests) samples at λ = 0.
//! - **Filtering.** `λ ≤ 0` magnifies with [`Sampler::mag`]; `λ > 0`
//!   minifies with [`Sampler::min`] on the level chosen by
//!   [`Sampler::mip`]: `None` level 0; `Nearest` level `round(λ)`, ties
//!   to even as WGSL's `round` (clamped to the chain); `Linear` the blend
//!   of levels `⌊λ⌋` and `⌊λ⌋ + 1` by `fract(λ)` (clamped). `Nearest` reads the texel that
//!   contains the point; `Linear` is bilinear between the four texel
//!   centres around it (OpenGL's rules: `x = u·w − ½`).
//! - **Wrapping** applies to every texel coordinate separately
//!   ([`Wrap::apply`]).
//! - **Transform** ([`UvTransform`]): KHR_texture_transform,
//!   `uv' = T·R·S·uv` with `R = [[cos r, sin r], [−sin r, cos r]]`.
//!
//! What a surface point's texture coordinates, colour and normal are:
//!
//! - **Triangles** interpolate their vertices' uv sets, colours and tangents
//!   with the barycentrics `(1 − u − v, u, v)`; without a set, uv is (0, 0),
//!   without colours the colour is (1, 1, 1, 1).
//! - **Planes** have planar coordinates in world units: with `a = (0, 0, −1)`
//!   where `|n_y| > 0.999`, else `a = (0, 1, 0)`, the axes are
//!   `e_u = normalize(a × n)` and `e_v = e_u × n`, and
//!   `uv = (p·e_u, p·e_v)` for the world point `p`. The ground plane
//!   `n = +Y` thus has `u = x`, `v = z`; a wall facing +Z has `u = x`,
//!   `v = −y` (upright seen from the front). `A_uv/A_world = 1`.
//! - **Spheres** have latitude-longitude coordinates: with
//!   `d = (p − centre)/r`, `u = ½ − atan2(d_z, d_x)/(2π)` and
//!   `v = acos(d_y)/π` (v = 0 at the +Y pole, the seam at −X, u growing
//!   to the right seen from outside); `A_uv/A_world = 1/(2π² r² sin θ)`
//!   with `sin θ = max(sqrt(1 − d_y²), 1e-4)`.
//! - **Normal maps**: the texel's `t = 2·rgb − 1` scaled to
//!   `(t_x·s, t_y·s, t_z)` (glTF's `scale` s) and normalised; with the
//!   interpolated shading normal `n` (before it is turned to face the
//!   viewer) and the interpolated tangent `(T, w)` (both as interpolated,
//!   not renormalised before this formula): `T' = normalize(T − n(n·T))`,
//!   `B = w·(n × T')`, the new normal `normalize(t_x·T' + t_y·B + t_z·n)`,
//!   then turned to face the viewer like any shading normal; where
//!   `|T − n(n·T)|² ≤ 1e-20` (a zero tangent, as generated for a mesh
//!   without uvs, or one along `n`) the normal stays `n`. It is sampled
//!   at the primary hit's λ. Only meshes with [`crate::scene::Mesh::tangents`]
//!   can have a normal map (`Scene::validate` refuses it elsewhere).
//! - **Emission** `emission × texture.rgb` is added once to each sample's
//!   colour, with the ambient terms; shadows do not dim it.
//! - **Alpha** `opacity × opacity_texture.a × colour.a` is tested in
//!   traversal, for camera and shadow rays alike, at λ = 0 (the mag filter).
//!   A `Mask` point is there when alpha ≥ cutoff; a `Blend` point when
//!   alpha > ξ with `ξ = unit_float(hash3(pixel, primitive, seed ^ stream))`
//!   (`crate::reference::sampling`: `unit_float(h) = (h >> 8)·2⁻²⁴`,
//!   `pixel = y·width + x`), the stream `0x0b1e_0000 + pass` for
//!   camera rays and `0x0b1f_0000 + pass` for shadow rays (one ξ for all
//!   lights and light samples of a pass). `primitive` is the
//!   triangle's index over all triangles as the GPU lays them out
//!   (`render::layout::primitives`: objects in order, each mesh's
//!   triangles in order). Only meshes and triangles can be cut out:
//!   `Scene::validate` refuses an alpha mode other than `Opaque` on planes
//!   and spheres (glTF, where alpha comes from, has only triangles).

use std::path::PathBuf;

use glam::{DMat3, DVec2};

/// Index into [`crate::scene::Scene::textures`].
pub type TextureId = usize;

/// An RGBA8 image, row 0 at the top (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    /// What it is called in messages: the image file, or the glTF file and
    /// its field (`Duck.gltf images[0]`).
    pub label: String,
    /// The file the texels came from, for `penumbra watch` (`None`:
    /// embedded in another file).
    pub file: Option<PathBuf>,
    /// Width in texels, ≥ 1.
    pub width: u32,
    /// Height in texels, ≥ 1.
    pub height: u32,
    /// `width × height` texels, row by row from the top.
    pub texels: Vec<[u8; 4]>,
    /// RGB is sRGB-encoded (colour textures), decoded to linear before
    /// filtering; alpha is always linear.
    pub srgb: bool,
}

/// One level of a mip chain.
#[derive(Clone, Debug, PartialEq)]
pub struct MipLevel {
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// Texels, row by row from the top.
    pub texels: Vec<[u8; 4]>,
}

/// sRGB's decoding curve (IEC 61966-2-1) of an 8-bit value, to linear.
pub fn srgb_to_linear(c: u8) -> f64 {
    let c = f64::from(c) / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// sRGB's encoding curve of a linear value in [0, 1], to 8 bits (rounded).
pub fn linear_to_srgb8(c: f64) -> u8 {
    let c = c.clamp(0.0, 1.0);
    let s = if c <= 0.003_130_8 {
        c * 12.92
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0).round() as u8
}

/// The mean of four 8-bit linear values, rounded to nearest (ties up): the
/// plain formula `round((a/255 + b/255 + c/255 + d/255) / 4 · 255)` in
/// `f64`, without it where the sum leaves no tie. Away from a tie the mean
/// is at least ¼ from a rounding boundary, far beyond the formula's
/// rounding errors (about 1e-13), so the integer mean is the same; at a
/// tie (a sum ≡ 2 mod 4) the formula itself decides, as it did.
pub fn linear_mean8(q: [u8; 4]) -> u8 {
    let sum = q.map(u32::from).iter().sum::<u32>();
    if sum % 4 != 2 {
        return ((sum + 2) / 4) as u8;
    }
    let unorm = |b: u8| f64::from(b) / 255.0;
    let mean = (unorm(q[0]) + unorm(q[1]) + unorm(q[2]) + unorm(q[3])) / 4.0;
    (mean * 255.0).round() as u8
}

/// [`linear_to_srgb8`] without a `powf`: the mip chain's sRGB encode
/// (issue 39). For every code `k` in 1..=255, the smallest `f64` that
/// [`linear_to_srgb8`] encodes to `k` or more, found once by a binary
/// search over the bit patterns of the doubles in [0, 1] (which order as
/// their values do); a value's code is then the number of thresholds at or
/// below it, which is [`linear_to_srgb8`]'s own result wherever that is
/// non-decreasing (the test `srgb8_encoder_is_linear_to_srgb8` checks it
/// around every threshold and on random values).
#[derive(Debug)]
pub struct Srgb8Encoder {
    /// `bounds[k]` for `k` ≥ 1: the threshold of code `k`, times 4 (the
    /// sum of four values, whose mean is encoded); `bounds[0]` is −∞.
    bounds: [f64; 256],
    /// [`srgb_to_linear`] of each byte.
    linear: [f64; 256],
}

impl Srgb8Encoder {
    /// The thresholds, computed on first use.
    pub fn get() -> &'static Srgb8Encoder {
        static ENCODER: std::sync::OnceLock<Srgb8Encoder> = std::sync::OnceLock::new();
        ENCODER.get_or_init(|| {
            let mut bounds = [f64::NEG_INFINITY; 256];
            for (k, bound) in bounds.iter_mut().enumerate().skip(1) {
                // The least x in [0, 1] with linear_to_srgb8(x) ≥ k
                // (linear_to_srgb8(1) = 255, so there is one).
                let (mut lo, mut hi) = (0u64, 1.0f64.to_bits());
                while lo < hi {
                    let mid = lo + (hi - lo) / 2;
                    if usize::from(linear_to_srgb8(f64::from_bits(mid))) >= k {
                        hi = mid;
                    } else {
                        lo = mid + 1;
                    }
                }
                *bound = 4.0 * f64::from_bits(lo);
            }
            Srgb8Encoder {
                bounds,
                linear: std::array::from_fn(|b| srgb_to_linear(b as u8)),
            }
        })
    }

    /// [`linear_to_srgb8`] of `x` in [0, 1].
    pub fn encode(&self, x: f64) -> u8 {
        self.encode_sum(4.0 * x)
    }

    /// [`linear_to_srgb8`] of `sum / 4` (exact: a power of two).
    fn encode_sum(&self, sum: f64) -> u8 {
        let mut k = 0;
        for step in [128, 64, 32, 16, 8, 4, 2, 1] {
            if self.bounds[k + step] <= sum {
                k += step;
            }
        }
        k as u8
    }

    /// The mip texel over four texels of an sRGB texture: RGB the mean in
    /// linear light re-encoded to sRGB, alpha the linear mean
    /// ([`linear_mean8`]).
    pub fn mean(&self, q: [[u8; 4]; 4]) -> [u8; 4] {
        let l = |t: [u8; 4], c: usize| self.linear[usize::from(t[c])];
        let rgb = |c| self.encode_sum(l(q[0], c) + l(q[1], c) + l(q[2], c) + l(q[3], c));
        [
            rgb(0),
            rgb(1),
            rgb(2),
            linear_mean8([q[0][3], q[1][3], q[2][3], q[3][3]]),
        ]
    }
}

impl Texture {
    /// The mip chain, level 0 first, down to 1×1 (module docs: how each
    /// level is made).
    pub fn mip_chain(&self) -> Vec<MipLevel> {
        let mut levels = Vec::new();
        self.for_each_mip_level(|width, height, texels| {
            levels.push(MipLevel {
                width,
                height,
                texels: texels.to_vec(),
            })
        });
        levels
    }

    /// Calls `f(width, height, texels)` with each level of
    /// [`Texture::mip_chain`] in turn, holding only the level before it:
    /// level 0 is the texture's own texels, not a copy, so that a large
    /// texture is not held twice while it is uploaded.
    pub fn for_each_mip_level(&self, mut f: impl FnMut(u32, u32, &[[u8; 4]])) {
        f(self.width, self.height, &self.texels);
        let mut prev: Option<MipLevel> = None;
        loop {
            let (width, height, texels) = match &prev {
                Some(p) => (p.width, p.height, &p.texels[..]),
                None => (self.width, self.height, &self.texels[..]),
            };
            if width == 1 && height == 1 {
                break;
            }
            let next = self.half(width, height, texels);
            f(next.width, next.height, &next.texels);
            prev = Some(next);
        }
    }

    /// The level after a `width` × `height` level of `texels`: each texel
    /// the mean of the four under it (edges clamped), in linear light for
    /// the colour channels of an sRGB texture.
    ///
    /// Bit for bit what the plain formula gives (the test `half_is_the_plain_formula`
    /// keeps it as the reference): the colour channels of an sRGB texture sum
    /// the same four `f64` values of [`srgb_to_linear`] in the same order
    /// and encode the mean by [`Srgb8Encoder`]'s exact thresholds instead of
    /// a `powf` (issue 39: the `powf` and `round` were most of the mip
    /// chain's time); linear channels take the integer mean
    /// ([`linear_mean8`]). Rows in parallel: no level depends on the order.
    fn half(&self, width: u32, height: u32, texels: &[[u8; 4]]) -> MipLevel {
        use rayon::prelude::*;
        let (w, h) = ((width / 2).max(1), (height / 2).max(1));
        let encoder = Srgb8Encoder::get();
        let srgb = self.srgb;
        let (width, height) = (width as usize, height as usize);
        let mut out = vec![[0u8; 4]; w as usize * h as usize];
        out.par_chunks_mut(w as usize)
            .enumerate()
            .for_each(|(y, row)| {
                let y0 = (2 * y).min(height - 1);
                let y1 = (2 * y + 1).min(height - 1);
                let top = &texels[y0 * width..(y0 + 1) * width];
                let bottom = &texels[y1 * width..(y1 + 1) * width];
                for (x, texel) in row.iter_mut().enumerate() {
                    let x0 = (2 * x).min(width - 1);
                    let x1 = (2 * x + 1).min(width - 1);
                    // The order of the sum: (0, 0), (1, 0), (0, 1), (1, 1).
                    let q = [top[x0], top[x1], bottom[x0], bottom[x1]];
                    *texel = match srgb {
                        true => encoder.mean(q),
                        false => std::array::from_fn(|c| {
                            linear_mean8([q[0][c], q[1][c], q[2][c], q[3][c]])
                        }),
                    };
                }
            });
        MipLevel {
            width: w,
            height: h,
            texels: out,
        }
    }

    /// Bytes of the texture with its whole mip chain on the device (8 a
    /// texel: the GPU stores linear RGBA16, `render::layout::textures`).
    pub fn device_bytes(&self) -> u64 {
        Texture::device_bytes_of(self.width, self.height)
    }

    /// [`Texture::device_bytes`] of a `width` × `height` texture, known
    /// from an image's header before it is decoded.
    pub fn device_bytes_of(width: u32, height: u32) -> u64 {
        let (mut w, mut h, mut n) = (u64::from(width), u64::from(height), 0);
        loop {
            n += w * h;
            if w == 1 && h == 1 {
                break;
            }
            (w, h) = ((w / 2).max(1), (h / 2).max(1));
        }
        n * 8
    }
}

/// Texel filter.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Filter {
    /// The texel that contains the point.
    Nearest,
    /// Bilinear between the four nearest texel centres.
    #[default]
    Linear,
}

/// What a texel coordinate outside the image reads.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Wrap {
    /// The image tiles: `x mod n`.
    #[default]
    Repeat,
    /// Every other tile is mirrored.
    MirroredRepeat,
    /// The edge texel: `clamp(x, 0, n − 1)`.
    ClampToEdge,
}

impl Wrap {
    /// Texel index `i` (any integer) wrapped into `0..n`.
    pub fn apply(self, i: i64, n: u32) -> u32 {
        let n = i64::from(n);
        let wrapped = match self {
            Wrap::Repeat => i.rem_euclid(n),
            Wrap::MirroredRepeat => {
                let m = i.rem_euclid(2 * n);
                if m < n {
                    m
                } else {
                    2 * n - 1 - m
                }
            }
            Wrap::ClampToEdge => i.clamp(0, n - 1),
        };
        wrapped as u32
    }
}

/// How a texture is filtered and wrapped. The default is glTF's usual
/// choice where a file names none: trilinear, repeating.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Sampler {
    /// Filter when magnified (λ ≤ 0).
    pub mag: Filter,
    /// Filter within a level when minified (λ > 0).
    pub min: Filter,
    /// Between mip levels when minified; `None`: level 0 only.
    pub mip: Option<Filter>,
    /// Along u (glTF's wrapS).
    pub wrap_u: Wrap,
    /// Along v (glTF's wrapT).
    pub wrap_v: Wrap,
}

impl Default for Sampler {
    fn default() -> Self {
        Sampler {
            mag: Filter::Linear,
            min: Filter::Linear,
            mip: Some(Filter::Linear),
            wrap_u: Wrap::Repeat,
            wrap_v: Wrap::Repeat,
        }
    }
}

/// KHR_texture_transform: `uv' = T·R·S·uv`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UvTransform {
    /// Translation T.
    pub offset: DVec2,
    /// Rotation r in radians (counter-clockwise in uv).
    pub rotation: f64,
    /// Scale S.
    pub scale: DVec2,
}

impl Default for UvTransform {
    fn default() -> Self {
        UvTransform {
            offset: DVec2::ZERO,
            rotation: 0.0,
            scale: DVec2::ONE,
        }
    }
}

impl UvTransform {
    /// The transform as a 3×3 matrix acting on `(u, v, 1)`.
    pub fn matrix(&self) -> DMat3 {
        let (s, c) = self.rotation.sin_cos();
        let t = DMat3::from_cols(
            glam::DVec3::X,
            glam::DVec3::Y,
            glam::DVec3::new(self.offset.x, self.offset.y, 1.0),
        );
        // Column-major: R = [[c, s], [-s, c]] as rows.
        let r = DMat3::from_cols(
            glam::DVec3::new(c, -s, 0.0),
            glam::DVec3::new(s, c, 0.0),
            glam::DVec3::Z,
        );
        let sc = DMat3::from_diagonal(glam::DVec3::new(self.scale.x, self.scale.y, 1.0));
        t * r * sc
    }

    /// `uv` transformed.
    pub fn apply(&self, uv: DVec2) -> DVec2 {
        let m = self.matrix();
        let p = m * glam::DVec3::new(uv.x, uv.y, 1.0);
        DVec2::new(p.x, p.y)
    }

    /// `log2` of the uv scale the transform applies (`½·log2|det S|`): how
    /// much it shifts the level of detail.
    pub fn lod_bias(&self) -> f64 {
        0.5 * (self.scale.x * self.scale.y).abs().log2()
    }
}

/// One use of a texture: which texture, sampled how, at which texture
/// coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TextureRef {
    /// Index into [`crate::scene::Scene::textures`].
    pub texture: TextureId,
    /// Filtering and wrapping.
    pub sampler: Sampler,
    /// Which texture coordinates: 0 (`TEXCOORD_0`, [`crate::scene::Mesh::uvs`]
    /// set 0, and the procedural coordinates of planes and spheres) or 1.
    pub tex_coord: u32,
    /// KHR_texture_transform (identity when absent).
    pub transform: UvTransform,
}

impl TextureRef {
    /// A texture with the default sampler on TEXCOORD_0, untransformed.
    pub fn new(texture: TextureId) -> Self {
        TextureRef {
            texture,
            sampler: Sampler::default(),
            tex_coord: 0,
            transform: UvTransform::default(),
        }
    }
}

/// How a surface's alpha (`opacity × texture alpha × vertex alpha`) is used.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum AlphaMode {
    /// Alpha is ignored.
    #[default]
    Opaque,
    /// A cut-out: points with alpha below the cutoff are not there, for
    /// camera and shadow rays alike.
    Mask {
        /// glTF's alphaCutoff (default 0.5).
        cutoff: f32,
    },
    /// Stochastic transparency: a ray passes a point with probability
    /// `1 − alpha`, decided by a hash of the pixel, the sample and the
    /// primitive, so an image is deterministic for a seed and converges to
    /// alpha blending with `--spp`.
    Blend,
}

/// What a material adds to its shader, the same for every shading model:
/// the engine applies these (the hit stage tilts the normal, traversal cuts
/// out, the shade stage adds emission), so user shaders get them too.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceMaps {
    /// Tangent-space normal map and its `scale` (glTF `normalTexture`).
    pub normal: Option<(TextureRef, f32)>,
    /// Linear RGB emitted, added to the colour at the point (glTF
    /// `emissiveFactor × KHR_materials_emissive_strength`). Not a light.
    pub emission: glam::Vec3,
    /// Multiplies [`SurfaceMaps::emission`] (sRGB).
    pub emission_texture: Option<TextureRef>,
    /// How alpha is used.
    pub alpha_mode: AlphaMode,
    /// Alpha factor (glTF `baseColorFactor`'s alpha).
    pub opacity: f32,
    /// The texture whose alpha multiplies [`SurfaceMaps::opacity`] (glTF's
    /// base colour texture).
    pub opacity_texture: Option<TextureRef>,
    /// Whether the back faces of its triangles are seen (glTF's material
    /// `doubleSided`; true for everything but glTF's single-sided materials).
    /// Camera rays pass through a single-sided triangle's back face
    /// (glTF 2.0, 3.9.5 "Double Sided"); shadow rays do not: a closed
    /// single-sided mesh still casts its shadow.
    pub double_sided: bool,
    /// glTF `occlusionTexture` and its `strength` in [0, 1]: the light of
    /// the environment (and only of it: glTF 2.0, material.occlusionTexture
    /// is for indirect light) is scaled by `1 + strength × (R − 1)`, R the
    /// texture's red channel (linear).
    pub occlusion: Option<(TextureRef, f32)>,
    /// The emission is also scaled by the vertex colour (`COLOR_0`'s RGB):
    /// KHR_materials_unlit's colour is base colour × texture × vertex
    /// colour, and penumbra emits it.
    pub emission_by_colour: bool,
}

impl Default for SurfaceMaps {
    fn default() -> Self {
        SurfaceMaps::NONE
    }
}

impl SurfaceMaps {
    /// No maps, no emission, opaque.
    pub const NONE: SurfaceMaps = SurfaceMaps {
        normal: None,
        emission: glam::Vec3::ZERO,
        emission_texture: None,
        alpha_mode: AlphaMode::Opaque,
        opacity: 1.0,
        opacity_texture: None,
        double_sided: true,
        occlusion: None,
        emission_by_colour: false,
    };

    /// Whether any map, emission or alpha is in use.
    pub fn is_none(&self) -> bool {
        self.normal.is_none()
            && self.emission == glam::Vec3::ZERO
            && self.emission_texture.is_none()
            && self.alpha_mode == AlphaMode::Opaque
            && self.occlusion.is_none()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrap_modes() {
        let r: Vec<u32> = (-3..7).map(|i| Wrap::Repeat.apply(i, 3)).collect();
        assert_eq!(r, [0, 1, 2, 0, 1, 2, 0, 1, 2, 0]);
        let m: Vec<u32> = (-3..7).map(|i| Wrap::MirroredRepeat.apply(i, 3)).collect();
        assert_eq!(m, [2, 1, 0, 0, 1, 2, 2, 1, 0, 0]);
        let c: Vec<u32> = (-3..7).map(|i| Wrap::ClampToEdge.apply(i, 3)).collect();
        assert_eq!(c, [0, 0, 0, 0, 1, 2, 2, 2, 2, 2]);
    }

    #[test]
    fn srgb_round_trips_every_byte() {
        for b in 0..=255u8 {
            assert_eq!(linear_to_srgb8(srgb_to_linear(b)), b);
        }
        assert!((srgb_to_linear(188) - 0.5).abs() < 0.003);
    }

    #[test]
    fn mips_average_in_linear_space() {
        // Black and white texels average to linear 0.5, which is sRGB 188.
        let t = Texture {
            label: "t".into(),
            file: None,
            width: 2,
            height: 1,
            texels: vec![[0, 0, 0, 0], [255, 255, 255, 255]],
            srgb: true,
        };
        let chain = t.mip_chain();
        assert_eq!(chain.len(), 2);
        assert_eq!((chain[1].width, chain[1].height), (1, 1));
        assert_eq!(chain[1].texels[0], [188, 188, 188, 128]);
        assert_eq!(t.device_bytes(), 24);
        // 5×3 → 2×1 → 1×1.
        let odd = Texture {
            width: 5,
            height: 3,
            texels: vec![[10, 20, 30, 40]; 15],
            srgb: false,
            ..t
        };
        let sizes: Vec<_> = odd
            .mip_chain()
            .iter()
            .map(|l| (l.width, l.height))
            .collect();
        assert_eq!(sizes, [(5, 3), (2, 1), (1, 1)]);
    }

    /// The mip level as it was made before issue 39's faster `half`: the
    /// plain formula, with a `powf` per sRGB channel. The reference the new
    /// code must match bit for bit.
    fn half_plain(t: &Texture, width: u32, height: u32, texels: &[[u8; 4]]) -> Vec<[u8; 4]> {
        let (w, h) = ((width / 2).max(1), (height / 2).max(1));
        let mut out = Vec::new();
        for y in 0..h {
            for x in 0..w {
                let mut sum = [0.0f64; 4];
                for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                    let sx = (2 * x + dx).min(width - 1);
                    let sy = (2 * y + dy).min(height - 1);
                    let p = texels[(sy * width + sx) as usize];
                    for (c, s) in sum.iter_mut().enumerate() {
                        *s += if t.srgb && c < 3 {
                            srgb_to_linear(p[c])
                        } else {
                            f64::from(p[c]) / 255.0
                        };
                    }
                }
                out.push(std::array::from_fn(|c| {
                    let mean = sum[c] / 4.0;
                    if t.srgb && c < 3 {
                        linear_to_srgb8(mean)
                    } else {
                        (mean * 255.0).round() as u8
                    }
                }));
            }
        }
        out
    }

    /// A xorshift generator: the same pseudo-random bytes on every run.
    fn xorshift(state: &mut u64) -> u64 {
        *state ^= *state << 13;
        *state ^= *state >> 7;
        *state ^= *state << 17;
        *state
    }

    #[test]
    fn half_is_the_plain_formula() {
        let mut rng = 0x9e37_79b9_7f4a_7c15u64;
        for (width, height) in [(64, 64), (37, 23), (1, 5), (6, 1), (129, 2)] {
            for srgb in [true, false] {
                // Noise, and smooth ramps (where sums tie most often).
                for smooth in [false, true] {
                    let texels = (0..width * height)
                        .map(|i| match smooth {
                            false => xorshift(&mut rng).to_le_bytes()[..4].try_into().unwrap(),
                            true => {
                                let (x, y) = (i % width, i / width);
                                [x as u8, y as u8, (x + y) as u8, (3 * x) as u8]
                            }
                        })
                        .collect();
                    let t = Texture {
                        label: "t".into(),
                        file: None,
                        width,
                        height,
                        texels,
                        srgb,
                    };
                    let mut prev = t.clone().texels;
                    let (mut w, mut h) = (width, height);
                    let chain = t.mip_chain();
                    for level in &chain[1..] {
                        let plain = half_plain(&t, w, h, &prev);
                        assert!(
                            level.texels == plain,
                            "{width}×{height} srgb {srgb}: level {}×{}",
                            level.width,
                            level.height
                        );
                        (w, h, prev) = (level.width, level.height, level.texels.clone());
                    }
                }
            }
        }
    }

    #[test]
    fn linear_mean_is_the_plain_formula() {
        let plain = |q: [u8; 4]| {
            let sum: f64 = q.iter().map(|&b| f64::from(b) / 255.0).sum();
            ((sum / 4.0) * 255.0).round() as u8
        };
        // Every pair of bytes for the first two, with a spread of the last two.
        let mut rng = 7u64;
        let tails: Vec<[u8; 2]> = (0..24)
            .map(|_| xorshift(&mut rng).to_le_bytes()[..2].try_into().unwrap())
            .chain([[0, 0], [255, 255], [0, 255], [1, 2]])
            .collect();
        for a in 0..=255u8 {
            for b in 0..=255u8 {
                for &[c, d] in &tails {
                    assert_eq!(
                        linear_mean8([a, b, c, d]),
                        plain([a, b, c, d]),
                        "{a} {b} {c} {d}"
                    );
                }
            }
        }
    }

    #[test]
    fn srgb8_encoder_is_linear_to_srgb8() {
        let e = Srgb8Encoder::get();
        // Around every threshold, ulp by ulp, where a wrong one would show.
        for k in 1..=255usize {
            let at = (e.bounds[k] / 4.0).to_bits();
            for bits in at - 300..at + 300 {
                let x = f64::from_bits(bits);
                assert_eq!(e.encode(x), linear_to_srgb8(x), "code {k}, x {x:e}");
            }
        }
        // Every byte's own linear value, and random values in and outside [0, 1].
        for b in 0..=255u8 {
            assert_eq!(e.encode(srgb_to_linear(b)), b);
        }
        let mut rng = 1u64;
        for _ in 0..200_000 {
            let x = (xorshift(&mut rng) >> 11) as f64 / (1u64 << 53) as f64 * 1.2 - 0.1;
            assert_eq!(e.encode(x), linear_to_srgb8(x), "{x:e}");
        }
        assert_eq!(e.encode(f64::NAN), linear_to_srgb8(f64::NAN));
        // Means of four bytes' linear values, as the mip chain takes them.
        for _ in 0..200_000 {
            let q: [u8; 4] = xorshift(&mut rng).to_le_bytes()[..4].try_into().unwrap();
            let sum = q.iter().fold(0.0, |s, &b| s + srgb_to_linear(b));
            let texels = q.map(|b| [b, b, b, 0]);
            assert_eq!(e.mean(texels)[0], linear_to_srgb8(sum / 4.0), "{q:?}");
        }
    }

    #[test]
    fn transform_order_is_translate_rotate_scale() {
        let t = UvTransform {
            offset: DVec2::new(0.5, 0.0),
            rotation: std::f64::consts::FRAC_PI_2,
            scale: DVec2::new(2.0, 1.0),
        };
        // S: (1, 0) → (2, 0); R (rows [c s; -s c], r = 90°): (2, 0) → (0, −2); T: (0.5, −2).
        let p = t.apply(DVec2::new(1.0, 0.0));
        assert!((p - DVec2::new(0.5, -2.0)).length() < 1e-12, "{p}");
        assert!((t.lod_bias() - 0.5).abs() < 1e-12);
    }
}
