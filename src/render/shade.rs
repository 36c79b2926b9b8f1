//! The shade stage: one compute pipeline per shader file.
//!
//! A shade pipeline is compiled from `shaders/shading/interface.wgsl` (the
//! engine types `Surface` and `LightSample`), `shaders/stages/shade.wgsl`
//! (the stage, all of whose names start with `penumbra_`), the shader file,
//! and two functions generated here from the file's `struct Params`: the
//! loader that reads a material's parameters from the packed parameter words,
//! and the call of the optional `ambient`. Built-in shaders (Phong,
//! Blinn-Phong) are such files too, so built-in and user shaders share one
//! mechanism.

use std::fmt::Write as _;
use std::path::PathBuf;

use super::compile::{Assembled, CompileError, ShaderSource};
use super::stages::SHADE_PRELUDE;
use super::RenderError;
use crate::scene::shading::{ParamField, ParamType};
use crate::scene::Features;
use crate::wgsl::{reflect, ShaderFileError};

/// The shade stage's entry point (`shaders/stages/shade.wgsl`).
pub const SHADE_ENTRY_POINT: &str = "penumbra_shade_stage";

/// The features that a shade pipeline is specialised to (its overrides,
/// compile.rs), the rest cleared: the key under which a file's shade
/// pipeline is cached beside the file, so that scenes differing only in
/// what the shade stage does not see share it.
pub fn variant(f: &Features) -> Features {
    Features {
        textures: f.textures,
        attributes: f.attributes,
        vertex_colours: f.vertex_colours,
        emission: f.emission,
        checker: f.checker,
        planes: f.planes,
        spheres: f.spheres,
        occlusion: f.occlusion,
        ..Features::default()
    }
}

/// Where a shade program's file comes from.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum ProgramFile {
    /// A built-in shader file, relative to `shaders/` (read through the
    /// renderer's [`ShaderSource`], so shader development edits it).
    Builtin(&'static str),
    /// A user's shader file (the scene refers to it).
    User(PathBuf),
}

impl ProgramFile {
    /// The name reload reports and errors use.
    pub fn label(&self) -> String {
        match self {
            ProgramFile::Builtin(name) => format!("shaders/{name}"),
            ProgramFile::User(path) => path.display().to_string(),
        }
    }

    /// The name compile errors and reload reports use when the built-in
    /// files come from `source`: a built-in read from a
    /// [`ShaderSource::Directory`] is named by its path there (the file the
    /// developer edits); otherwise as [`ProgramFile::label`].
    pub fn label_in(&self, source: &ShaderSource) -> String {
        match (self, source) {
            (ProgramFile::Builtin(name), ShaderSource::Directory(dir)) => {
                dir.join(name).display().to_string()
            }
            _ => self.label(),
        }
    }
}

/// A shade program's assembled source and what it declares.
pub struct ShadeSource {
    /// Prelude, shader file and generated functions.
    pub assembled: Assembled,
    /// The `Params` fields, in declaration order (empty: none).
    pub fields: Vec<ParamField>,
    /// Whether the file defines `ambient`.
    pub has_ambient: bool,
}

/// The texts of the user's shader files as the loader read them again
/// (a reload), by path.
pub type UserTexts = std::collections::BTreeMap<PathBuf, String>;

/// Reads the text of a built-in `file` through `source`. A user file's
/// text comes from the loader (the scene's [`crate::scene::WgslShader`], or
/// [`UserTexts`] on a reload): the renderer reads no user file itself.
pub fn read_program(source: &ShaderSource, file: &ProgramFile) -> Result<String, CompileError> {
    match file {
        ProgramFile::Builtin(name) => source.read(name).map(|(_, text)| text),
        ProgramFile::User(path) => Err(CompileError {
            location: path.display().to_string(),
            message: "a user's shader file is read by the loader".into(),
        }),
    }
}

/// Assembles the shade program of `file` whose text is `text`.
pub fn assemble(
    source: &ShaderSource,
    file: &ProgramFile,
    text: &str,
) -> Result<ShadeSource, CompileError> {
    let mut assembled = source.assemble_files(SHADE_PRELUDE)?;
    let label = file.label_in(source);
    assembled.push_file(label.clone(), text);
    assembled.subject = Some(label.clone());
    // What the file declares (crate::wgsl, which also
    // checks `shade` and `ambient`); a file without Params gets the
    // placeholder that `shade` still takes.
    let declared = reflect(std::path::Path::new(&label), text).map_err(file_error)?;
    let placeholder = !declared.has_params;
    if placeholder {
        assembled.push_file("(placeholder Params)".into(), PLACEHOLDER_PARAMS);
    }
    let fields = declared.fields;
    let has_ambient = declared.has_ambient;
    assembled.push_file(
        format!("(penumbra's parameter loader for {label})"),
        &generated(&fields, has_ambient, declared.has_prepare, placeholder),
    );
    Ok(ShadeSource {
        assembled,
        fields,
        has_ambient,
    })
}

/// `Params` for a shader file that declares none.
const PLACEHOLDER_PARAMS: &str = "struct Params {\n    penumbra_unused: u32,\n}\n";

/// A shader file's reflection error as a compile error (same text).
fn file_error(e: ShaderFileError) -> CompileError {
    let text = e.to_string();
    let head = e.path.display().to_string();
    match text.strip_prefix(&head) {
        Some(rest) => {
            let (place, message) = rest.split_once(": ").unwrap_or(("", rest));
            CompileError {
                location: format!("{head}{place}"),
                message: message.to_string(),
            }
        }
        None => CompileError {
            location: head,
            message: e.message,
        },
    }
}

/// The loader of `Params` from the packed words, and the sum of the
/// file's `ambient` over the lights.
fn generated(
    fields: &[ParamField],
    has_ambient: bool,
    has_prepare: bool,
    placeholder: bool,
) -> String {
    let mut out = String::new();
    // `at` is the first texel of the material's words (4-word aligned), so
    // each word's texel and component are known here.
    let words: usize = fields.iter().map(|f| f.ty.words()).sum();
    let mut body = String::new();
    for t in 0..words.div_ceil(4) {
        let _ = writeln!(
            body,
            "    let t{t} = textureLoad(penumbra_params, penumbra_texel(at + {t}u));"
        );
    }
    let word = |i: usize| format!("t{}.{}", i / 4, ["x", "y", "z", "w"][i % 4]);
    let mut at = 0usize;
    let mut args = Vec::new();
    for field in fields {
        let kind = &field.ty;
        args.push(match kind {
            ParamType::F32 => format!("bitcast<f32>({})", word(at)),
            ParamType::I32 => format!("bitcast<i32>({})", word(at)),
            ParamType::U32 => word(at),
            vec => {
                let n = vec.words();
                let parts: Vec<String> = (0..n)
                    .map(|i| format!("bitcast<f32>({})", word(at + i)))
                    .collect();
                format!("vec{n}<f32>({})", parts.join(", "))
            }
        });
        at += kind.words();
    }
    if placeholder {
        args.push("0u".into());
    }
    let _ = writeln!(
        out,
        "fn penumbra_load_params(at: u32) -> Params {{\n{body}    return Params({});\n}}",
        args.join(", ")
    );
    let sum = if has_ambient {
        "    var sum = vec3<f32>(0.0);\n    for (var i = 0u; i < penumbra_push.light_count; i++) {\n        sum += ambient(s, penumbra_f3(textureLoad(penumbra_light_colours, penumbra_texel(3u * i + 2u))), p);\n    }\n    return sum;"
    } else {
        "    return vec3<f32>(0.0);"
    };
    let _ = writeln!(
        out,
        "fn penumbra_ambient_sum(s: Surface, p: Params) -> vec3<f32> {{\n{sum}\n}}"
    );
    let prepare = if has_prepare { "prepare(s, p)" } else { "p" };
    let _ = writeln!(
        out,
        "fn penumbra_prepare(s: Surface, p: Params) -> Params {{\n    return {prepare};\n}}"
    );
    out
}

/// A built-in shader's parameter words, in the order of its file's `Params`
/// fields: `value` gives a field's value by name and type (`None`: not one
/// of the shader's fields, which `known` lists for the error).
fn builtin_words(
    fields: &[ParamField],
    label: &str,
    known: &str,
    value: impl Fn(&str, ParamType) -> Option<Vec<f32>>,
) -> Result<Vec<u32>, CompileError> {
    let mut words = Vec::new();
    for ParamField { name, ty } in fields {
        let Some(v) = value(name, *ty) else {
            return Err(CompileError {
                location: label.to_string(),
                message: format!("Params field `{name}: {}` is not one of {known}", ty.wgsl()),
            });
        };
        words.extend(v.iter().map(|x| x.to_bits()));
    }
    Ok(words)
}

/// A texture parameter's word (its use's index, or none), as an `f32`'s bits.
fn texture_word(
    uses: &[crate::scene::TextureRef],
    t: &Option<crate::scene::TextureRef>,
) -> Vec<f32> {
    let index = t.as_ref().map_or(super::layout::textures::NO_TEXTURE, |t| {
        crate::scene::Scene::texture_use_index(uses, t)
    });
    vec![f32::from_bits(index)]
}

/// The parameter words of a built-in Phong-type shader, in the order of the
/// file's `Params` fields (the JSON types `phong` and `blinn_phong` map to
/// these files and keep their fields).
pub fn phong_words(
    fields: &[ParamField],
    p: &crate::scene::Phong,
    uses: &[crate::scene::TextureRef],
    label: &str,
) -> Result<Vec<u32>, CompileError> {
    builtin_words(fields, label, "the built-in shader's fields (ambient, diffuse, specular: vec3<f32>; shininess: f32; ambient_texture, diffuse_texture, specular_texture: u32)", |name, ty| {
        Some(match (name, ty) {
            ("ambient", ParamType::Vec3) => p.ambient.to_array().to_vec(),
            ("diffuse", ParamType::Vec3) => p.diffuse.to_array().to_vec(),
            ("specular", ParamType::Vec3) => p.specular.to_array().to_vec(),
            ("shininess", ParamType::F32) => vec![p.shininess],
            ("ambient_texture", ParamType::U32) => texture_word(uses, &p.textures.ambient),
            ("diffuse_texture", ParamType::U32) => texture_word(uses, &p.textures.diffuse),
            ("specular_texture", ParamType::U32) => texture_word(uses, &p.textures.specular),
            _ => return None,
        })
    })
}

/// The parameter words of the built-in metallic-roughness shader, in the
/// order of the file's `Params` fields (matched by name).
pub fn metallic_roughness_words(
    fields: &[ParamField],
    m: &crate::scene::MetallicRoughness,
    uses: &[crate::scene::TextureRef],
    label: &str,
) -> Result<Vec<u32>, CompileError> {
    builtin_words(fields, label, "the metallic-roughness shader's fields (base_colour: vec3<f32>; metallic, roughness: f32; base_colour_texture, metallic_roughness_texture: u32)", |name, ty| {
        Some(match (name, ty) {
            ("base_colour", ParamType::Vec3) => m.base_colour.to_array().to_vec(),
            ("metallic", ParamType::F32) => vec![m.metallic],
            ("roughness", ParamType::F32) => vec![m.roughness],
            ("base_colour_texture", ParamType::U32) => {
                texture_word(uses, &m.textures.base_colour)
            }
            ("metallic_roughness_texture", ParamType::U32) => {
                texture_word(uses, &m.textures.metallic_roughness)
            }
            _ => return None,
        })
    })
}

/// The parameter words of the built-in specular-glossiness shader, in the
/// order of the file's `Params` fields (matched by name).
pub fn specular_glossiness_words(
    fields: &[ParamField],
    m: &crate::scene::SpecularGlossiness,
    uses: &[crate::scene::TextureRef],
    label: &str,
) -> Result<Vec<u32>, CompileError> {
    builtin_words(fields, label, "the specular-glossiness shader's fields (diffuse, specular: vec3<f32>; glossiness: f32; diffuse_texture, specular_glossiness_texture: u32)", |name, ty| {
        Some(match (name, ty) {
            ("diffuse", ParamType::Vec3) => m.diffuse.to_array().to_vec(),
            ("specular", ParamType::Vec3) => m.specular.to_array().to_vec(),
            ("glossiness", ParamType::F32) => vec![m.glossiness],
            ("diffuse_texture", ParamType::U32) => texture_word(uses, &m.textures.diffuse),
            ("specular_glossiness_texture", ParamType::U32) => {
                texture_word(uses, &m.textures.specular_glossiness)
            }
            _ => return None,
        })
    })
}

/// One shade program: a shader file, its text, and its `Params` fields.
#[derive(Clone, Debug, PartialEq)]
pub struct Program {
    /// The file.
    pub file: ProgramFile,
    /// Its text as last read.
    pub text: String,
    /// Its `Params` fields.
    pub fields: Vec<ParamField>,
}

/// The shade programs of a scene and every leaf shader's parameters.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Materials {
    /// One per distinct shader file, in order of first use.
    pub programs: Vec<Program>,
    /// Every leaf's parameter words, each leaf's starting a 4-word texel.
    pub words: Vec<u32>,
    /// Per scene shader: (program, first parameter texel) of a leaf, `None`
    /// for a checker.
    pub leaves: Vec<Option<(u32, u32)>>,
}

impl Materials {
    /// The programs and parameters of `shaders`, reading the built-in files
    /// through `source`. User files are taken as the scene loaded them
    /// (validated against their parameters), or, on a reload after an edit,
    /// as `reread` holds them (read again by the loader, through its guard:
    /// [`crate::loaders::read_shader_file`]).
    /// `uses` is the scene's [`crate::scene::Scene::texture_uses`]: a
    /// texture parameter's word is its index there.
    pub fn new(
        shaders: &[crate::scene::Shader],
        uses: &[crate::scene::TextureRef],
        source: &ShaderSource,
        reread: Option<&UserTexts>,
    ) -> Result<Materials, RenderError> {
        use crate::scene::Shader;
        let mut m = Materials::default();
        for sh in shaders {
            let file = match sh {
                Shader::Phong(_) => ProgramFile::Builtin("shading/phong.wgsl"),
                Shader::BlinnPhong(_) => ProgramFile::Builtin("shading/blinn_phong.wgsl"),
                Shader::MetallicRoughness(_) => {
                    ProgramFile::Builtin("shading/metallic_roughness.wgsl")
                }
                Shader::SpecularGlossiness(_) => {
                    ProgramFile::Builtin("shading/specular_glossiness.wgsl")
                }
                Shader::Wgsl(w) => ProgramFile::User(w.path.clone()),
                Shader::Checker(_) => {
                    m.leaves.push(None);
                    continue;
                }
            };
            let program = match m.programs.iter().position(|p| p.file == file) {
                Some(i) => i,
                None => {
                    let text = match (sh, reread) {
                        (Shader::Wgsl(w), None) => w.source.clone(),
                        (Shader::Wgsl(w), Some(texts)) => match texts.get(&w.path) {
                            Some(text) => text.clone(),
                            None => {
                                return Err(RenderError::Compile(CompileError {
                                    location: file.label(),
                                    message: "the shader file was not read again".into(),
                                }))
                            }
                        },
                        _ => read_program(source, &file)?,
                    };
                    let fields = assemble(source, &file, &text)?.fields;
                    m.programs.push(Program {
                        file: file.clone(),
                        text,
                        fields,
                    });
                    m.programs.len() - 1
                }
            };
            let label = file.label();
            let words = match sh {
                Shader::Phong(p) | Shader::BlinnPhong(p) => {
                    phong_words(&m.programs[program].fields, p, uses, &label)?
                }
                Shader::MetallicRoughness(mr) => {
                    metallic_roughness_words(&m.programs[program].fields, mr, uses, &label)?
                }
                Shader::SpecularGlossiness(sg) => {
                    specular_glossiness_words(&m.programs[program].fields, sg, uses, &label)?
                }
                Shader::Wgsl(w) => {
                    // The scene's values were checked against the Params the
                    // file had when it was loaded.
                    if w.fields != m.programs[program].fields {
                        return Err(RenderError::ParamsChanged { file: label });
                    }
                    w.words(|t| crate::scene::Scene::texture_use_index(uses, t))
                }
                Shader::Checker(_) => Vec::new(),
            };
            // Each leaf's words start a texel (stages/shade.wgsl).
            m.leaves
                .push(Some((program as u32, (m.words.len() / 4) as u32)));
            m.words.extend(&words);
            m.words.resize(m.words.len().next_multiple_of(4), 0);
        }
        Ok(m)
    }
}

/// The parsed module of the built-in Phong shade pipeline, from the
/// embedded files: what the layout and override tests read the shade
/// stage's declarations from.
#[cfg(test)]
pub(crate) fn phong_module() -> naga::Module {
    let file = ProgramFile::Builtin("shading/phong.wgsl");
    let text = read_program(&ShaderSource::Embedded, &file).unwrap();
    assemble(&ShaderSource::Embedded, &file, &text)
        .unwrap()
        .assembled
        .parse()
        .unwrap()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builtins_assemble_with_the_phong_fields() {
        for name in ["shading/phong.wgsl", "shading/blinn_phong.wgsl"] {
            let file = ProgramFile::Builtin(name);
            let text = read_program(&ShaderSource::Embedded, &file).unwrap();
            let s = assemble(&ShaderSource::Embedded, &file, &text).unwrap();
            let names: Vec<_> = s.fields.iter().map(|f| (f.name.as_str(), f.ty)).collect();
            assert_eq!(
                names,
                [
                    ("ambient", ParamType::Vec3),
                    ("diffuse", ParamType::Vec3),
                    ("specular", ParamType::Vec3),
                    ("shininess", ParamType::F32),
                    ("ambient_texture", ParamType::U32),
                    ("diffuse_texture", ParamType::U32),
                    ("specular_texture", ParamType::U32)
                ]
            );
            assert!(s.has_ambient);
            let words = s
                .assembled
                .compile_entry(&Default::default(), SHADE_ENTRY_POINT)
                .unwrap();
            assert_eq!(words[0], 0x0723_0203);
        }
    }

    /// A scene without textures gets a Phong shade pipeline without the
    /// texture sampler: `render::prune` drops the arms that
    /// `penumbra_HAS_TEXTURES` switches off, which was most of the pipeline
    /// creation of a Phong edit on lavapipe (docs/reload.md). The texture
    /// sampler is the only code that loads from `penumbra_texture_texels`
    /// (binding 20), so its absence shows as that binding's absence.
    #[test]
    fn without_textures_the_phong_pipeline_has_no_sampler() {
        let file = ProgramFile::Builtin("shading/phong.wgsl");
        let text = read_program(&ShaderSource::Embedded, &file).unwrap();
        let s = assemble(&ShaderSource::Embedded, &file, &text).unwrap();
        let compile = |textures: bool| {
            let key = super::super::StageKernel {
                features: variant(&Features {
                    textures,
                    triangles: true,
                    directional_lights: true,
                    ..Features::default()
                }),
                ..Default::default()
            };
            s.assembled.compile_entry(&key, SHADE_ENTRY_POINT).unwrap()
        };
        // OpDecorate %var Binding 20: (4 << 16) | 71, the variable, 33, 20.
        let binds_20 = |words: &[u32]| {
            words
                .windows(4)
                .any(|w| w[0] == (4 << 16) | 71 && w[2] == 33 && w[3] == 20)
        };
        let with = compile(true);
        let without = compile(false);
        assert!(
            binds_20(&with),
            "the sampler's texels are bound with textures"
        );
        assert!(!binds_20(&without), "the sampler stayed without textures");
        assert!(without.len() < with.len());
    }

    /// The shade stage stores its colours as 64-bit words only where the
    /// stages write words (lavapipe): otherwise its module declares no
    /// 64-bit integers, which a GPU without `shaderInt64` could not run.
    #[test]
    fn only_stage_words_give_the_shade_stage_64_bit_integers() {
        /// SPIR-V's `Int64` capability.
        const INT64: u32 = 11;
        let file = ProgramFile::Builtin("shading/phong.wgsl");
        let text = read_program(&ShaderSource::Embedded, &file).unwrap();
        let s = assemble(&ShaderSource::Embedded, &file, &text).unwrap();
        let int64 = |stage_words: bool| {
            let key = super::super::StageKernel {
                settings: super::super::Settings {
                    stage_words,
                    ..Default::default()
                },
                ..Default::default()
            };
            let words = s.assembled.compile_entry(&key, SHADE_ENTRY_POINT).unwrap();
            crate::render::spirv::capabilities(&words).contains(&INT64)
        };
        assert!(int64(true));
        assert!(!int64(false));
    }

    /// The shade stage runs user code: naga clamps its texel fetches (an
    /// image-size query each) and buffer indices, which the engine's other
    /// stages leave unchecked (none of their files asks for an image's size).
    #[test]
    fn the_shade_stage_is_bounds_checked() {
        /// `OpImageQuerySizeLod` and `OpImageQuerySize`.
        const QUERIES: [u32; 2] = [103, 104];
        let queries = |words: &[u32]| {
            let mut n = 0;
            let mut at = 5;
            while at < words.len() {
                let (op, count) = (words[at] & 0xffff, (words[at] >> 16) as usize);
                n += usize::from(QUERIES.contains(&op));
                at += count.max(1);
            }
            n
        };
        let file = ProgramFile::User("painted.wgsl".into());
        let text = include_str!("../../scenes/shaders/painted.wgsl");
        let s = assemble(&ShaderSource::Embedded, &file, text).unwrap();
        let key = super::super::StageKernel {
            features: variant(&Features {
                textures: true,
                ..Features::default()
            }),
            ..Default::default()
        };
        let shade = s.assembled.compile_entry(&key, SHADE_ENTRY_POINT).unwrap();
        assert!(queries(&shade) > 0, "no bounds checks in the shade stage");
        for stage in super::super::stages::Stage::FRAME {
            let assembled = ShaderSource::Embedded.assemble_stage(stage).unwrap();
            let words = assembled
                .compile_entry(&Default::default(), stage.entry_point())
                .unwrap();
            assert_eq!(queries(&words), 0, "{}", stage.entry_point());
        }
    }

    #[test]
    fn a_file_without_params_gets_the_placeholder() {
        let file = ProgramFile::User("normals.wgsl".into());
        let text = "fn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32> {\n    return 0.5 * s.normal + 0.5;\n}\n";
        let s = assemble(&ShaderSource::Embedded, &file, text).unwrap();
        assert!(s.fields.is_empty() && !s.has_ambient);
        s.assembled
            .compile_entry(&Default::default(), SHADE_ENTRY_POINT)
            .unwrap();
    }

    #[test]
    fn packs_every_kind_in_field_order() {
        let file = ProgramFile::User("toon.wgsl".into());
        let text = "struct Params { a: f32, b: i32, c: u32, d: vec2<f32>, e: vec4<f32> }\nfn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32> {\n    return vec3<f32>(p.a + f32(p.b) + f32(p.c) + p.d.x + p.e.w);\n}\n";
        let s = assemble(&ShaderSource::Embedded, &file, text).unwrap();
        let kinds: Vec<_> = s.fields.iter().map(|f| f.ty).collect();
        assert_eq!(
            kinds,
            [
                ParamType::F32,
                ParamType::I32,
                ParamType::U32,
                ParamType::Vec2,
                ParamType::Vec4
            ]
        );
        let loader = s
            .assembled
            .text
            .rsplit("fn penumbra_load_params")
            .next()
            .unwrap();
        assert!(
            loader.contains("vec4<f32>(bitcast<f32>(t1.y), bitcast<f32>(t1.z), bitcast<f32>(t1.w), bitcast<f32>(t2.x))"),
            "{loader}"
        );
        s.assembled
            .compile_entry(&Default::default(), SHADE_ENTRY_POINT)
            .unwrap();
    }
}
