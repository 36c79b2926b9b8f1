//! The JSON scene format, documented field by field in `scenes/README.md`.
//!
//! Parsing is strict: unknown fields are errors, every field has one type,
//! and every value is checked where it is read, so an error names the file and
//! the JSON path of the field (`objects[2].radius`).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use glam::{DMat3, DMat4, DVec3, Vec3};
use serde::Deserialize;

use super::{LoadOptions, Loaded};
use crate::scene::MAX_LIGHT_SAMPLES;
use crate::scene::{
    Camera, Checker, Filter, Light, LightKind, MetallicRoughness, MetallicRoughnessTextures,
    Object, ParamField, ParamType, ParamValue, Phong, PhongTextures, Plane, Projection, Sampler,
    Scene, Shader, ShaderId, Shape, Sphere, Texture, TextureId, TextureRef, Triangle, UvTransform,
    WgslShader, Wrap,
};
use crate::SceneError;

/// Light samples per pass of an area light without a `samples` field.
pub const DEFAULT_LIGHT_SAMPLES: u32 = 16;

type V3 = [f64; 3];
type C3 = [f32; 3];

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    camera: CameraFile,
    #[serde(default)]
    background: C3,
    #[serde(default)]
    shaders: BTreeMap<String, ShaderFile>,
    #[serde(default)]
    objects: Vec<ObjectFile>,
    #[serde(default)]
    lights: Vec<LightFile>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraFile {
    position: V3,
    look_at: Option<V3>,
    up: Option<V3>,
    yaw: Option<f64>,
    pitch: Option<f64>,
    roll: Option<f64>,
    #[serde(default)]
    projection: ProjectionKind,
    fov: Option<f64>,
    half_height: Option<f64>,
    width: u32,
    height: u32,
}

#[derive(Deserialize, Default, PartialEq, Clone, Copy)]
#[serde(rename_all = "snake_case")]
enum ProjectionKind {
    #[default]
    Perspective,
    Orthographic,
}

#[derive(Deserialize, PartialEq, Clone, Copy)]
#[serde(rename_all = "snake_case")]
enum ShaderKind {
    Phong,
    BlinnPhong,
    MetallicRoughness,
    SpecularGlossiness,
    Checker,
    Wgsl,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ShaderFile {
    #[serde(rename = "type")]
    kind: ShaderKind,
    /// `[r, g, b]` or a texture object ([`Reader::colour_or_texture`]).
    ambient: Option<serde_json::Value>,
    /// As `ambient`.
    diffuse: Option<serde_json::Value>,
    /// As `ambient`.
    specular: Option<serde_json::Value>,
    shininess: Option<f32>,
    /// `[r, g, b]` or a texture object (metallic_roughness).
    base_colour: Option<serde_json::Value>,
    metallic: Option<f32>,
    roughness: Option<f32>,
    /// A texture object: B scales metallic, G roughness.
    metallic_roughness: Option<serde_json::Value>,
    glossiness: Option<f32>,
    /// A texture object: RGB scales specular, A glossiness.
    specular_glossiness: Option<serde_json::Value>,
    size: Option<f64>,
    even: Option<String>,
    odd: Option<String>,
    file: Option<PathBuf>,
    params: Option<serde_json::Map<String, serde_json::Value>>,
}

#[derive(Deserialize, PartialEq, Clone, Copy)]
#[serde(rename_all = "snake_case")]
enum ObjectKind {
    Plane,
    Sphere,
    Triangle,
    Mesh,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ObjectFile {
    #[serde(rename = "type")]
    kind: ObjectKind,
    shader: Option<String>,
    point: Option<V3>,
    normal: Option<V3>,
    center: Option<V3>,
    radius: Option<f64>,
    vertices: Option<[V3; 3]>,
    file: Option<PathBuf>,
    transform: Option<TransformFile>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct TransformFile {
    #[serde(default)]
    translate: V3,
    /// Degrees about the world X, then Y, then Z axis.
    #[serde(default)]
    rotate: V3,
    scale: Option<Scale>,
}

#[derive(Deserialize)]
#[serde(untagged)]
enum Scale {
    Uniform(f64),
    PerAxis(V3),
}

#[derive(Deserialize, PartialEq, Clone, Copy)]
#[serde(rename_all = "snake_case")]
enum LightType {
    Directional,
    Point,
    Spot,
    Rect,
    Sphere,
    Environment,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LightFile {
    #[serde(rename = "type")]
    kind: LightType,
    position: Option<V3>,
    direction: Option<V3>,
    inner_angle: Option<f64>,
    outer_angle: Option<f64>,
    corner: Option<V3>,
    edge1: Option<V3>,
    edge2: Option<V3>,
    center: Option<V3>,
    radius: Option<f64>,
    up: Option<V3>,
    samples: Option<u32>,
    intensity: Option<f32>,
    ambient: Option<C3>,
    diffuse: Option<C3>,
    specular: Option<C3>,
}

/// Checks that exactly the fields a kind needs are present: `fields` lists
/// (name, present, needed-by-this-kind).
fn fields_for(
    file: &Path,
    at: &str,
    kind: &str,
    fields: &[(&str, bool, bool)],
) -> Result<(), SceneError> {
    for &(name, present, needed) in fields {
        if needed && !present {
            return Err(SceneError::new(
                file,
                at,
                format!("missing field `{name}` (required for {kind})"),
            ));
        }
        if present && !needed {
            return Err(SceneError::new(
                file,
                format!("{at}.{name}"),
                format!("not a field of {kind}"),
            ));
        }
    }
    Ok(())
}

/// The shaders of a scene file, their ids by name, the WGSL files read and
/// the textures they sample.
struct Shaders {
    shaders: Vec<Shader>,
    ids: BTreeMap<String, ShaderId>,
    wgsl_files: Vec<PathBuf>,
    textures: Textures,
}

/// The texture files read so far: the scene's texture list, and each file's
/// place in it, so that a file named twice is read and uploaded once.
#[derive(Default)]
struct Textures {
    /// In the order first named: [`Scene::textures`].
    list: Vec<Texture>,
    /// By the file's canonical path (or its path as named, when it cannot be
    /// resolved) and whether it is decoded from sRGB: one file named with
    /// both encodings is two textures.
    by_path: BTreeMap<(PathBuf, bool), TextureId>,
}

/// The keys of a texture object (`{"texture": "wood.png", ...}`).
const TEXTURE_KEYS: [&str; 5] = ["texture", "scale", "filter", "wrap", "encoding"];

/// What a texture object may stand for, for the message when one is found
/// elsewhere.
const TEXTURE_PLACES: &str = "a texture (`{\"texture\": ...}`) can only be the `ambient`, `diffuse` or `specular` colour of a phong or blinn_phong shader, the `base_colour` or `metallic_roughness` of a metallic_roughness shader, the `diffuse` or `specular_glossiness` of a specular_glossiness shader, or the value of a u32 Params field of a wgsl shader";

/// A JSON value described for messages.
fn describe(v: &serde_json::Value) -> String {
    use serde_json::Value;
    match v {
        Value::Null => "null".to_string(),
        Value::Bool(b) => format!("{b}"),
        Value::Number(n) => format!("{n}"),
        Value::String(s) => format!("the string {s:?}"),
        Value::Array(a) => format!("an array of {}", a.len()),
        Value::Object(_) => "an object".to_string(),
    }
}

/// The WGSL files read so far, by resolved path: text and reflection.
type WgslFiles = BTreeMap<PathBuf, (String, crate::wgsl::Reflection)>;

struct Reader<'a> {
    file: &'a Path,
    /// The shader of a `mesh` object without one (its glTF materials).
    gltf_materials: super::GltfMaterials,
}

impl Reader<'_> {
    fn err(&self, field: impl Into<String>, msg: impl Into<String>) -> SceneError {
        SceneError::new(self.file, field, msg)
    }

    fn finite(&self, field: &str, v: V3) -> Result<DVec3, SceneError> {
        let v = DVec3::from_array(v);
        if !v.is_finite() {
            return Err(self.err(field, format!("must be finite, got {v}")));
        }
        Ok(v)
    }

    fn direction(&self, field: &str, v: V3) -> Result<DVec3, SceneError> {
        let v = self.finite(field, v)?;
        let len = v.length();
        if !(len > 0.0 && len.is_finite()) {
            return Err(self.err(field, "must be a non-zero vector"));
        }
        Ok(v / len)
    }

    fn colour(&self, field: &str, c: C3) -> Result<Vec3, SceneError> {
        let c = Vec3::from_array(c);
        if !c.is_finite() || c.min_element() < 0.0 {
            return Err(self.err(field, format!("must be finite and non-negative, got {c}")));
        }
        Ok(c)
    }

    /// The camera: position, orientation (`look_at`/`up` or yaw, pitch and
    /// roll), projection, and the image size after `opts`' overrides.
    fn camera(&self, c: &CameraFile, opts: &LoadOptions) -> Result<Camera, SceneError> {
        let position = self.finite("camera.position", c.position)?;
        let euler = c.yaw.is_some() || c.pitch.is_some() || c.roll.is_some();
        let orientation = match (c.look_at, euler) {
            (Some(_), true) => {
                return Err(self.err(
                    "camera",
                    "give either `look_at` (with `up`) or `yaw`/`pitch`/`roll`, not both",
                ))
            }
            (Some(target), false) => {
                let target = self.finite("camera.look_at", target)?;
                let up = self.finite("camera.up", c.up.unwrap_or([0.0, 1.0, 0.0]))?;
                Camera::look_at(position, target, up).map_err(|e| match e {
                    crate::scene::camera::OrientationError::ZeroViewDirection => {
                        self.err("camera.look_at", "must differ from camera.position")
                    }
                    crate::scene::camera::OrientationError::ZeroUp => {
                        self.err("camera.up", "must be a non-zero vector")
                    }
                    crate::scene::camera::OrientationError::UpParallelToView => self.err(
                        "camera.up",
                        "is parallel to the view direction (look_at - position)",
                    ),
                })?
            }
            (None, _) => {
                if c.up.is_some() {
                    return Err(self.err("camera.up", "only used with `look_at`"));
                }
                let mut angles = [0.0; 3];
                for (k, (name, v)) in [("yaw", c.yaw), ("pitch", c.pitch), ("roll", c.roll)]
                    .into_iter()
                    .enumerate()
                {
                    let v = v.unwrap_or(0.0);
                    if !v.is_finite() {
                        return Err(self.err(format!("camera.{name}"), "must be finite"));
                    }
                    angles[k] = v;
                }
                Camera::yaw_pitch_roll(angles[0], angles[1], angles[2])
            }
        };
        let projection = match c.projection {
            ProjectionKind::Perspective => {
                if c.half_height.is_some() {
                    return Err(self.err(
                        "camera.half_height",
                        "only used with \"projection\": \"orthographic\"",
                    ));
                }
                let fov = c.fov.unwrap_or(45.0);
                if !(fov > 0.0 && fov < 180.0) {
                    return Err(self.err(
                        "camera.fov",
                        format!("must be in (0, 180) degrees, got {fov}"),
                    ));
                }
                Projection::Perspective { vfov_deg: fov }
            }
            ProjectionKind::Orthographic => {
                if c.fov.is_some() {
                    return Err(self.err(
                        "camera.fov",
                        "only used with \"projection\": \"perspective\"",
                    ));
                }
                let h = c.half_height.ok_or_else(|| {
                    self.err(
                        "camera",
                        "missing field `half_height` (required for an orthographic camera)",
                    )
                })?;
                if !(h > 0.0 && h.is_finite()) {
                    return Err(
                        self.err("camera.half_height", format!("must be positive, got {h}"))
                    );
                }
                Projection::Orthographic { half_height: h }
            }
        };
        let (width, height) = super::override_size(opts, c.width, c.height);
        let max = crate::scene::MAX_IMAGE_SIDE;
        for (name, v, cli) in [
            ("camera.width", width, opts.width.is_some()),
            ("camera.height", height, opts.height.is_some()),
        ] {
            if v == 0 || v > max {
                let field = if cli {
                    name.replace("camera.", "--")
                } else {
                    name.to_string()
                };
                return Err(self.err(field, format!("must be in 1..={max} pixels, got {v}")));
            }
        }
        Ok(Camera {
            position,
            orientation,
            projection,
            width,
            height,
        })
    }

    /// Reads, once per file, the WGSL file `rel` of shader `at` (relative to
    /// the scene's folder `base`) and reflects it; `read` keeps what was read.
    fn wgsl_file(
        &self,
        at: &str,
        rel: &Path,
        base: &Path,
        guard: &super::guard::Guard,
        read: &mut WgslFiles,
    ) -> Result<(PathBuf, String, crate::wgsl::Reflection), SceneError> {
        let field = format!("{at}.file");
        let path = base.join(rel);
        if let Some((source, r)) = read.get(&path) {
            return Ok((path, source.clone(), r.clone()));
        }
        if !path.exists() {
            return Err(self.err(field, format!("no such file: {}", path.display())));
        }
        let source = super::read_shader_file(&path, guard).map_err(|e| self.err(&field, e.0))?;
        let r =
            crate::wgsl::reflect(&path, &source).map_err(|e| self.err(&field, e.to_string()))?;
        read.insert(path.clone(), (source.clone(), r.clone()));
        Ok((path, source, r))
    }

    /// The colour field `at` of a phong or blinn_phong shader: `[r, g, b]`
    /// (`default` when absent), or a texture object, which makes the colour
    /// (1, 1, 1) and returns the texture's use.
    fn colour_or_texture(
        &self,
        at: &str,
        v: Option<&serde_json::Value>,
        default: C3,
        base: &Path,
        guard: &super::guard::Guard,
        textures: &mut Textures,
    ) -> Result<(Vec3, Option<TextureRef>), SceneError> {
        use serde_json::Value;
        match v {
            None | Some(Value::Null) => Ok((self.colour(at, default)?, None)),
            Some(a @ Value::Array(_)) => {
                let c: C3 =
                    serde_json::from_value(a.clone()).map_err(|e| self.err(at, e.to_string()))?;
                Ok((self.colour(at, c)?, None))
            }
            Some(Value::Object(m)) => {
                let t = self.texture_use(at, m, base, guard, textures)?;
                Ok((Vec3::ONE, Some(t)))
            }
            Some(other) => Err(self.err(
                at,
                format!(
                    "must be a colour [r, g, b] or a texture {{\"texture\": \"file.png\"}}, got {}",
                    describe(other)
                ),
            )),
        }
    }

    /// A texture object at `at`: `{"texture": FILE}` with optional
    /// `"scale"`, `"filter"`, `"wrap"` and `"encoding"`; the file is read
    /// relative to `base` (once per file and encoding) and decoded as an
    /// sRGB colour texture, or as linear values with `"encoding": "linear"`
    /// (data such as roughness or heights; pbrt-v4's image textures name
    /// the same choice `encoding`).
    fn texture_use(
        &self,
        at: &str,
        m: &serde_json::Map<String, serde_json::Value>,
        base: &Path,
        guard: &super::guard::Guard,
        textures: &mut Textures,
    ) -> Result<TextureRef, SceneError> {
        use serde_json::Value;
        for key in m.keys() {
            if !TEXTURE_KEYS.contains(&key.as_str()) {
                return Err(self.err(
                    format!("{at}.{key}"),
                    format!(
                        "unknown field `{key}` of a texture, expected one of `texture`, `scale`, `filter`, `wrap`, `encoding`"
                    ),
                ));
            }
        }
        let field = |k: &str| format!("{at}.{k}");
        let file = match m.get("texture") {
            Some(Value::String(f)) if !f.is_empty() => f,
            Some(other) => {
                return Err(self.err(
                    field("texture"),
                    format!("must be an image file name, got {}", describe(other)),
                ))
            }
            None => {
                return Err(self.err(
                    at,
                    "missing field `texture` (the image file, relative to the scene file)",
                ))
            }
        };
        let srgb = match m.get("encoding") {
            None => true,
            Some(Value::String(e)) if e == "srgb" => true,
            Some(Value::String(e)) if e == "linear" => false,
            Some(other) => {
                return Err(self.err(
                    field("encoding"),
                    format!("must be \"srgb\" or \"linear\", got {}", describe(other)),
                ))
            }
        };
        let texture = self.texture_file(
            &field("texture"),
            Path::new(file),
            base,
            guard,
            textures,
            srgb,
        )?;
        let (mag, min, mip) = match m.get("filter") {
            None => (Filter::Linear, Filter::Linear, Some(Filter::Linear)),
            Some(Value::String(f)) => match f.as_str() {
                "nearest" => (Filter::Nearest, Filter::Nearest, None),
                "bilinear" => (Filter::Linear, Filter::Linear, Some(Filter::Nearest)),
                "trilinear" => (Filter::Linear, Filter::Linear, Some(Filter::Linear)),
                _ => {
                    return Err(self.err(
                        field("filter"),
                        format!(
                        "unknown filter {f:?}, expected \"nearest\", \"bilinear\" or \"trilinear\""
                    ),
                    ))
                }
            },
            Some(other) => {
                return Err(self.err(
                    field("filter"),
                    format!(
                        "must be \"nearest\", \"bilinear\" or \"trilinear\", got {}",
                        describe(other)
                    ),
                ))
            }
        };
        let wrap_of = |at: &str, v: &Value| -> Result<Wrap, SceneError> {
            match v.as_str() {
                Some("repeat") => Ok(Wrap::Repeat),
                Some("mirrored_repeat") => Ok(Wrap::MirroredRepeat),
                Some("clamp") => Ok(Wrap::ClampToEdge),
                Some(w) => Err(self.err(
                    at,
                    format!("unknown wrap mode {w:?}, expected \"repeat\", \"mirrored_repeat\" or \"clamp\""),
                )),
                None => Err(self.err(
                    at,
                    format!(
                        "must be \"repeat\", \"mirrored_repeat\" or \"clamp\" (or an array of two: u, v), got {}",
                        describe(v)
                    ),
                )),
            }
        };
        let (wrap_u, wrap_v) = match m.get("wrap") {
            None => (Wrap::Repeat, Wrap::Repeat),
            Some(Value::Array(a)) if a.len() == 2 => (
                wrap_of(&format!("{at}.wrap[0]"), &a[0])?,
                wrap_of(&format!("{at}.wrap[1]"), &a[1])?,
            ),
            Some(v) => {
                let w = wrap_of(&field("wrap"), v)?;
                (w, w)
            }
        };
        let scale = match m.get("scale") {
            None => glam::DVec2::ONE,
            Some(Value::Number(n)) => glam::DVec2::splat(n.as_f64().unwrap_or(f64::NAN)),
            Some(Value::Array(a)) if a.len() == 2 && a.iter().all(Value::is_number) => {
                glam::DVec2::new(
                    a[0].as_f64().unwrap_or(f64::NAN),
                    a[1].as_f64().unwrap_or(f64::NAN),
                )
            }
            Some(other) => {
                return Err(self.err(
                    field("scale"),
                    format!(
                        "must be a number or an array of two numbers [su, sv], got {}",
                        describe(other)
                    ),
                ))
            }
        };
        // f32 on the GPU: finite there too, and not zero (that would squash
        // the texture to one texel).
        let s32 = scale.as_vec2();
        if !s32.is_finite() || s32.x == 0.0 || s32.y == 0.0 {
            return Err(self.err(
                field("scale"),
                format!("must be finite and non-zero, got {scale}"),
            ));
        }
        Ok(TextureRef {
            texture,
            sampler: Sampler {
                mag,
                min,
                mip,
                wrap_u,
                wrap_v,
            },
            tex_coord: 0,
            transform: UvTransform {
                scale,
                ..UvTransform::default()
            },
        })
    }

    /// The texture file `rel` named at `field`, relative to `base`: its id
    /// in `textures`, reading and decoding it (through the guard; `srgb`:
    /// as a colour texture) the first time it is named with that encoding.
    fn texture_file(
        &self,
        field: &str,
        rel: &Path,
        base: &Path,
        guard: &super::guard::Guard,
        textures: &mut Textures,
        srgb: bool,
    ) -> Result<TextureId, SceneError> {
        let path = base.join(rel);
        let key = (path.canonicalize().unwrap_or_else(|_| path.clone()), srgb);
        if let Some(&id) = textures.by_path.get(&key) {
            return Ok(id);
        }
        if !path.exists() {
            return Err(self.err(field, format!("no such file: {}", path.display())));
        }
        let texture = read_texture(&path, srgb, guard).map_err(|e| self.err(field, e.0))?;
        textures.list.push(texture);
        let id = textures.list.len() - 1;
        textures.by_path.insert(key, id);
        Ok(id)
    }

    /// The value of Params field `field` of shader file `file` from the JSON
    /// value `v` at `at`.
    ///
    /// A u32 field may be given a texture object, which reads the texture
    /// ([`Reader::texture_use`]) and makes the value
    /// [`ParamValue::Texture`].
    #[allow(clippy::too_many_arguments)]
    fn param(
        &self,
        at: &str,
        file: &str,
        field: &ParamField,
        v: &serde_json::Value,
        base: &Path,
        guard: &super::guard::Guard,
        textures: &mut Textures,
    ) -> Result<ParamValue, SceneError> {
        use serde_json::Value;
        if let Value::Object(m) = v {
            if field.ty == ParamType::U32 {
                return Ok(ParamValue::Texture(
                    self.texture_use(at, m, base, guard, textures)?,
                ));
            }
            if m.contains_key("texture") {
                return Err(self.err(
                    at,
                    format!(
                        "Params field `{}` of {file} is {}; only a u32 field can take a texture",
                        field.name, field.ty
                    ),
                ));
            }
        }
        let what = |v: &Value| match v {
            Value::Null => "null".to_string(),
            Value::Bool(b) => format!("{b}"),
            Value::Number(n) => format!("{n}"),
            Value::String(_) => "a string".to_string(),
            Value::Array(a) => format!("an array of {}", a.len()),
            Value::Object(_) => "an object".to_string(),
        };
        let (name, ty) = (&field.name, field.ty);
        let wrong = |expected: &str| {
            self.err(
                at,
                format!(
                    "Params field `{name}` of {file} is {ty}, expected {expected}, got {}",
                    what(v)
                ),
            )
        };
        // An f32 from a JSON number: finite also after rounding to f32.
        let float = |x: &Value, label: &str| -> Result<f32, SceneError> {
            let Some(f) = x.as_f64() else {
                return Err(self.err(
                    at,
                    format!(
                        "Params field `{name}` of {file} is {ty}, expected {label}, got {}",
                        what(x)
                    ),
                ));
            };
            let g = f as f32;
            if !g.is_finite() {
                return Err(self.err(
                    at,
                    format!("Params field `{name}` of {file} is {ty}, expected a finite number, got {f:e} (not finite as f32)"),
                ));
            }
            Ok(g)
        };
        match ty {
            ParamType::F32 => Ok(ParamValue::F32(float(v, "a number")?)),
            ParamType::I32 => v
                .as_i64()
                .and_then(|x| i32::try_from(x).ok())
                .map(ParamValue::I32)
                .ok_or_else(|| wrong("an integer in -2147483648..=2147483647")),
            ParamType::U32 => v
                .as_u64()
                .and_then(|x| u32::try_from(x).ok())
                .map(ParamValue::U32)
                .ok_or_else(|| wrong("an integer in 0..=4294967295")),
            ParamType::Vec2 | ParamType::Vec3 | ParamType::Vec4 => {
                let n = ty.words();
                let expected = format!("an array of {n} numbers");
                let Value::Array(items) = v else {
                    return Err(wrong(&expected));
                };
                if items.len() != n {
                    return Err(self.err(
                        at,
                        format!(
                            "Params field `{name}` of {file} is {ty}, expected {expected}, got {}",
                            items.len()
                        ),
                    ));
                }
                let xs = items
                    .iter()
                    .map(|x| float(x, &expected))
                    .collect::<Result<Vec<_>, _>>()?;
                Ok(ParamValue::Vec(xs))
            }
        }
    }

    /// A `wgsl` shader at `at`: its file, reflected, and its params.
    fn wgsl(
        &self,
        at: &str,
        s: &ShaderFile,
        base: &Path,
        guard: &super::guard::Guard,
        read: &mut WgslFiles,
        textures: &mut Textures,
    ) -> Result<WgslShader, SceneError> {
        let rel = s.file.clone().unwrap_or_default();
        let (path, source, r) = self.wgsl_file(at, &rel, base, guard, read)?;
        let file = rel.display().to_string();
        let empty = serde_json::Map::new();
        let given = s.params.as_ref().unwrap_or(&empty);
        for key in given.keys() {
            if !r.fields.iter().any(|f| &f.name == key) {
                return Err(self.err(
                    format!("{at}.params.{key}"),
                    format!("{file}'s Params has no field `{key}`"),
                ));
            }
        }
        let mut values = Vec::with_capacity(r.fields.len());
        for field in &r.fields {
            let fat = format!("{at}.params.{}", field.name);
            let Some(v) = given.get(&field.name) else {
                return Err(self.err(
                    fat,
                    format!(
                        "missing: Params field `{}: {}` of {file} has no value",
                        field.name, field.ty
                    ),
                ));
            };
            values.push(self.param(&fat, &file, field, v, base, guard, textures)?);
        }
        Ok(WgslShader {
            path,
            source,
            fields: r.fields,
            values,
            has_ambient: r.has_ambient,
        })
    }

    /// The shaders of the file, in name order (a shader's id is its place),
    /// every WGSL file read and the textures the shaders sample.
    fn shaders(
        &self,
        files: &BTreeMap<String, ShaderFile>,
        base: &Path,
        guard: &super::guard::Guard,
    ) -> Result<Shaders, SceneError> {
        let mut read = BTreeMap::new();
        let mut textures = Textures::default();
        let ids: BTreeMap<String, ShaderId> = files
            .keys()
            .enumerate()
            .map(|(i, k)| (k.clone(), i))
            .collect();
        let mut shaders = Vec::new();
        for (name, s) in files {
            shaders.push(self.shader(name, s, &ids, base, guard, &mut read, &mut textures)?);
        }
        self.checker_cycles(&shaders, &ids)?;
        Ok(Shaders {
            shaders,
            ids,
            wgsl_files: read.into_keys().collect(),
            textures,
        })
    }

    /// Shader `name`: the fields its kind needs (and no others), its
    /// colours and sizes, a checker's children by name in `ids`, a `wgsl`
    /// shader's file and params ([`Reader::wgsl`]); the textures they name
    /// go into `textures`.
    #[allow(clippy::too_many_arguments)]
    fn shader(
        &self,
        name: &str,
        s: &ShaderFile,
        ids: &BTreeMap<String, ShaderId>,
        base: &Path,
        guard: &super::guard::Guard,
        read: &mut WgslFiles,
        textures: &mut Textures,
    ) -> Result<Shader, SceneError> {
        let at = format!("shaders.{name}");
        let f = |k: &str| format!("{at}.{k}");
        let phong = matches!(s.kind, ShaderKind::Phong | ShaderKind::BlinnPhong);
        let checker = s.kind == ShaderKind::Checker;
        let wgsl = s.kind == ShaderKind::Wgsl;
        let pbr = s.kind == ShaderKind::MetallicRoughness;
        let sg = s.kind == ShaderKind::SpecularGlossiness;
        let kind = match s.kind {
            ShaderKind::Phong => "a phong shader",
            ShaderKind::BlinnPhong => "a blinn_phong shader",
            ShaderKind::MetallicRoughness => "a metallic_roughness shader",
            ShaderKind::SpecularGlossiness => "a specular_glossiness shader",
            ShaderKind::Checker => "a checker shader",
            ShaderKind::Wgsl => "a wgsl shader",
        };
        fields_for(
            self.file,
            &at,
            kind,
            &[
                // Required by Phong, optional for specular_glossiness.
                ("diffuse", s.diffuse.is_some() && !sg, phong),
                ("size", s.size.is_some(), checker),
                ("even", s.even.is_some(), checker),
                ("odd", s.odd.is_some(), checker),
                ("file", s.file.is_some(), wgsl),
            ],
        )?;
        for (k, present) in [
            ("ambient", s.ambient.is_some()),
            ("specular", s.specular.is_some()),
            ("shininess", s.shininess.is_some()),
        ] {
            if present && !phong && !(sg && k == "specular") {
                return Err(self.err(f(k), format!("not a field of {kind}")));
            }
        }
        for (k, present) in [
            ("base_colour", s.base_colour.is_some()),
            ("metallic", s.metallic.is_some()),
            ("roughness", s.roughness.is_some()),
            ("metallic_roughness", s.metallic_roughness.is_some()),
        ] {
            if present && !pbr {
                return Err(self.err(f(k), format!("not a field of {kind}")));
            }
        }
        for (k, present) in [
            ("glossiness", s.glossiness.is_some()),
            ("specular_glossiness", s.specular_glossiness.is_some()),
        ] {
            if present && !sg {
                return Err(self.err(f(k), format!("not a field of {kind}")));
            }
        }
        if s.params.is_some() && !wgsl {
            return Err(self.err(f("params"), format!("not a field of {kind}")));
        }
        // One exhaustive match: a new kind must say how it is read.
        match s.kind {
            ShaderKind::MetallicRoughness => self.metallic_roughness(&at, s, base, guard, textures),
            ShaderKind::SpecularGlossiness => {
                self.specular_glossiness(&at, s, base, guard, textures)
            }
            ShaderKind::Wgsl => Ok(Shader::Wgsl(
                self.wgsl(&at, s, base, guard, read, textures)?,
            )),
            ShaderKind::Phong | ShaderKind::BlinnPhong => self.phong(&at, s, base, guard, textures),
            ShaderKind::Checker => self.checker(&at, s, ids),
        }
    }

    /// A `phong` or `blinn_phong` shader at `at`: colours or textures,
    /// shininess.
    fn phong(
        &self,
        at: &str,
        s: &ShaderFile,
        base: &Path,
        guard: &super::guard::Guard,
        textures: &mut Textures,
    ) -> Result<Shader, SceneError> {
        let f = |k: &str| format!("{at}.{k}");
        let shininess = s.shininess.unwrap_or(1.0);
        if !(shininess >= 0.0 && shininess.is_finite()) {
            return Err(self.err(
                f("shininess"),
                format!("must be finite and >= 0, got {shininess}"),
            ));
        }
        let mut colour = |k: &str, v: &Option<serde_json::Value>| {
            self.colour_or_texture(&f(k), v.as_ref(), [0.0; 3], base, guard, textures)
        };
        let (ambient, ambient_t) = colour("ambient", &s.ambient)?;
        let (diffuse, diffuse_t) = colour("diffuse", &s.diffuse)?;
        let (specular, specular_t) = colour("specular", &s.specular)?;
        let p = Phong {
            textures: PhongTextures {
                ambient: ambient_t,
                diffuse: diffuse_t,
                specular: specular_t,
            },
            ambient,
            diffuse,
            specular,
            shininess,
        };
        Ok(match s.kind {
            ShaderKind::BlinnPhong => Shader::BlinnPhong(p),
            _ => Shader::Phong(p),
        })
    }

    /// A `checker` shader at `at`: its size and its two sub-shaders by name.
    fn checker(
        &self,
        at: &str,
        s: &ShaderFile,
        ids: &BTreeMap<String, ShaderId>,
    ) -> Result<Shader, SceneError> {
        let f = |k: &str| format!("{at}.{k}");
        let size = s.size.unwrap_or_default();
        if !(size > 0.0 && size.is_finite()) {
            return Err(self.err(f("size"), format!("must be positive, got {size}")));
        }
        let sub = |k: &str, v: &Option<String>| {
            let v = v.as_deref().unwrap_or_default();
            ids.get(v)
                .copied()
                .ok_or_else(|| self.err(f(k), format!("no shader named \"{v}\"")))
        };
        Ok(Shader::Checker(Checker {
            size,
            even: sub("even", &s.even)?,
            odd: sub("odd", &s.odd)?,
        }))
    }

    /// A `specular_glossiness` shader at `at`: the extension's defaults
    /// (diffuse and specular white, glossiness 1) for absent fields.
    fn specular_glossiness(
        &self,
        at: &str,
        s: &ShaderFile,
        base: &Path,
        guard: &super::guard::Guard,
        textures: &mut Textures,
    ) -> Result<Shader, SceneError> {
        let f = |k: &str| format!("{at}.{k}");
        let glossiness = match s.glossiness.unwrap_or(1.0) {
            x if (0.0..=1.0).contains(&x) => x,
            x => return Err(self.err(f("glossiness"), format!("must be in [0, 1], got {x}"))),
        };
        let (diffuse, diffuse_t) = self.colour_or_texture(
            &f("diffuse"),
            s.diffuse.as_ref(),
            [1.0; 3],
            base,
            guard,
            textures,
        )?;
        let specular = match &s.specular {
            None | Some(serde_json::Value::Null) => self.colour(&f("specular"), [1.0; 3])?,
            Some(v) => {
                let c: C3 = serde_json::from_value(v.clone())
                    .map_err(|e| self.err(f("specular"), e.to_string()))?;
                self.colour(&f("specular"), c)?
            }
        };
        let specular_glossiness = self.optional_texture(
            &f("specular_glossiness"),
            s.specular_glossiness.as_ref(),
            r#"{"texture": "file.png"}"#,
            (base, guard, textures),
        )?;
        Ok(Shader::SpecularGlossiness(
            crate::scene::SpecularGlossiness {
                diffuse,
                specular,
                glossiness,
                textures: crate::scene::SpecularGlossinessTextures {
                    diffuse: diffuse_t,
                    specular_glossiness,
                },
            },
        ))
    }

    /// A field that is absent (or null) or a texture object like `example`.
    fn optional_texture(
        &self,
        field: &str,
        v: Option<&serde_json::Value>,
        example: &str,
        (base, guard, textures): (&Path, &super::guard::Guard, &mut Textures),
    ) -> Result<Option<TextureRef>, SceneError> {
        match v {
            None | Some(serde_json::Value::Null) => Ok(None),
            Some(serde_json::Value::Object(m)) => {
                Ok(Some(self.texture_use(field, m, base, guard, textures)?))
            }
            Some(other) => Err(self.err(
                field,
                format!("must be a texture {example}, got {}", describe(other)),
            )),
        }
    }

    /// A `metallic_roughness` shader at `at`: glTF's defaults (base colour
    /// white, metallic 1, roughness 1) for absent fields.
    fn metallic_roughness(
        &self,
        at: &str,
        s: &ShaderFile,
        base: &Path,
        guard: &super::guard::Guard,
        textures: &mut Textures,
    ) -> Result<Shader, SceneError> {
        let f = |k: &str| format!("{at}.{k}");
        let factor = |k: &str, v: Option<f32>| match v.unwrap_or(1.0) {
            x if (0.0..=1.0).contains(&x) => Ok(x),
            x => Err(self.err(f(k), format!("must be in [0, 1], got {x}"))),
        };
        let metallic = factor("metallic", s.metallic)?;
        let roughness = factor("roughness", s.roughness)?;
        let (base_colour, base_t) = self.colour_or_texture(
            &f("base_colour"),
            s.base_colour.as_ref(),
            [1.0; 3],
            base,
            guard,
            textures,
        )?;
        let metallic_roughness = self.optional_texture(
            &f("metallic_roughness"),
            s.metallic_roughness.as_ref(),
            r#"{"texture": "file.png", "encoding": "linear"}"#,
            (base, guard, textures),
        )?;
        Ok(Shader::MetallicRoughness(MetallicRoughness {
            base_colour,
            metallic,
            roughness,
            textures: MetallicRoughnessTextures {
                base_colour: base_t,
                metallic_roughness,
            },
        }))
    }

    /// No cycle among the checker shaders.
    fn checker_cycles(
        &self,
        shaders: &[Shader],
        ids: &BTreeMap<String, ShaderId>,
    ) -> Result<(), SceneError> {
        // Checkers nest, but a cycle never resolves. Scene::validate rejects
        // one too, by index; here the error names the shader as the file does.
        let children = |i: ShaderId| match &shaders[i] {
            Shader::Checker(c) => vec![c.even, c.odd],
            _ => Vec::new(),
        };
        for (name, &start) in ids {
            let mut seen = vec![false; shaders.len()];
            let mut todo = children(start);
            while let Some(i) = todo.pop() {
                if i == start {
                    return Err(self.err(
                        format!("shaders.{name}"),
                        "checker shaders refer to each other in a cycle",
                    ));
                }
                if !std::mem::replace(&mut seen[i], true) {
                    todo.extend(children(i));
                }
            }
        }
        Ok(())
    }

    /// Light `i`: the fields its kind needs (and no others), its geometry,
    /// angles, sample count, intensity and colours.
    fn light(&self, i: usize, l: &LightFile) -> Result<Light, SceneError> {
        let at = format!("lights[{i}]");
        let f = |k: &str| format!("{at}.{k}");
        // Every field by name, without `..`: a field added to LightFile is a
        // compile error here until this function reads it.
        let LightFile {
            kind: light_type,
            position,
            direction,
            inner_angle,
            outer_angle,
            corner,
            edge1,
            edge2,
            center,
            radius,
            up,
            samples,
            intensity,
            ambient,
            diffuse,
            specular,
        } = l;
        // Which of the kind-specific fields each kind takes: one exhaustive
        // match, so that a new kind must say.
        let (kind_name, needs_pos, needs_dir, spot, rect, sphere, area) = match light_type {
            LightType::Directional => (
                "a directional light",
                false,
                true,
                false,
                false,
                false,
                false,
            ),
            LightType::Point => ("a point light", true, false, false, false, false, false),
            LightType::Spot => ("a spot light", true, true, true, false, false, false),
            LightType::Rect => ("a rect light", false, false, false, true, false, true),
            LightType::Sphere => ("a sphere light", false, false, false, false, true, true),
            LightType::Environment => ("an environment", false, false, false, false, false, true),
        };
        fields_for(
            self.file,
            &at,
            kind_name,
            &[
                ("position", position.is_some(), needs_pos),
                ("direction", direction.is_some(), needs_dir),
                ("inner_angle", inner_angle.is_some(), spot),
                ("outer_angle", outer_angle.is_some(), spot),
                ("corner", corner.is_some(), rect),
                ("edge1", edge1.is_some(), rect),
                ("edge2", edge2.is_some(), rect),
                ("center", center.is_some(), sphere),
                ("radius", radius.is_some(), sphere),
            ],
        )?;
        // Optional for an area light, not a field of the others.
        if samples.is_some() && !area {
            return Err(self.err(f("samples"), format!("not a field of {kind_name}")));
        }
        // Optional for the environment (default +y), not a field of the others.
        let environment = *light_type == LightType::Environment;
        if up.is_some() && !environment {
            return Err(self.err(f("up"), format!("not a field of {kind_name}")));
        }
        let sample_count = || {
            let n = samples.unwrap_or(DEFAULT_LIGHT_SAMPLES);
            if n == 0 || n > MAX_LIGHT_SAMPLES {
                return Err(self.err(
                    f("samples"),
                    format!("must be in 1..={MAX_LIGHT_SAMPLES}, got {n}"),
                ));
            }
            Ok(n)
        };
        let pos = || self.finite(&f("position"), position.unwrap_or_default());
        let dir = || self.direction(&f("direction"), direction.unwrap_or_default());
        let kind = match light_type {
            LightType::Directional => LightKind::Directional { direction: dir()? },
            LightType::Point => LightKind::Point { position: pos()? },
            LightType::Spot => {
                let (inner, outer) = (
                    inner_angle.unwrap_or_default(),
                    outer_angle.unwrap_or_default(),
                );
                if !(outer > 0.0 && outer <= 90.0) {
                    return Err(self.err(
                        f("outer_angle"),
                        format!("must be in (0, 90] degrees, got {outer}"),
                    ));
                }
                if !(inner >= 0.0 && inner < outer) {
                    return Err(self.err(
                        f("inner_angle"),
                        format!("must be in [0, outer_angle) degrees, got {inner}"),
                    ));
                }
                LightKind::Spot {
                    position: pos()?,
                    direction: dir()?,
                    inner_angle: inner.to_radians(),
                    outer_angle: outer.to_radians(),
                }
            }
            LightType::Rect => {
                let corner = self.finite(&f("corner"), corner.unwrap_or_default())?;
                let edge1 = self.finite(&f("edge1"), edge1.unwrap_or_default())?;
                let edge2 = self.finite(&f("edge2"), edge2.unwrap_or_default())?;
                // Zero area is checked with the scene (Scene::validate).
                LightKind::Rect {
                    corner,
                    edge1,
                    edge2,
                    samples: sample_count()?,
                }
            }
            LightType::Sphere => {
                let radius = radius.unwrap_or_default();
                if !(radius > 0.0 && radius.is_finite()) {
                    return Err(self.err(f("radius"), format!("must be positive, got {radius}")));
                }
                LightKind::Sphere {
                    center: self.finite(&f("center"), center.unwrap_or_default())?,
                    radius,
                    samples: sample_count()?,
                }
            }
            LightType::Environment => LightKind::Environment {
                up: self.direction(&f("up"), up.unwrap_or([0.0, 1.0, 0.0]))?,
                samples: samples
                    .map_or(Ok(crate::scene::ENVIRONMENT_SAMPLES), |_| sample_count())?,
            },
        };
        let intensity = intensity.unwrap_or(1.0);
        if !(intensity >= 0.0 && intensity.is_finite()) {
            return Err(self.err(
                f("intensity"),
                format!("must be finite and >= 0, got {intensity}"),
            ));
        }
        Ok(Light {
            kind,
            intensity,
            ambient: self.colour(&f("ambient"), ambient.unwrap_or_default())?,
            diffuse: self.colour(&f("diffuse"), diffuse.unwrap_or([1.0; 3]))?,
            specular: self.colour(&f("specular"), specular.unwrap_or([1.0; 3]))?,
        })
    }

    /// Object `i` of the file, added to `loaded`: the fields its kind
    /// needs (and no others), its shader by name and its shape; a mesh adds
    /// one object per glTF mesh ([`Reader::mesh`]).
    fn object(
        &self,
        i: usize,
        o: &ObjectFile,
        ids: &BTreeMap<String, ShaderId>,
        base: &Path,
        guard: &super::guard::Guard,
        loaded: &mut Loaded,
    ) -> Result<(), SceneError> {
        let at = format!("objects[{i}]");
        let f = |k: &str| format!("{at}.{k}");
        let (kind, needs): (&str, [bool; 6]) = match o.kind {
            // point, normal, center, radius, vertices, file
            ObjectKind::Plane => ("a plane", [true, true, false, false, false, false]),
            ObjectKind::Sphere => ("a sphere", [false, false, true, true, false, false]),
            ObjectKind::Triangle => ("a triangle", [false, false, false, false, true, false]),
            ObjectKind::Mesh => ("a mesh", [false, false, false, false, false, true]),
        };
        fields_for(
            self.file,
            &at,
            kind,
            &[
                ("point", o.point.is_some(), needs[0]),
                ("normal", o.normal.is_some(), needs[1]),
                ("center", o.center.is_some(), needs[2]),
                ("radius", o.radius.is_some(), needs[3]),
                ("vertices", o.vertices.is_some(), needs[4]),
                ("file", o.file.is_some(), needs[5]),
                (
                    "transform",
                    o.transform.is_some(),
                    o.kind == ObjectKind::Mesh && o.transform.is_some(),
                ),
            ],
        )?;
        let shader = match &o.shader {
            Some(name) => Some(
                *ids.get(name)
                    .ok_or_else(|| self.err(f("shader"), format!("no shader named \"{name}\"")))?,
            ),
            None if o.kind == ObjectKind::Mesh => None,
            None => {
                return Err(self.err(&at, format!("missing field `shader` (required for {kind})")))
            }
        };
        let shape = match o.kind {
            ObjectKind::Plane => Shape::Plane(Plane {
                point: self.finite(&f("point"), o.point.unwrap_or_default())?,
                normal: self.direction(&f("normal"), o.normal.unwrap_or_default())?,
            }),
            ObjectKind::Sphere => {
                let radius = o.radius.unwrap_or_default();
                if !(radius > 0.0 && radius.is_finite()) {
                    return Err(self.err(f("radius"), format!("must be positive, got {radius}")));
                }
                Shape::Sphere(Sphere {
                    center: self.finite(&f("center"), o.center.unwrap_or_default())?,
                    radius,
                })
            }
            ObjectKind::Triangle => {
                let v = o.vertices.unwrap_or_default();
                let mut vertices = [DVec3::ZERO; 3];
                for k in 0..3 {
                    vertices[k] = self.finite(&f(&format!("vertices[{k}]")), v[k])?;
                }
                Shape::Triangle(Triangle { vertices })
            }
            ObjectKind::Mesh => return self.mesh(&at, o, shader, base, guard, loaded),
        };
        loaded.scene.objects.push(Object {
            maps: Default::default(),
            shape,
            shader: shader.unwrap_or_default(),
        });
        Ok(())
    }

    /// A `mesh` object at `at` with the shader `shader` (None: each glTF
    /// mesh gets a shader of its material, as `--gltf-materials` says): reads the glTF file
    /// relative to `base`, applies the transform and adds the meshes, the
    /// notes and the files read to `loaded`.
    fn mesh(
        &self,
        at: &str,
        o: &ObjectFile,
        shader: Option<ShaderId>,
        base: &Path,
        guard: &super::guard::Guard,
        loaded: &mut Loaded,
    ) -> Result<(), SceneError> {
        let rel = o.file.clone().unwrap_or_default();
        let mesh_path = base.join(&rel);
        if !mesh_path.is_file() {
            return Err(self.err(
                format!("{at}.file"),
                format!("no such file: {}", mesh_path.display()),
            ));
        }
        guard
            .check_path(&mesh_path, "mesh file")
            .map_err(|e| self.err(format!("{at}.file"), e.0))?;
        let m = o
            .transform
            .as_ref()
            .map(|t| self.transform(&format!("{at}.transform"), t))
            .transpose()?
            .unwrap_or(DMat4::IDENTITY);
        let doc = super::gltf::read_with(&mesh_path, guard)?;
        let pbr =
            shader.is_none() && self.gltf_materials == super::GltfMaterials::MetallicRoughness;
        let applied = |n: &String| !(pbr && n.ends_with(super::gltf::METALLIC_ROUGHNESS_NOTE));
        loaded.notes.extend(doc.notes.into_iter().filter(applied));
        loaded.files.extend(doc.files);
        // The file's textures follow the scene's: its materials' texture
        // ids move by this much.
        let offset = loaded.scene.textures.len();
        if shader.is_none() {
            loaded.scene.textures.extend(doc.textures);
        }
        let moved = |t: &mut Option<TextureRef>| {
            if let Some(t) = t {
                t.texture += offset;
            }
        };
        let linear = DMat3::from_mat4(m);
        let normal_m = linear.inverse().transpose();
        for gm in doc.meshes {
            let (shader, maps) = match shader {
                // The scene's shader replaces the material, maps included.
                Some(s) => (s, Default::default()),
                None => {
                    let material = match self.gltf_materials {
                        _ if gm.unlit => Shader::Phong(super::gltf::UNLIT),
                        super::GltfMaterials::MetallicRoughness
                            if gm.specular_glossiness.is_some() =>
                        {
                            let mut sg = gm.specular_glossiness.expect("matched");
                            moved(&mut sg.textures.diffuse);
                            moved(&mut sg.textures.specular_glossiness);
                            Shader::SpecularGlossiness(sg)
                        }
                        super::GltfMaterials::MetallicRoughness => {
                            let mut pbr = gm.pbr;
                            moved(&mut pbr.textures.base_colour);
                            moved(&mut pbr.textures.metallic_roughness);
                            Shader::MetallicRoughness(pbr)
                        }
                        super::GltfMaterials::Phong => {
                            let mut phong = gm.phong;
                            moved(&mut phong.textures.ambient);
                            moved(&mut phong.textures.diffuse);
                            moved(&mut phong.textures.specular);
                            Shader::Phong(phong)
                        }
                    };
                    let mut maps = gm.maps;
                    if let Some((t, _)) = &mut maps.normal {
                        t.texture += offset;
                    }
                    moved(&mut maps.emission_texture);
                    moved(&mut maps.opacity_texture);
                    loaded.scene.shaders.push(material);
                    (loaded.scene.shaders.len() - 1, maps)
                }
            };
            let mut mesh = gm.mesh;
            for p in &mut mesh.positions {
                *p = m.transform_point3(*p);
            }
            if let Some(ns) = &mut mesh.normals {
                for n in ns.iter_mut() {
                    *n = (normal_m * *n).normalize_or_zero();
                }
            }
            if let Some(ts) = &mut mesh.tangents {
                // Tangents lie in the surface: they move with it; w (the
                // bitangent's sign) stays.
                for t in ts.iter_mut() {
                    let d = (linear * t.truncate()).normalize_or_zero();
                    *t = d.extend(t.w);
                }
            }
            loaded.scene.objects.push(Object {
                maps,
                shape: Shape::Mesh(mesh),
                shader,
            });
        }
        Ok(())
    }

    /// A mesh's transform at `at`: translate, rotate (degrees about X, then
    /// Y, then Z) and a positive scale.
    fn transform(&self, at: &str, t: &TransformFile) -> Result<DMat4, SceneError> {
        let translate = self.finite(&format!("{at}.translate"), t.translate)?;
        let r = self.finite(&format!("{at}.rotate"), t.rotate)?;
        let scale = match t.scale {
            None => DVec3::ONE,
            Some(Scale::Uniform(s)) => DVec3::splat(s),
            Some(Scale::PerAxis(s)) => DVec3::from_array(s),
        };
        if !scale.is_finite() || scale.min_element() <= 0.0 {
            return Err(self.err(
                format!("{at}.scale"),
                format!("must be finite and positive, got {scale}"),
            ));
        }
        let rot = DMat3::from_rotation_z(r.z.to_radians())
            * DMat3::from_rotation_y(r.y.to_radians())
            * DMat3::from_rotation_x(r.x.to_radians());
        Ok(DMat4::from_translation(translate) * DMat4::from_mat3(rot) * DMat4::from_scale(scale))
    }
}

/// Reads and parses a JSON scene file within the guard's limits: strict
/// deserialisation, an error naming the JSON path of the field.
fn parse(path: &Path, guard: &super::guard::Guard) -> Result<SceneFile, SceneError> {
    let bytes = guard
        .read(path, "scene")
        .map_err(|e| SceneError::new(path, "", e.0))?;
    let text = String::from_utf8(bytes)
        .map_err(|e| SceneError::new(path, "", format!("cannot read scene: {e}")))?;
    let de = &mut serde_json::Deserializer::from_str(&text);
    serde_path_to_error::deserialize(de).map_err(|e| {
        let field = e.path().to_string();
        let misplaced = is_texture_object(&text, e.path());
        let inner = e.into_inner();
        let field = if field == "." { String::new() } else { field };
        if misplaced {
            return SceneError::new(path, field, TEXTURE_PLACES);
        }
        // serde_json appends " at line L column C"; keep it, it helps.
        SceneError::new(path, field, inner.to_string())
    })
}

/// Whether the value at `at` in the JSON `text` is a texture object (has a
/// `texture` key): a texture where the format takes none.
fn is_texture_object(text: &str, at: &serde_path_to_error::Path) -> bool {
    use serde_path_to_error::Segment;
    let Ok(root) = serde_json::from_str::<serde_json::Value>(text) else {
        return false;
    };
    let mut v = &root;
    for seg in at.iter() {
        let next = match seg {
            Segment::Seq { index } => v.get(index),
            Segment::Map { key } => v.get(key),
            Segment::Enum { .. } | Segment::Unknown => None,
        };
        match next {
            Some(n) => v = n,
            None => return false,
        }
    }
    v.as_object().is_some_and(|m| m.contains_key("texture"))
}

/// Reads the image file `path` through `guard` and decodes it
/// ([`super::texture::decode`]; `srgb`: a colour texture) into a texture
/// labelled and tagged with its path, so that `penumbra watch` can read it
/// again when it changes. The message names the file.
pub fn read_texture(
    path: &Path,
    srgb: bool,
    guard: &super::guard::Guard,
) -> Result<Texture, super::guard::Refused> {
    let bytes = guard.read(path, "texture")?;
    let label = path.display().to_string();
    let mut t = super::texture::decode(&bytes, None, &label, srgb, guard)
        .map_err(|e| super::guard::Refused(format!("the texture {label} {}", e.0)))?;
    t.file = Some(path.to_path_buf());
    Ok(t)
}

/// Reads a JSON scene file: parses it, then reads the camera, the
/// background, the shaders, the objects and the lights in this order (the
/// first error is reported).
pub fn load(path: &Path, opts: &LoadOptions) -> Result<Loaded, SceneError> {
    let guard = super::guard::Guard::new(path, opts);
    let file = parse(path, &guard)?;
    let r = Reader {
        file: path,
        gltf_materials: opts.gltf_materials,
    };
    let camera = r.camera(&file.camera, opts)?;
    let background = r.colour("background", file.background)?;
    let base = path.parent().unwrap_or(Path::new("."));
    let Shaders {
        shaders,
        ids,
        wgsl_files,
        textures,
    } = r.shaders(&file.shaders, base, &guard)?;
    let mut files = vec![path.to_path_buf()];
    files.extend(wgsl_files);
    // A file named with both encodings is two textures but one file.
    for f in textures.list.iter().filter_map(|t| t.file.clone()) {
        if !files.contains(&f) {
            files.push(f);
        }
    }
    let mut loaded = Loaded {
        scene: Scene {
            textures: textures.list,
            camera,
            background,
            shaders,
            objects: Vec::new(),
            lights: Vec::new(),
        },
        notes: Vec::new(),
        files,
        lit_by_default: false,
    };
    for (i, o) in file.objects.iter().enumerate() {
        r.object(i, o, &ids, base, &guard, &mut loaded)?;
    }
    loaded.scene.lights = file
        .lights
        .iter()
        .enumerate()
        .map(|(i, l)| r.light(i, l))
        .collect::<Result<Vec<_>, _>>()?;
    super::lighting::apply(&mut loaded, &opts.lighting);
    Ok(loaded)
}
