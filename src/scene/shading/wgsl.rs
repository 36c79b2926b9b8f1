//! A shader written as a WGSL file, as the scene model holds it: its file,
//! its text, the members of its `Params` and the values the scene gives them.
//! Reading the file's interface (naga) is the WGSL layer's job
//! ([`crate::wgsl`]); this is plain data.

use std::fmt;
use std::path::PathBuf;

/// The type of one member of `Params`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ParamType {
    /// `f32`.
    F32,
    /// `i32`.
    I32,
    /// `u32`.
    U32,
    /// `vec2<f32>`.
    Vec2,
    /// `vec3<f32>`.
    Vec3,
    /// `vec4<f32>`.
    Vec4,
}

impl ParamType {
    /// Number of 32-bit words the value takes in [`WgslShader::words`].
    pub fn words(self) -> usize {
        match self {
            ParamType::F32 | ParamType::I32 | ParamType::U32 => 1,
            ParamType::Vec2 => 2,
            ParamType::Vec3 => 3,
            ParamType::Vec4 => 4,
        }
    }

    /// The type as WGSL spells it (`f32`, `vec3<f32>`...).
    pub fn wgsl(self) -> &'static str {
        match self {
            ParamType::F32 => "f32",
            ParamType::I32 => "i32",
            ParamType::U32 => "u32",
            ParamType::Vec2 => "vec2<f32>",
            ParamType::Vec3 => "vec3<f32>",
            ParamType::Vec4 => "vec4<f32>",
        }
    }
}

impl fmt::Display for ParamType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.wgsl())
    }
}

/// One member of `Params`.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct ParamField {
    /// The member's name.
    pub name: String,
    /// Its type.
    pub ty: ParamType,
}

/// The value of one member of `Params`.
#[derive(Clone, Debug, PartialEq)]
pub enum ParamValue {
    /// For an `f32` member.
    F32(f32),
    /// For an `i32` member.
    I32(i32),
    /// For a `u32` member.
    U32(u32),
    /// For a `vecN<f32>` member: exactly N components.
    Vec(Vec<f32>),
    /// For a `u32` member given `{"texture": ...}`: the shader receives
    /// the index of this use in [`crate::scene::Scene::texture_uses`] and
    /// samples it with `texture_sample`.
    Texture(crate::scene::TextureRef),
}

impl ParamValue {
    /// Whether this value fills a member of type `ty`.
    pub fn fits(&self, ty: ParamType) -> bool {
        match (self, ty) {
            (ParamValue::F32(_), ParamType::F32)
            | (ParamValue::I32(_), ParamType::I32)
            | (ParamValue::U32(_), ParamType::U32)
            | (ParamValue::Texture(_), ParamType::U32) => true,
            (ParamValue::Vec(v), ParamType::Vec2 | ParamType::Vec3 | ParamType::Vec4) => {
                v.len() == ty.words()
            }
            _ => false,
        }
    }

    /// Whether every floating-point component is finite.
    pub fn is_finite(&self) -> bool {
        match self {
            ParamValue::F32(x) => x.is_finite(),
            ParamValue::Vec(v) => v.iter().all(|x| x.is_finite()),
            ParamValue::I32(_) | ParamValue::U32(_) | ParamValue::Texture(_) => true,
        }
    }
}

/// A shader given as a WGSL file, with the values of its `Params`.
#[derive(Clone, Debug, PartialEq)]
pub struct WgslShader {
    /// The file as resolved (relative to the scene file's folder).
    pub path: PathBuf,
    /// Its text as loaded.
    pub source: String,
    /// The members of `Params` in declaration order; empty when the file
    /// declares no `Params`.
    pub fields: Vec<ParamField>,
    /// One value per field, in the same order.
    pub values: Vec<ParamValue>,
    /// The file defines `fn ambient`.
    pub has_ambient: bool,
}

impl WgslShader {
    /// The values packed tightly in field order: `f32`, `i32` and `u32` as
    /// their bits (one word each), `vecN<f32>` as N `f32` words, a texture
    /// as the index `use_index` gives its use (the scene's
    /// [`crate::scene::Scene::texture_uses`]).
    pub fn words(&self, use_index: impl Fn(&crate::scene::TextureRef) -> u32) -> Vec<u32> {
        let mut words = Vec::with_capacity(self.fields.iter().map(|f| f.ty.words()).sum());
        for v in &self.values {
            match v {
                ParamValue::F32(x) => words.push(x.to_bits()),
                ParamValue::I32(x) => words.push(*x as u32),
                ParamValue::U32(x) => words.push(*x),
                ParamValue::Texture(t) => words.push(use_index(t)),
                ParamValue::Vec(xs) => words.extend(xs.iter().map(|x| x.to_bits())),
            }
        }
        words
    }
}
