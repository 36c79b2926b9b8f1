//! Textures as the kernel sees them (`shaders/textures.wgsl`,
//! `shaders/surface_maps.wgsl`, `shaders/attributes.wgsl`): every texture's
//! mip chain packed into one texel image (linear RGBA16, two texels a texel), the table of texture uses, each
//! object's surface maps, and each triangle's vertex attributes.

use glam::{DVec3, Vec4};
use rayon::prelude::*;

use crate::scene::texture::{AlphaMode, Filter, Sampler, TextureRef, Wrap};
use crate::scene::{Scene, Shape};

/// Texels per texture use (`penumbra_USE_TEXELS`).
pub const USE_TEXELS: usize = 3;
/// Texels per object's surface maps (`penumbra_SURFACE_MAP_TEXELS`).
pub const SURFACE_MAP_TEXELS: usize = 4;
/// Texels per triangle's vertex attributes (`penumbra_ATTRIBUTE_TEXELS`).
pub const ATTRIBUTE_TEXELS: usize = 9;
/// Texture use index meaning "no texture" (`penumbra_NO_TEXTURE`).
pub const NO_TEXTURE: u32 = u32::MAX;

/// Flag bits of a texture use, as in `shaders/textures.wgsl`.
pub const TEXTURE_SRGB: u32 = 1;
/// Magnification is bilinear.
pub const TEXTURE_MAG_LINEAR: u32 = 2;
/// Minification is bilinear within a level.
pub const TEXTURE_MIN_LINEAR: u32 = 4;
/// First bit of the mip mode (0 none, 1 nearest, 2 linear).
pub const TEXTURE_MIP_SHIFT: u32 = 3;
/// First bit of the wrap mode along u (0 repeat, 1 mirrored, 2 clamp).
pub const TEXTURE_WRAP_U_SHIFT: u32 = 5;
/// First bit of the wrap mode along v.
pub const TEXTURE_WRAP_V_SHIFT: u32 = 7;
/// The use reads texture coordinate set 1.
pub const TEXTURE_SET_1: u32 = 512;

/// Alpha modes, as in `shaders/surface_maps.wgsl`.
pub const ALPHA_OPAQUE: u32 = 0;
/// Cut-out below a cutoff.
pub const ALPHA_MASK: u32 = 1;
/// Stochastic transparency.
pub const ALPHA_BLEND: u32 = 2;

/// A scene's textures laid out for the GPU.
#[derive(Clone, Debug, Default)]
pub struct GpuTextures {
    /// Every texture's mip chain, linear RGBA16 texels packed two to a texel.
    pub texels: Vec<[u32; 4]>,
    /// The texture uses ([`Scene::texture_uses`] order), [`USE_TEXELS`] each.
    pub uses: Vec<[u32; 4]>,
    /// Per object, [`SURFACE_MAP_TEXELS`] each.
    pub surface_maps: Vec<[u32; 4]>,
    /// Per triangle (GPU order), [`ATTRIBUTE_TEXELS`] each; empty when no
    /// mesh has attributes and the scene samples no texture.
    pub attributes: Vec<[u32; 4]>,
    /// Bytes of texels with their mip chains (the render summary's texture
    /// memory).
    pub texture_bytes: u64,
    /// Where each texture's chain lies in [`GpuTextures::texels`].
    pub chains: Vec<TextureChain>,
}

/// Where one texture's mip chain lies in the packed texels, and what it
/// was made from: a texture of the same size and colour space can replace
/// it in place.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TextureChain {
    /// The texel its level 0 starts at.
    pub first_texel: u64,
    /// Its packed words (texels, levels one after the other).
    pub words: usize,
    /// Level-0 width.
    pub width: u32,
    /// Level-0 height.
    pub height: u32,
    /// Colour texture (sRGB).
    pub srgb: bool,
}

/// `t`'s mip chain as packed words, level after level: each texel as
/// linear RGBA in four unorm16 values (two words: `r | g << 16`,
/// `b | a << 16`), sRGB decoded here on the host from the chain's 8-bit
/// texels. The shaders then filter without a `pow` per texel (the decode
/// cost a textured frame about a sixth of its time on lavapipe:
/// docs/textures.md), and the 16-bit rounding (at most 7.7e-6) is far below
/// what 8 bits resolve.
pub fn texture_words(t: &crate::scene::Texture) -> (Vec<u32>, u32) {
    let mut words = Vec::with_capacity((t.device_bytes() / 4) as usize);
    let levels = push_texture_words(t, &mut words);
    (words, levels)
}

/// Appends [`texture_words`] of `t` to `words`, level after level, and
/// returns its number of levels; no level is held beyond the one it is
/// made from ([`crate::scene::Texture::for_each_mip_level`]).
fn push_texture_words(t: &crate::scene::Texture, words: &mut Vec<u32>) -> u32 {
    let start = words.len();
    words.resize(start + (t.device_bytes() / 4) as usize, 0);
    fill_texture_words(t, &mut words[start..])
}

/// Writes [`texture_words`] of `t` into `out`, exactly its length
/// (`device_bytes / 4` words), and returns its number of levels.
fn fill_texture_words(t: &crate::scene::Texture, out: &mut [u32]) -> u32 {
    let lut: [u32; 256] = std::array::from_fn(|b| {
        if t.srgb {
            (crate::scene::texture::srgb_to_linear(b as u8) * 65535.0).round() as u32
        } else {
            b as u32 * 257
        }
    });
    let mut levels = 0;
    let mut at = 0;
    t.for_each_mip_level(|_, _, texels| {
        levels += 1;
        let level = &mut out[at..at + 2 * texels.len()];
        at += level.len();
        level
            .par_chunks_mut(2 * PARALLEL_TEXELS)
            .zip(texels.par_chunks(PARALLEL_TEXELS))
            .for_each(|(words, texels)| {
                for (w, p) in words.chunks_exact_mut(2).zip(texels) {
                    w[0] = lut[p[0] as usize] | lut[p[1] as usize] << 16;
                    w[1] = lut[p[2] as usize] | (u32::from(p[3]) * 257) << 16;
                }
            });
    });
    levels
}

/// Texels per piece of work handed to rayon when a level is packed.
const PARALLEL_TEXELS: usize = 1 << 16;

fn wrap_bits(w: Wrap) -> u32 {
    match w {
        Wrap::Repeat => 0,
        Wrap::MirroredRepeat => 1,
        Wrap::ClampToEdge => 2,
    }
}

fn sampler_flags(s: &Sampler) -> u32 {
    let mut f = 0;
    if s.mag == Filter::Linear {
        f |= TEXTURE_MAG_LINEAR;
    }
    if s.min == Filter::Linear {
        f |= TEXTURE_MIN_LINEAR;
    }
    let mip = match s.mip {
        None => 0,
        Some(Filter::Nearest) => 1,
        Some(Filter::Linear) => 2,
    };
    f | mip << TEXTURE_MIP_SHIFT
        | wrap_bits(s.wrap_u) << TEXTURE_WRAP_U_SHIFT
        | wrap_bits(s.wrap_v) << TEXTURE_WRAP_V_SHIFT
}

/// The three texels of texture use `r` of a texture whose level 0 starts at
/// packed word `base` and which has `levels` levels.
fn use_texels(scene: &Scene, r: &TextureRef, base: u32, levels: u32) -> [[u32; 4]; 3] {
    let t = &scene.textures[r.texture];
    let mut flags = sampler_flags(&r.sampler);
    if t.srgb {
        flags |= TEXTURE_SRGB;
    }
    if r.tex_coord == 1 {
        flags |= TEXTURE_SET_1;
    }
    let m = r.transform.matrix();
    let bias = 0.5 * (f64::from(t.width) * f64::from(t.height)).log2() + r.transform.lod_bias();
    let f = |x: f64| (x as f32).to_bits();
    [
        [t.width, t.height, levels, flags],
        [f(m.x_axis.x), f(m.y_axis.x), f(m.z_axis.x), f(bias)],
        [f(m.x_axis.y), f(m.y_axis.y), f(m.z_axis.y), base],
    ]
}

fn use_index(uses: &[TextureRef], t: &Option<TextureRef>) -> u32 {
    t.as_ref()
        .map_or(NO_TEXTURE, |t| Scene::texture_use_index(uses, t))
}

impl GpuTextures {
    /// Lays out `scene`'s textures, uses, surface maps and vertex
    /// attributes (tangents relative to nothing: they are directions).
    pub fn new(scene: &Scene) -> GpuTextures {
        let mut g = GpuTextures::default();
        let uses = scene.texture_uses();
        // Each texture's chain, at a word offset of its own, written in
        // place into one buffer of the final size.
        let capacity: u64 = scene
            .textures
            .iter()
            .map(|t| (t.device_bytes() / 4).next_multiple_of(4))
            .sum();
        let mut words: Vec<u32> = vec![0; capacity as usize];
        // Each chain starts a texel, so one texture's texels can be
        // rewritten without touching another's ([`texture_words`]).
        let mut bases = Vec::with_capacity(scene.textures.len());
        let mut end = 0;
        for t in &scene.textures {
            let base = end;
            end = (base + (t.device_bytes() / 4) as usize).next_multiple_of(4);
            bases.push(base);
        }
        words.truncate(end);
        // The chains are made in parallel (issue 39), each into its own
        // part of the one buffer.
        let mut parts: Vec<&mut [u32]> = Vec::with_capacity(scene.textures.len());
        let mut rest = &mut words[..];
        for (t, &base) in scene.textures.iter().zip(&bases) {
            let done = end - rest.len();
            let (_, tail) = rest.split_at_mut(base - done);
            let (part, tail) = tail.split_at_mut((t.device_bytes() / 4) as usize);
            parts.push(part);
            rest = tail;
        }
        let levels: Vec<u32> = parts
            .into_par_iter()
            .zip(scene.textures.par_iter())
            .map(|(part, t)| fill_texture_words(t, part))
            .collect();
        let mut chains = Vec::with_capacity(scene.textures.len());
        for ((t, &base), levels) in scene.textures.iter().zip(&bases).zip(levels) {
            chains.push((base as u32, levels));
            g.chains.push(TextureChain {
                first_texel: (base / 4) as u64,
                words: (t.device_bytes() / 4) as usize,
                width: t.width,
                height: t.height,
                srgb: t.srgb,
            });
        }
        g.texture_bytes = g.chains.iter().map(|c| c.words as u64 * 4).sum();
        // Four words a texel, the same buffer when its capacity allows.
        g.texels = bytemuck::allocation::try_cast_vec(words).unwrap_or_else(|(_, words)| {
            words
                .chunks_exact(4)
                .map(|c| [c[0], c[1], c[2], c[3]])
                .collect()
        });
        for r in &uses {
            let (base, levels) = chains[r.texture];
            g.uses.extend(use_texels(scene, r, base, levels));
        }
        for o in &scene.objects {
            let m = &o.maps;
            let f = |x: f32| x.to_bits();
            let (mode, cutoff) = match m.alpha_mode {
                AlphaMode::Opaque => (ALPHA_OPAQUE, 0.0),
                AlphaMode::Mask { cutoff } => (ALPHA_MASK, cutoff),
                AlphaMode::Blend => (ALPHA_BLEND, 0.0),
            };
            let (normal, scale) = match &m.normal {
                Some((t, s)) => (Scene::texture_use_index(&uses, t), *s),
                None => (NO_TEXTURE, 1.0),
            };
            let (occlusion, strength) = match &m.occlusion {
                Some((t, s)) => (Scene::texture_use_index(&uses, t), *s),
                None => (NO_TEXTURE, 0.0),
            };
            g.surface_maps.extend([
                [
                    f(m.emission.x),
                    f(m.emission.y),
                    f(m.emission.z),
                    use_index(&uses, &m.emission_texture),
                ],
                [normal, f(scale), mode, f(cutoff)],
                [
                    f(m.opacity),
                    use_index(&uses, &m.opacity_texture),
                    u32::from(!m.double_sided),
                    0,
                ],
                [occlusion, f(strength), u32::from(m.emission_by_colour), 0],
            ]);
        }
        if scene.features().attributes {
            g.attributes = attributes(scene);
        }
        g
    }
}

/// Every triangle's attribute texels, in the GPU's triangle order
/// (objects in order, each mesh's triangles in order).
fn attributes(scene: &Scene) -> Vec<[u32; 4]> {
    let f = |x: f64| (x as f32).to_bits();
    let c = |v: Vec4| v.to_array().map(f32::to_bits);
    let mut out = Vec::new();
    let mut push =
        |uv0: [glam::DVec2; 3], uv1: [glam::DVec2; 3], col: [Vec4; 3], tan: [[u32; 4]; 3]| {
            out.push([f(uv0[0].x), f(uv0[0].y), f(uv0[1].x), f(uv0[1].y)]);
            out.push([f(uv0[2].x), f(uv0[2].y), f(uv1[0].x), f(uv1[0].y)]);
            out.push([f(uv1[1].x), f(uv1[1].y), f(uv1[2].x), f(uv1[2].y)]);
            out.extend(col.map(c));
            out.extend(tan);
        };
    let zero = [glam::DVec2::ZERO; 3];
    for o in &scene.objects {
        match &o.shape {
            Shape::Triangle(_) => push(zero, zero, [Vec4::ONE; 3], [[0; 4]; 3]),
            Shape::Mesh(m) => {
                for idx in &m.indices {
                    let at = |set: usize| {
                        m.uvs
                            .get(set)
                            .map_or(zero, |uv| idx.map(|k| uv[k as usize]))
                    };
                    let col = m
                        .colours
                        .as_ref()
                        .map_or([Vec4::ONE; 3], |cs| idx.map(|k| cs[k as usize]));
                    let tan = m.tangents.as_ref().map_or([[0; 4]; 3], |ts| {
                        idx.map(|k| {
                            let t = ts[k as usize];
                            let d = DVec3::new(t.x, t.y, t.z);
                            [f(d.x), f(d.y), f(d.z), f(t.w)]
                        })
                    });
                    push(at(0), at(1), col, tan);
                }
            }
            _ => {}
        }
    }
    out
}
