//! glTF materials as penumbra's shaders and [`SurfaceMaps`], and the
//! textures, images and samplers they use.
//!
//! A material becomes two shaders, of which the load options pick one
//! ([`crate::loaders::GltfMaterials`]): glTF's own model,
//! [`MetallicRoughness`] (`baseColorFactor`, `metallicFactor`,
//! `roughnessFactor`, `baseColorTexture`, `metallicRoughnessTexture`), the
//! default; and the seminar's mapping, `Phong { ambient: 0, diffuse:
//! baseColorFactor.rgb, specular: 0, shininess: 1 }` with
//! `baseColorTexture` as its diffuse texture, kept so that older renders can
//! be reproduced. Its normal map, emission and alpha become the primitive's
//! [`SurfaceMaps`]. Under Phong, metallic-roughness has no meaning: it is
//! named in a note, not applied (a material with `metallicFactor` 0,
//! `roughnessFactor` 1 and no metallic-roughness texture is the diffuse
//! surface Phong draws, and gets no note; glTF's defaults, 1 and 1, are a
//! rough metal and do). Occlusion applies to indirect light only, which
//! penumbra's punctual lights are not: it is named in a note.
//!
//! Images are decoded once per (image, colour space): a colour use (base
//! colour, emission) is sRGB, a normal map linear, so an image used both
//! ways becomes two textures.

use std::path::Path;

use glam::{DVec2, Vec3};
use gltf::texture::{MagFilter, MinFilter, WrappingMode};

use super::{Reader, Result};
use crate::loaders::texture;
use crate::scene::{
    AlphaMode, Filter, MetallicRoughness, MetallicRoughnessTextures, Phong, Sampler,
    SpecularGlossiness, SpecularGlossinessTextures, SurfaceMaps, TextureId, TextureRef,
    UvTransform, Wrap,
};

/// What one glTF material gives a primitive: its shader and its maps. The
/// [`TextureRef`]s index [`super::GltfDocument::textures`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Material {
    /// Linear RGB of `baseColorFactor`; `None` for the default material.
    pub base_color: Option<Vec3>,
    /// The Phong shader of the seminar's mapping.
    pub phong: Phong,
    /// glTF's own model.
    pub pbr: MetallicRoughness,
    /// Normal map, emission, alpha and occlusion.
    pub maps: SurfaceMaps,
    /// KHR_materials_unlit: the base colour (factor × texture × `COLOR_0`)
    /// is the colour, lights do not shade it (`maps.emission` holds it,
    /// `maps.emission_by_colour` is set).
    pub unlit: bool,
    /// KHR_materials_pbrSpecularGlossiness, which replaces `pbr` where given.
    pub specular_glossiness: Option<SpecularGlossiness>,
}

/// glTF's default material: white, opaque, no maps.
const DEFAULT: Material = Material {
    base_color: None,
    phong: Phong {
        ambient: Vec3::ZERO,
        diffuse: Vec3::ONE,
        specular: Vec3::ZERO,
        shininess: 1.0,
        textures: crate::scene::PhongTextures {
            ambient: None,
            diffuse: None,
            specular: None,
        },
    },
    // glTF 2.0, 3.9.1: metallicFactor and roughnessFactor default to 1.
    pbr: MetallicRoughness {
        base_colour: Vec3::ONE,
        metallic: 1.0,
        roughness: 1.0,
        textures: MetallicRoughnessTextures {
            base_colour: None,
            metallic_roughness: None,
        },
    },
    maps: SurfaceMaps::NONE,
    unlit: false,
    specular_glossiness: None,
};

/// The extension that gives a texture a KTX2/Basis Universal image
/// ([`crate::loaders::ktx2`]).
pub(super) const BASISU: &str = "KHR_texture_basisu";

/// The extensions whose meaning penumbra applies; every other one in
/// `extensionsUsed` is named in a note.
pub(super) const SUPPORTED_EXTENSIONS: &[&str] = &[
    "KHR_lights_punctual",
    "KHR_texture_transform",
    "KHR_materials_emissive_strength",
    "KHR_materials_unlit",
    "KHR_materials_pbrSpecularGlossiness",
];

impl Reader<'_> {
    /// The material of a primitive, read once per material index.
    pub(super) fn material(&mut self, material: &gltf::Material) -> Result<Material> {
        let Some(m) = material.index() else {
            return Ok(DEFAULT);
        };
        if let Some(Some(done)) = self.materials.get(m) {
            return Ok(*done);
        }
        let f = |k: &str| format!("materials[{m}].{k}");
        let pbr = material.pbr_metallic_roughness();
        let [r, g, b, alpha] = pbr.base_color_factor();
        let c = Vec3::new(r, g, b);
        if !c.is_finite() || c.min_element() < 0.0 {
            let field = f("pbrMetallicRoughness.baseColorFactor");
            return self.fail(field, format!("must be finite and non-negative, got {c}"));
        }
        if !(0.0..=1.0).contains(&alpha) {
            let field = f("pbrMetallicRoughness.baseColorFactor");
            return self.fail(field, format!("alpha must be in [0, 1], got {alpha}"));
        }
        let (metallic, roughness) = (pbr.metallic_factor(), pbr.roughness_factor());
        for (k, x) in [("metallicFactor", metallic), ("roughnessFactor", roughness)] {
            if !(0.0..=1.0).contains(&x) {
                let field = f(&format!("pbrMetallicRoughness.{k}"));
                return self.fail(field, format!("must be in [0, 1], got {x}"));
            }
        }
        let metallic_roughness = match pbr.metallic_roughness_texture() {
            Some(info) => {
                let field = f("pbrMetallicRoughness.metallicRoughnessTexture");
                Some(self.info(&info, &field, false)?)
            }
            None => None,
        };
        // Metallic 0 and roughness 1 without a texture is the diffuse
        // surface that Phong draws; anything else looks different.
        self.flags.metallic_roughness |= pbr.metallic_factor() != 0.0
            || pbr.roughness_factor() != 1.0
            || pbr.metallic_roughness_texture().is_some();
        // glTF 2.0, material.occlusionTexture: R channel, linear, strength
        // in [0, 1] (default 1); it scales the environment's light only.
        let occlusion = match material.occlusion_texture() {
            Some(o) => {
                let field = f("occlusionTexture");
                let strength = o.strength();
                if !(0.0..=1.0).contains(&strength) {
                    let message = format!("must be in [0, 1], got {strength}");
                    return self.fail(format!("{field}.strength"), message);
                }
                let (transform, set) = self.raw_transform(m, "occlusionTexture", &field)?;
                let texture = self.texture(&o.texture(), false, &field)?;
                let (tex_coord, at) = match set {
                    Some(k) => (
                        k,
                        format!("{field}.extensions.KHR_texture_transform.texCoord"),
                    ),
                    None => (o.tex_coord(), format!("{field}.texCoord")),
                };
                Some((
                    self.texture_ref(texture, tex_coord, transform, &at)?,
                    strength,
                ))
            }
            None => None,
        };

        let base_texture = match pbr.base_color_texture() {
            Some(info) => {
                Some(self.info(&info, &f("pbrMetallicRoughness.baseColorTexture"), true)?)
            }
            None => None,
        };
        let normal = match material.normal_texture() {
            Some(n) => {
                let field = f("normalTexture");
                let scale = n.scale();
                if !scale.is_finite() {
                    return self.fail(format!("{field}.scale"), "must be finite");
                }
                let (transform, set) = self.raw_transform(m, "normalTexture", &field)?;
                let texture = self.texture(&n.texture(), false, &field)?;
                let (tex_coord, at) = match set {
                    Some(k) => (
                        k,
                        format!("{field}.extensions.KHR_texture_transform.texCoord"),
                    ),
                    None => (n.tex_coord(), format!("{field}.texCoord")),
                };
                let r = self.texture_ref(texture, tex_coord, transform, &at)?;
                Some((r, scale))
            }
            None => None,
        };
        let strength = material.emissive_strength().unwrap_or(1.0);
        if !(strength >= 0.0 && strength.is_finite()) {
            let field = f("extensions.KHR_materials_emissive_strength.emissiveStrength");
            return self.fail(field, format!("must be finite and >= 0, got {strength}"));
        }
        let factor = Vec3::from_array(material.emissive_factor());
        if !factor.is_finite() || factor.min_element() < 0.0 {
            let message = format!("must be finite and non-negative, got {factor}");
            return self.fail(f("emissiveFactor"), message);
        }
        let emission_texture = match material.emissive_texture() {
            Some(info) => Some(self.info(&info, &f("emissiveTexture"), true)?),
            None => None,
        };
        let alpha_mode = match material.alpha_mode() {
            gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
            gltf::material::AlphaMode::Mask => {
                let cutoff = material.alpha_cutoff().unwrap_or(0.5);
                if !(cutoff >= 0.0 && cutoff.is_finite()) {
                    let message = format!("must be finite and >= 0, got {cutoff}");
                    return self.fail(f("alphaCutoff"), message);
                }
                AlphaMode::Mask { cutoff }
            }
            gltf::material::AlphaMode::Blend => AlphaMode::Blend,
        };
        let specular_glossiness = match material.pbr_specular_glossiness() {
            Some(sg) => Some(self.specular_glossiness(m, &sg)?),
            None => None,
        };
        // KHR_materials_unlit: the base colour is emitted as it is (the
        // emission's own factors are not part of an unlit material).
        let unlit = self.has_extension(m, "KHR_materials_unlit");
        let (emission, emission_texture) = match unlit {
            true => (c, base_texture),
            false => (factor * strength, emission_texture),
        };
        // Alpha comes from the base colour texture, the same use (the
        // diffuse ones under KHR_materials_pbrSpecularGlossiness).
        let (alpha, alpha_texture) = match &specular_glossiness {
            Some((_, a)) => (
                *a,
                specular_glossiness.and_then(|(s, _)| s.textures.diffuse),
            ),
            None => (alpha, base_texture),
        };
        let maps = SurfaceMaps {
            normal,
            emission,
            emission_texture,
            alpha_mode,
            opacity: alpha,
            opacity_texture: alpha_texture.filter(|_| alpha_mode != AlphaMode::Opaque),
            // glTF 2.0, material.doubleSided (default false): back faces of
            // a single-sided material are culled.
            double_sided: material.double_sided(),
            occlusion,
            // KHR_materials_unlit: base colour × texture × vertex colour.
            emission_by_colour: unlit,
        };
        let phong = Phong {
            textures: crate::scene::PhongTextures {
                diffuse: base_texture,
                ..Default::default()
            },
            diffuse: c,
            ..DEFAULT.phong
        };
        let pbr = MetallicRoughness {
            base_colour: c,
            metallic,
            roughness,
            textures: MetallicRoughnessTextures {
                base_colour: base_texture,
                metallic_roughness,
            },
        };
        let done = Material {
            base_color: Some(c),
            phong,
            pbr,
            maps,
            unlit,
            specular_glossiness: specular_glossiness.map(|(s, _)| s),
        };
        if self.materials.len() <= m {
            self.materials.resize(m + 1, None);
        }
        self.materials[m] = Some(done);
        Ok(done)
    }

    /// A `textureInfo` at `field` (`materials[0].emissiveTexture`) as a
    /// texture use; `srgb` for colour textures.
    fn info(&mut self, info: &gltf::texture::Info, field: &str, srgb: bool) -> Result<TextureRef> {
        let mut tex_coord = info.tex_coord();
        let mut at = format!("{field}.texCoord");
        let transform = match info.texture_transform() {
            Some(t) => {
                if let Some(k) = t.tex_coord() {
                    tex_coord = k;
                    at = format!("{field}.extensions.KHR_texture_transform.texCoord");
                }
                let [ox, oy] = t.offset();
                let [sx, sy] = t.scale();
                let field = format!("{field}.extensions.KHR_texture_transform");
                transform(&[ox, oy, t.rotation(), sx, sy])
                    .map_err(|(key, message)| self.err(format!("{field}.{key}"), message))?
            }
            None => UvTransform::default(),
        };
        let texture = self.texture(&info.texture(), srgb, field)?;
        self.texture_ref(texture, tex_coord, transform, &at)
    }

    /// A texture use from its parts; `at` is the field of its `texCoord`,
    /// which must be 0 or 1.
    fn texture_ref(
        &self,
        (texture, sampler): (TextureId, Sampler),
        tex_coord: u32,
        transform: UvTransform,
        at: &str,
    ) -> Result<TextureRef> {
        if tex_coord >= 2 {
            let message = format!("is {tex_coord}; penumbra reads TEXCOORD_0 and TEXCOORD_1 only");
            return self.fail(at, message);
        }
        Ok(TextureRef {
            texture,
            sampler,
            tex_coord,
            transform,
        })
    }

    /// `materials[m]`'s KHR_materials_pbrSpecularGlossiness and the alpha
    /// of its `diffuseFactor`.
    fn specular_glossiness(
        &mut self,
        m: usize,
        sg: &gltf::material::PbrSpecularGlossiness,
    ) -> Result<(SpecularGlossiness, f32)> {
        let at =
            |k: &str| format!("materials[{m}].extensions.KHR_materials_pbrSpecularGlossiness.{k}");
        let [r, g, b, a] = sg.diffuse_factor();
        let diffuse = Vec3::new(r, g, b);
        let specular = Vec3::from_array(sg.specular_factor());
        for (k, c) in [("diffuseFactor", diffuse), ("specularFactor", specular)] {
            if !c.is_finite() || c.min_element() < 0.0 {
                return self.fail(at(k), format!("must be finite and non-negative, got {c}"));
            }
        }
        if !(0.0..=1.0).contains(&a) {
            return self.fail(
                at("diffuseFactor"),
                format!("alpha must be in [0, 1], got {a}"),
            );
        }
        let glossiness = sg.glossiness_factor();
        if !(0.0..=1.0).contains(&glossiness) {
            let message = format!("must be in [0, 1], got {glossiness}");
            return self.fail(at("glossinessFactor"), message);
        }
        let diffuse_texture = match sg.diffuse_texture() {
            Some(info) => Some(self.info(&info, &at("diffuseTexture"), true)?),
            None => None,
        };
        // Specular in sRGB RGB, glossiness in linear A: an sRGB texture's
        // alpha is linear.
        let specular_glossiness = match sg.specular_glossiness_texture() {
            Some(info) => Some(self.info(&info, &at("specularGlossinessTexture"), true)?),
            None => None,
        };
        let s = SpecularGlossiness {
            diffuse,
            specular,
            glossiness,
            textures: SpecularGlossinessTextures {
                diffuse: diffuse_texture,
                specular_glossiness,
            },
        };
        Ok((s, a))
    }

    /// Whether `materials[m].extensions` has `name` (read from the JSON
    /// itself, as the crate's optional features for it are off).
    fn has_extension(&mut self, m: usize, name: &str) -> bool {
        if self.raw.is_none() {
            let value = serde_json::from_slice(self.json).unwrap_or(serde_json::Value::Null);
            self.raw = Some(value);
        }
        let raw = self.raw.as_ref().expect("parsed above");
        raw["materials"][m]["extensions"][name].is_object()
    }

    /// KHR_texture_transform of `materials[m].<key>` (`normalTexture` or
    /// `occlusionTexture`), which the `gltf` crate does not expose: read
    /// from the JSON itself, with its `texCoord`, which overrides the
    /// texture info's.
    fn raw_transform(
        &mut self,
        m: usize,
        key: &str,
        field: &str,
    ) -> Result<(UvTransform, Option<u32>)> {
        if self.raw.is_none() {
            let value = serde_json::from_slice(self.json).unwrap_or(serde_json::Value::Null);
            self.raw = Some(value);
        }
        let raw = self.raw.as_ref().expect("parsed above");
        let ext = &raw["materials"][m][key]["extensions"]["KHR_texture_transform"];
        if ext.is_null() {
            return Ok((UvTransform::default(), None));
        }
        let at = format!("{field}.extensions.KHR_texture_transform");
        let num = |v: &serde_json::Value, default: f64| match v {
            serde_json::Value::Null => Some(default),
            v => v.as_f64(),
        };
        let pair = |k: &str, d: f64| {
            let v = &ext[k];
            Some([num(&v[0], d)?, num(&v[1], d)?]).filter(|_| v.is_null() || v.is_array())
        };
        let not_numbers = |key: &str| self.err(format!("{at}.{key}"), "must be finite numbers");
        let [ox, oy] = pair("offset", 0.0).ok_or_else(|| not_numbers("offset"))?;
        let [sx, sy] = pair("scale", 1.0).ok_or_else(|| not_numbers("scale"))?;
        let rotation = num(&ext["rotation"], 0.0).ok_or_else(|| not_numbers("rotation"))?;
        let set = match &ext["texCoord"] {
            serde_json::Value::Null => None,
            v => match v.as_u64().and_then(|k| u32::try_from(k).ok()) {
                Some(k) => Some(k),
                None => return self.fail(format!("{at}.texCoord"), "must be an integer >= 0"),
            },
        };
        let parts = [ox, oy, rotation, sx, sy].map(|x| x as f32);
        let t =
            transform(&parts).map_err(|(key, message)| self.err(format!("{at}.{key}"), message));
        Ok((t?, set))
    }

    /// The texture `t` as a texture id (decoding its image in colour space
    /// `srgb` once) and its sampler; `field` is where it is used.
    fn texture(
        &mut self,
        t: &gltf::Texture,
        srgb: bool,
        field: &str,
    ) -> Result<(TextureId, Sampler)> {
        let sampler = sampler(&t.sampler());
        let image = self.texture_image(t)?;
        if let Some(&id) = self.texture_ids.get(&(image, srgb)) {
            return Ok((id, sampler));
        }
        self.at = format!("{field}.index");
        let id = self.image(image, srgb)?;
        self.texture_ids.insert((image, srgb), id);
        Ok((id, sampler))
    }

    /// The image of texture `t`: its KHR_texture_basisu image where it
    /// has one, else its `source`.
    fn texture_image(&self, t: &gltf::Texture) -> Result<usize> {
        let at = format!("textures[{}]", t.index());
        let basisu = &self.raw_json()["textures"][t.index()]["extensions"][BASISU];
        if basisu.is_object() {
            return basisu["source"]
                .as_u64()
                .and_then(|i| usize::try_from(i).ok())
                .ok_or_else(|| {
                    let message = "must be the index of a KTX2 image";
                    self.err(format!("{at}.extensions.{BASISU}.source"), message)
                });
        }
        // Without `source` the crate reads u32::MAX, and `source()` panics.
        let json = &self.document.as_json().textures[t.index()];
        match json.source.value() {
            i if i == u32::MAX as usize => self.fail(format!("{at}.source"), "is missing"),
            i => Ok(i),
        }
    }

    /// Decodes `images[i]` (a data: URI, a bufferView or a file next to
    /// the glTF file) into a new texture.
    fn image(&mut self, i: usize, srgb: bool) -> Result<TextureId> {
        let field = format!("images[{i}]");
        let Some(json) = self.document.as_json().images.get(i) else {
            return self.fail(field, "does not exist");
        };
        let declared = json.mime_type.as_ref().map(|m| m.0.as_str());
        let mut file = None;
        let (bytes, mime, at): (std::borrow::Cow<[u8]>, Option<&str>, String) =
            match (&json.buffer_view, &json.uri) {
                (Some(view), _) => {
                    let at = format!("{field}.bufferView");
                    let Some(mime) = declared else {
                        let message = "is required for an image in a bufferView";
                        return self.fail(format!("{field}.mimeType"), message);
                    };
                    let Some(view) = self.document.views().nth(view.value()) else {
                        return self.fail(at, "does not exist");
                    };
                    let bytes = self.view_bytes(&view)?;
                    (bytes.to_vec().into(), Some(mime), at)
                }
                (None, Some(uri)) if uri.starts_with("data:") => {
                    let at = format!("{field}.uri");
                    let Some((head, payload)) = uri.split_once(";base64,") else {
                        return self.fail(at, "is not a base64 data: URI");
                    };
                    let Some(bytes) = super::decode_base64(payload) else {
                        return self.fail(at, "is not a base64 data: URI");
                    };
                    let in_uri = head
                        .strip_prefix("data:")
                        .filter(|m| m.starts_with("image/"));
                    (bytes.into(), declared.or(in_uri), at)
                }
                (None, Some(uri)) => {
                    let at = format!("{field}.uri");
                    let Some(relative) = super::percent_decode(uri).filter(|_| !uri.contains(':'))
                    else {
                        let message = "is neither a relative path nor a base64 data: URI";
                        return self.fail(at, message);
                    };
                    let base = self.file.parent().unwrap_or(Path::new(""));
                    let path = base.join(relative);
                    let bytes = self
                        .guard
                        .read(&path, "image")
                        .map_err(|e| self.err(&at, e.0))?;
                    if !self.doc.files.contains(&path) {
                        self.doc.files.push(path.clone());
                    }
                    file = Some(path);
                    (bytes.into(), declared, at)
                }
                (None, None) => return self.fail(field, "has neither a uri nor a bufferView"),
            };
        let name = self.file.file_name().unwrap_or(self.file.as_os_str());
        let label = format!("{} {field}", name.to_string_lossy());
        // Checked and charged now, decoded with the others after the walk
        // (in parallel: module `decode`).
        let pending = texture::prepare(bytes.into_owned(), mime, &label, srgb, self.guard)
            .map_err(|e| self.err(&at, e.0))?;
        self.pending.push((self.doc.textures.len(), pending, at));
        self.doc.textures.push(super::decode::placeholder(file));
        Ok(self.doc.textures.len() - 1)
    }
}

/// A transform from `[offset.x, offset.y, rotation, scale.x, scale.y]`,
/// or the KHR_texture_transform key that is wrong (`offset`, `rotation`,
/// `scale`) and why: each must be finite, and the scale non-zero in u and v
/// (the level of detail takes its log), checked here so that the error
/// names the file's field rather than the scene's shader.
fn transform(p: &[f32; 5]) -> std::result::Result<UvTransform, (&'static str, String)> {
    let finite = |key: &'static str, v: &[f32]| match v.iter().all(|x| x.is_finite()) {
        true => Ok(()),
        false => Err((key, format!("must be finite, got {v:?}"))),
    };
    finite("offset", &p[0..2])?;
    finite("rotation", &p[2..3])?;
    finite("scale", &p[3..5])?;
    if p[3] == 0.0 || p[4] == 0.0 {
        let message = format!("must be non-zero in u and v, got {:?}", &p[3..5]);
        return Err(("scale", message));
    }
    Ok(UvTransform {
        offset: DVec2::new(f64::from(p[0]), f64::from(p[1])),
        rotation: f64::from(p[2]),
        scale: DVec2::new(f64::from(p[3]), f64::from(p[4])),
    })
}

/// A glTF sampler; undefined filters take [`Sampler::default`]'s.
pub(super) fn sampler(s: &gltf::texture::Sampler) -> Sampler {
    let d = Sampler::default();
    let mag = match s.mag_filter() {
        Some(MagFilter::Nearest) => Filter::Nearest,
        Some(MagFilter::Linear) => Filter::Linear,
        None => d.mag,
    };
    let (min, mip) = match s.min_filter() {
        Some(MinFilter::Nearest) => (Filter::Nearest, None),
        Some(MinFilter::Linear) => (Filter::Linear, None),
        Some(MinFilter::NearestMipmapNearest) => (Filter::Nearest, Some(Filter::Nearest)),
        Some(MinFilter::LinearMipmapNearest) => (Filter::Linear, Some(Filter::Nearest)),
        Some(MinFilter::NearestMipmapLinear) => (Filter::Nearest, Some(Filter::Linear)),
        Some(MinFilter::LinearMipmapLinear) => (Filter::Linear, Some(Filter::Linear)),
        None => (d.min, d.mip),
    };
    let wrap = |w| match w {
        WrappingMode::ClampToEdge => Wrap::ClampToEdge,
        WrappingMode::MirroredRepeat => Wrap::MirroredRepeat,
        WrappingMode::Repeat => Wrap::Repeat,
    };
    Sampler {
        mag,
        min,
        mip,
        wrap_u: wrap(s.wrap_s()),
        wrap_v: wrap(s.wrap_t()),
    }
}
