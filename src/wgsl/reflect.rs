//! Reflection of shader files written as WGSL: what a file declares, read
//! once per text ([`super::reflect()`], which caches).
//!
//! A shader file defines
//!
//! ```wgsl
//! fn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32>                // required
//! fn ambient(s: Surface, light_ambient: vec3<f32>, p: Params) -> vec3<f32>    // optional
//! struct Params { ... }                                                       // optional
//! ```
//!
//! against the engine's types of `shaders/shading/interface.wgsl`. [`reflect`]
//! parses the file after that interface (parse only: the renderer validates
//! the pipeline it builds), checks the signatures, and lists the members of
//! `Params`, whose values the scene supplies
//! ([`WgslShader::values`](crate::scene::shading::WgslShader::values)).

use std::fmt;
use std::ops::Range;
use std::path::{Path, PathBuf};

use super::limits::{MAX_PARAMS_BYTES, MAX_PARAMS_FIELDS};
use super::scan::floor_char_boundary;
use crate::scene::shading::{ParamField, ParamType};

/// The engine's types a shader file is written against.
pub const INTERFACE: &str = include_str!("../../shaders/shading/interface.wgsl");

/// The texture sampling the interface's `texture_sample` and `texture_at`
/// call, parsed before it.
const TEXTURES: &str = include_str!("../../shaders/textures.wgsl");

/// The types and functions the engine declares; a shader file must not
/// declare them.
pub const ENGINE_TYPES: [&str; 4] = ["Surface", "LightSample", "texture_sample", "texture_at"];

/// Names that start with this are the engine's; a shader file must not use them.
pub const RESERVED_PREFIX: &str = "penumbra_";

/// What the parse-only check appends when a file declares no `Params`: the
/// engine supplies the same placeholder.
const PLACEHOLDER_PARAMS: &str = "struct Params { penumbra_unused: u32 }\n";

/// What [`reflect`] reads from a shader file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Reflection {
    /// The file declares `struct Params` (possibly without members).
    pub has_params: bool,
    /// The members of `Params` in declaration order; empty without `Params`.
    pub fields: Vec<ParamField>,
    /// The file defines `fn ambient`.
    pub has_ambient: bool,
    /// The file defines `fn prepare`.
    pub has_prepare: bool,
    /// The bytes one invocation holds (variables, array and struct values;
    /// [`super::footprint`]).
    pub invocation_bytes: u64,
}

/// A place in a shader file, for an error message.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Location {
    /// 1-based line number.
    pub line: usize,
    /// 1-based column, in characters.
    pub column: usize,
    /// The text of that line (without its line break).
    pub line_text: String,
    /// How many characters the caret line marks (at least 1).
    pub width: usize,
}

/// A problem with a shader file: which file, where in it (when known) and what.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ShaderFileError {
    /// The shader file.
    pub path: PathBuf,
    /// Where in it, when the problem has a place.
    pub at: Option<Location>,
    /// What is wrong, in plain words.
    pub message: String,
}

impl fmt::Display for ShaderFileError {
    /// `FILE:LINE:COL: MESSAGE`, then the source line and a caret under the
    /// span on two more lines; `FILE: MESSAGE` without a place.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let Some(at) = &self.at else {
            return write!(f, "{}: {}", self.path.display(), self.message);
        };
        write!(
            f,
            "{}:{}:{}: {}",
            self.path.display(),
            at.line,
            at.column,
            self.message
        )?;
        let number = at.line.to_string();
        let gutter = " ".repeat(number.len());
        // Keep tabs so that the caret lines up under the same characters.
        let indent: String = at
            .line_text
            .chars()
            .take(at.column - 1)
            .map(|c| if c == '\t' { '\t' } else { ' ' })
            .collect();
        write!(
            f,
            "\n {number} | {}\n {gutter} | {indent}{}",
            at.line_text,
            "^".repeat(at.width.max(1))
        )
    }
}

impl std::error::Error for ShaderFileError {}

/// The place of byte range `start..end` of `source`.
fn locate(source: &str, start: usize, end: usize) -> Location {
    let start = floor_char_boundary(source, start.min(source.len()));
    let end = floor_char_boundary(source, end.clamp(start, source.len()));
    let line_start = source[..start].rfind('\n').map_or(0, |i| i + 1);
    let line_end = source[start..]
        .find('\n')
        .map_or(source.len(), |i| start + i);
    let line_text = source[line_start..line_end].trim_end_matches('\r');
    let column = source[line_start..start].chars().count() + 1;
    let width = source[start..end.min(line_end)].chars().count();
    Location {
        line: source[..start].matches('\n').count() + 1,
        column,
        line_text: line_text.to_string(),
        width: width.max(1),
    }
}

/// One identifier of WGSL source outside comments: its text and byte range.
struct Ident<'a> {
    text: &'a str,
    start: usize,
}

/// The identifiers (and keywords) of `source`, skipping comments and numbers.
fn identifiers(source: &str) -> Vec<Ident<'_>> {
    super::lexer::tokens(source)
        .filter(|t| t.kind == super::lexer::Kind::Ident)
        .map(|t| Ident {
            text: t.text(source),
            start: t.range.start,
        })
        .collect()
}

/// In the function declared at `range` of `source`: the byte ranges of its
/// parenthesised arguments and of its result type (after `->`; the closing
/// parenthesis when it has none), where they can be found.
fn signature_parts(
    source: &str,
    range: Range<usize>,
) -> (Option<Range<usize>>, Option<Range<usize>>) {
    let text = &source[range.clone()];
    let Some(open) = text.find('(') else {
        return (None, None);
    };
    let mut depth = 0usize;
    let mut close = None;
    for (k, c) in text[open..].char_indices() {
        match c {
            '(' => depth += 1,
            ')' => {
                depth -= 1;
                if depth == 0 {
                    close = Some(open + k);
                    break;
                }
            }
            _ => {}
        }
    }
    let Some(close) = close else {
        return (None, None);
    };
    let args = Some(range.start + open..range.start + close + 1);
    let after = &text[close + 1..];
    let body = after.find('{').unwrap_or(after.len());
    let head = &after[..body];
    let result = match head.find("->") {
        Some(arrow) => {
            let ty = &head[arrow + 2..];
            let lead = ty.len() - ty.trim_start().len();
            let start = range.start + close + 1 + arrow + 2 + lead;
            Some(start..start + ty.trim().len())
        }
        None => Some(range.start + close..range.start + close + 1),
    };
    (args, result)
}

/// The byte range of member `name` (from its name to the end of its type)
/// in the struct declared at `range` of `source`.
fn member_range(source: &str, range: Range<usize>, name: &str) -> Option<Range<usize>> {
    let text = &source[range.clone()];
    let body = text.find('{')?;
    for id in identifiers(&text[body..]) {
        if id.text != name {
            continue;
        }
        let start = body + id.start;
        let rest = &text[start + name.len()..];
        if !rest.trim_start().starts_with(':') {
            continue;
        }
        // The type ends at the `,` or `}` that closes the member, outside `<>`.
        let mut depth = 0i32;
        let mut end = text.len();
        for (k, c) in text[start..].char_indices() {
            match c {
                '<' => depth += 1,
                '>' => depth -= 1,
                ',' | '}' if depth <= 0 => {
                    end = start + k;
                    break;
                }
                _ => {}
            }
        }
        let member = text[start..end].trim_end();
        return Some(range.start + start..range.start + start + member.len());
    }
    None
}

/// The WGSL spelling of type `h` of `module`, for messages.
fn type_name(module: &naga::Module, h: naga::Handle<naga::Type>) -> String {
    let ty = &module.types[h];
    if let Some(name) = &ty.name {
        return name.clone();
    }
    let scalar = |s: naga::Scalar| match (s.kind, s.width) {
        (naga::ScalarKind::Float, 4) => "f32".to_string(),
        (naga::ScalarKind::Float, 2) => "f16".to_string(),
        (naga::ScalarKind::Sint, 4) => "i32".to_string(),
        (naga::ScalarKind::Uint, 4) => "u32".to_string(),
        (naga::ScalarKind::Bool, _) => "bool".to_string(),
        (kind, width) => format!("{kind:?}{}", width * 8).to_lowercase(),
    };
    match &ty.inner {
        naga::TypeInner::Scalar(s) => scalar(*s),
        naga::TypeInner::Vector { size, scalar: s } => {
            format!("vec{}<{}>", *size as u8, scalar(*s))
        }
        naga::TypeInner::Matrix {
            columns,
            rows,
            scalar: s,
        } => format!("mat{}x{}<{}>", *columns as u8, *rows as u8, scalar(*s)),
        naga::TypeInner::Array {
            base,
            size: naga::ArraySize::Constant(n),
            ..
        } => format!("array<{}, {n}>", type_name(module, *base)),
        naga::TypeInner::Array { base, .. } => format!("array<{}>", type_name(module, *base)),
        naga::TypeInner::Atomic(s) => format!("atomic<{}>", scalar(*s)),
        naga::TypeInner::Pointer { base, .. } => format!("ptr<{}>", type_name(module, *base)),
        other => format!("{other:?}")
            .split([' ', '{', '('])
            .next()
            .unwrap_or("a type")
            .to_lowercase(),
    }
}

/// The [`ParamType`] of type `h`, if it is one a `Params` member may have.
fn param_type(module: &naga::Module, h: naga::Handle<naga::Type>) -> Option<ParamType> {
    use naga::{Scalar, TypeInner, VectorSize};
    match module.types[h].inner {
        TypeInner::Scalar(Scalar::F32) => Some(ParamType::F32),
        TypeInner::Scalar(Scalar::I32) => Some(ParamType::I32),
        TypeInner::Scalar(Scalar::U32) => Some(ParamType::U32),
        TypeInner::Vector {
            size,
            scalar: Scalar::F32,
        } => Some(match size {
            VectorSize::Bi => ParamType::Vec2,
            VectorSize::Tri => ParamType::Vec3,
            VectorSize::Quad => ParamType::Vec4,
        }),
        _ => None,
    }
}

/// Whether type `h` is `vec3<f32>`.
fn is_vec3f(module: &naga::Module, h: naga::Handle<naga::Type>) -> bool {
    param_type(module, h) == Some(ParamType::Vec3)
}

/// Parses shader file `path` (text `source`) after the engine's interface,
/// checks its `shade`, `ambient` and `Params` and the names it must not
/// declare, and returns the members of `Params` and whether it has `ambient`.
/// Errors name `path` and, where the problem has a place, the line and
/// column in the user's own file.
pub fn reflect(path: &Path, source: &str) -> Result<Reflection, ShaderFileError> {
    let err = |at: Option<Location>, message: String| ShaderFileError {
        path: path.to_path_buf(),
        at,
        message,
    };
    let at = |start: usize, end: usize| Some(locate(source, start, end));

    // The limits and the declarations a file must not make, before any
    // parse (super::scan).
    super::scan::check(source).map_err(|r| err(at(r.range.start, r.range.end), r.message))?;

    // Names first, from the text: the parse would report a redefinition of
    // the engine's types in terms of the interface.
    let idents = identifiers(source);
    // Where the file declares the name `Params` (a struct, or anything else).
    let mut params_at: Option<Range<usize>> = None;
    for (k, id) in idents.iter().enumerate() {
        if id.text.starts_with(RESERVED_PREFIX) {
            return Err(err(
                at(id.start, id.start + id.text.len()),
                format!(
                    "`{}`: names starting with `{RESERVED_PREFIX}` are reserved for the engine",
                    id.text
                ),
            ));
        }
        let declares = k > 0
            && matches!(
                idents[k - 1].text,
                "struct" | "alias" | "fn" | "const" | "var" | "override" | "let"
            );
        if declares && ENGINE_TYPES.contains(&id.text) {
            return Err(err(
                at(id.start, id.start + id.text.len()),
                format!(
                    "`{}` is the engine's (shaders/shading/interface.wgsl); a shader file uses it and must not declare it",
                    id.text
                ),
            ));
        }
        if declares && id.text == "Params" && params_at.is_none() {
            params_at = Some(id.start..id.start + id.text.len());
        }
    }

    let mut text = String::with_capacity(TEXTURES.len() + INTERFACE.len() + source.len() + 64);
    text.push_str(TEXTURES);
    text.push('\n');
    text.push_str(INTERFACE);
    if !text.ends_with('\n') {
        text.push('\n');
    }
    let offset = text.len();
    text.push_str(source);
    let has_params = params_at.is_some();
    if params_at.is_none() {
        text.push('\n');
        text.push_str(PLACEHOLDER_PARAMS);
    }

    let parsed = super::stack::on_parse_stack(|| naga::front::wgsl::parse_str(&text))
        .map_err(|m| err(None, format!("internal error in naga's WGSL parser ({m})")))?;
    let module = parsed.map_err(|e| {
        let span = e.labels().next().and_then(|(s, _)| s.to_range());
        let place = span
            .filter(|r| r.start >= offset && r.start <= offset + source.len())
            .map(|r| locate(source, r.start - offset, r.end.saturating_sub(offset)));
        err(place, e.message().to_string())
    })?;

    // A span of the module as a byte range of the user's source.
    let user_range = |span: naga::Span| {
        span.to_range()
            .filter(|r| r.start >= offset && r.end <= offset + source.len())
            .map(|r| r.start - offset..r.end - offset)
    };

    // What one invocation holds, before any further work on the module.
    let invocation_bytes =
        super::footprint::check(&module, source, user_range, |h| type_name(&module, h))
            .map_err(|(r, message)| err(r.map(|r| locate(source, r.start, r.end)), message))?;

    let mut fields = Vec::new();
    if let Some(declared) = params_at {
        let params = module
            .types
            .iter()
            .find(|(_, t)| t.name.as_deref() == Some("Params"));
        let not_a_struct = || {
            err(
                Some(locate(source, declared.start, declared.end)),
                "`Params` must be declared as `struct Params { ... }`".to_string(),
            )
        };
        match params {
            Some((h, t)) => {
                let whole = user_range(module.types.get_span(h));
                let naga::TypeInner::Struct { members, .. } = &t.inner else {
                    return Err(not_a_struct());
                };
                for (k, m) in members.iter().enumerate() {
                    let name = m.name.clone().unwrap_or_else(|| format!("#{k}"));
                    let Some(ty) = param_type(&module, m.ty) else {
                        let place = whole.clone().map(|r| {
                            let m = member_range(source, r.clone(), &name).unwrap_or(r);
                            locate(source, m.start, m.end)
                        });
                        return Err(err(
                            place,
                            format!(
                                "Params field `{name}` has type {}; a Params field must be f32, i32, u32, vec2<f32>, vec3<f32> or vec4<f32>",
                                type_name(&module, m.ty)
                            ),
                        ));
                    };
                    fields.push(ParamField { name, ty });
                    let bytes: usize = fields.iter().map(|f| 4 * f.ty.words()).sum();
                    let limit = if fields.len() > MAX_PARAMS_FIELDS {
                        Some(format!(
                            "Params has more than {MAX_PARAMS_FIELDS} fields, the limit"
                        ))
                    } else if bytes > MAX_PARAMS_BYTES {
                        Some(format!("Params takes {bytes} bytes up to field `{}`; its fields may take at most {MAX_PARAMS_BYTES} bytes (4 a word)", fields[fields.len() - 1].name))
                    } else {
                        None
                    };
                    if let Some(message) = limit {
                        let place = whole.clone().map(|r| {
                            let m = member_range(source, r.clone(), &fields[fields.len() - 1].name)
                                .unwrap_or(r);
                            locate(source, m.start, m.end)
                        });
                        return Err(err(place, message));
                    }
                }
            }
            // `Params` declared as an alias of another type, a constant...
            None => return Err(not_a_struct()),
        }
    }
    let mut shade = None;
    let mut ambient = None;
    let mut prepare = None;
    for (h, f) in module.functions.iter() {
        match f.name.as_deref() {
            Some("shade") => shade = Some(h),
            Some("ambient") => ambient = Some(h),
            Some("prepare") => prepare = Some(h),
            _ => {}
        }
    }
    let Some(shade) = shade else {
        return Err(err(
            None,
            "no `fn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32>`: every shader file must define it".to_string(),
        ));
    };
    let check = |h: naga::Handle<naga::Function>, name: &str, second: &str| {
        let f = &module.functions[h];
        let wanted = format!("fn {name}(Surface, {second}, Params) -> vec3<f32>");
        let (args_at, result_at) = user_range(module.functions.get_span(h))
            .map(|r| signature_parts(source, r))
            .unwrap_or_default();
        let (args_at, result_at) = (
            args_at.map(|r| locate(source, r.start, r.end)),
            result_at.map(|r| locate(source, r.start, r.end)),
        );
        let got_args: Vec<String> = f
            .arguments
            .iter()
            .map(|a| type_name(&module, a.ty))
            .collect();
        let got_result = f
            .result
            .as_ref()
            .map(|r| type_name(&module, r.ty))
            .unwrap_or_else(|| "nothing".to_string());
        let args_ok = got_args.len() == 3
            && got_args[0] == "Surface"
            && got_args[2] == "Params"
            && if second == "LightSample" {
                got_args[1] == "LightSample"
            } else {
                is_vec3f(&module, f.arguments[1].ty)
            };
        if !args_ok {
            return Err(err(
                args_at,
                format!(
                    "`{name}` takes ({}), it must be `{wanted}`",
                    got_args.join(", ")
                ),
            ));
        }
        let result_ok = f.result.as_ref().is_some_and(|r| is_vec3f(&module, r.ty));
        if !result_ok {
            return Err(err(
                result_at,
                format!("`{name}` returns {got_result}, it must be `{wanted}`"),
            ));
        }
        Ok(())
    };
    check(shade, "shade", "LightSample")?;
    if let Some(h) = ambient {
        check(h, "ambient", "vec3<f32>")?;
    }
    if let Some(h) = prepare {
        let f = &module.functions[h];
        let wanted = "fn prepare(Surface, Params) -> Params";
        let args: Vec<String> = f
            .arguments
            .iter()
            .map(|a| type_name(&module, a.ty))
            .collect();
        let result = f.result.as_ref().map(|r| type_name(&module, r.ty));
        let (args_at, result_at) = user_range(module.functions.get_span(h))
            .map(|r| signature_parts(source, r))
            .unwrap_or_default();
        if args != ["Surface", "Params"] {
            return Err(err(
                args_at.map(|r| locate(source, r.start, r.end)),
                format!(
                    "`prepare` takes ({}), it must be `{wanted}`",
                    args.join(", ")
                ),
            ));
        }
        if result.as_deref() != Some("Params") {
            return Err(err(
                result_at.map(|r| locate(source, r.start, r.end)),
                format!(
                    "`prepare` returns {}, it must be `{wanted}`",
                    result.unwrap_or_else(|| "nothing".into())
                ),
            ));
        }
    }

    validate(&module, &text, &user_range)
        .map_err(|(r, message)| err(r.map(|r| locate(source, r.start, r.end)), message))?;

    Ok(Reflection {
        has_params,
        fields,
        has_ambient: ambient.is_some(),
        has_prepare: prepare.is_some(),
        invocation_bytes,
    })
}

/// Validates the module of a shader file (the interface followed by the
/// file) as the renderer will, so that its errors name the user's file and
/// place: types that cannot be laid out, overrides without a value, and
/// operations that the shade stage (a compute shader) cannot run. `user`
/// maps a span of the module to a byte range of the user's file.
fn validate(
    module: &naga::Module,
    text: &str,
    user: &dyn Fn(naga::Span) -> Option<Range<usize>>,
) -> Result<(), (Option<Range<usize>>, String)> {
    // Overrides: the engine gives values only to its own.
    for (h, o) in module.overrides.iter() {
        let Some(at) = user(module.overrides.get_span(h)) else {
            continue;
        };
        if o.init.is_none() {
            return Err((
                Some(at),
                format!(
                    "override `{}` has no value: the engine sets only its own overrides; give it a default (`= ...`) or make it a `const`",
                    o.name.as_deref().unwrap_or("?")
                ),
            ));
        }
    }
    let validated = super::stack::on_parse_stack(|| {
        crate::render::compile::validator()
            .validate(module)
            .map_err(Box::new)
    })
    .map_err(|m| (None, format!("internal error in naga's validator ({m})")))?;
    let info = validated.map_err(|e| {
        let at = e.spans().find_map(|(span, _)| user(*span));
        let at = at.or_else(|| {
            // Without a span of the file, the place of what it names.
            e.location(text)
                .and_then(|l| user(naga::Span::new(l.offset, l.offset + l.length)))
        });
        (at, error_chain(e.as_inner()))
    })?;
    // The shade stage is a compute shader: every function of the file must
    // be callable there. Callees come first in naga's arena, so the first
    // such function is where the operation is.
    for (h, f) in module.functions.iter() {
        let Some(at) = user(module.functions.get_span(h)) else {
            continue;
        };
        if !info[h]
            .available_stages
            .contains(naga::valid::ShaderStages::COMPUTE)
        {
            return Err((
                Some(at),
                format!(
                    "`{}` uses an operation that the shade stage, a compute shader, cannot run (derivatives such as dpdx or fwidth, textureSample without an explicit level, discard)",
                    f.name.as_deref().unwrap_or("?")
                ),
            ));
        }
    }
    Ok(())
}

/// An error and its causes, outermost first ("entry point render is
/// invalid: …: the real reason"), so that the author sees the reason and not
/// only naga's outermost context. Also the shade program's compile errors
/// (`render::compile`).
pub(crate) fn error_chain(e: &dyn std::error::Error) -> String {
    let mut text = e.to_string();
    let mut cause = e.source();
    while let Some(c) = cause {
        text.push_str(": ");
        text.push_str(&c.to_string());
        cause = c.source();
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::shading::{ParamValue, WgslShader};

    const TOON: &str = "\
struct Params {
    base: vec3<f32>,
    bands: u32,
    gain: f32,
    offset: i32,
    uv_scale: vec2<f32>,
    tint: vec4<f32>,
}

fn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32> {
    let d = max(dot(s.normal, l.to_light), 0.0);
    let q = floor(d * f32(p.bands)) / f32(p.bands);
    return p.base * q * l.intensity * l.diffuse * p.gain;
}

fn ambient(s: Surface, light_ambient: vec3<f32>, p: Params) -> vec3<f32> {
    return p.base * light_ambient;
}
";

    fn reflect_str(source: &str) -> Result<Reflection, ShaderFileError> {
        reflect(Path::new("toon.wgsl"), source)
    }

    #[test]
    fn reflects_every_param_type_in_order() {
        let r = reflect_str(TOON).unwrap();
        let got: Vec<(&str, ParamType)> = r.fields.iter().map(|f| (&*f.name, f.ty)).collect();
        assert_eq!(
            got,
            vec![
                ("base", ParamType::Vec3),
                ("bands", ParamType::U32),
                ("gain", ParamType::F32),
                ("offset", ParamType::I32),
                ("uv_scale", ParamType::Vec2),
                ("tint", ParamType::Vec4),
            ]
        );
        assert!(r.has_ambient);
        let wgsl: Vec<&str> = r.fields.iter().map(|f| f.ty.wgsl()).collect();
        assert_eq!(
            wgsl,
            ["vec3<f32>", "u32", "f32", "i32", "vec2<f32>", "vec4<f32>"]
        );
        let words: usize = r.fields.iter().map(|f| f.ty.words()).sum();
        assert_eq!(words, 3 + 1 + 1 + 1 + 2 + 4);
    }

    #[test]
    fn without_params_or_ambient() {
        let src = "fn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32> {\n    return s.normal * l.intensity;\n}\n";
        let r = reflect_str(src).unwrap();
        assert!(r.fields.is_empty() && !r.has_params);
        assert!(!r.has_ambient);
        // naga parses an empty Params, but WGSL requires a member: refused
        // by the validation at the declaration.
        let e = reflect_str(&format!("struct Params {{}}\n{src}")).unwrap_err();
        assert!(e.message.contains("must have at least one member"), "{e}");
        assert_eq!(e.at.map(|a| (a.line, a.column)), Some((1, 1)));
    }

    #[test]
    fn packs_words_in_field_order() {
        let r = reflect_str(TOON).unwrap();
        let s = WgslShader {
            path: "toon.wgsl".into(),
            source: TOON.into(),
            fields: r.fields,
            values: vec![
                ParamValue::Vec(vec![0.9, 0.3, 0.2]),
                ParamValue::U32(4),
                ParamValue::F32(1.5),
                ParamValue::I32(-2),
                ParamValue::Vec(vec![2.0, 3.0]),
                ParamValue::Vec(vec![1.0, 0.0, 0.5, 0.25]),
            ],
            has_ambient: r.has_ambient,
        };
        assert!(s.values.iter().zip(&s.fields).all(|(v, f)| v.fits(f.ty)));
        let f = |x: f32| x.to_bits();
        assert_eq!(
            s.words(|_| u32::MAX),
            vec![
                f(0.9),
                f(0.3),
                f(0.2),
                4,
                f(1.5),
                (-2i32) as u32,
                f(2.0),
                f(3.0),
                f(1.0),
                f(0.0),
                f(0.5),
                f(0.25),
            ]
        );
    }

    #[test]
    fn missing_shade() {
        let e = reflect_str("fn other() -> f32 { return 1.0; }\n").unwrap_err();
        assert!(e.message.contains("no `fn shade"), "{e}");
        assert_eq!(e.path, Path::new("toon.wgsl"));
    }

    #[test]
    fn mistyped_shade() {
        let src =
            "\n\nfn shade(s: Surface, l: LightSample, p: Params) -> f32 {\n    return 1.0;\n}\n";
        let e = reflect_str(src).unwrap_err();
        assert!(e.message.contains("`shade` returns f32"), "{e}");
        let at = e.at.as_ref().expect("a place");
        assert_eq!((at.line, at.column, at.width), (3, 52, 3), "{e}");
        let src = "fn shade(s: Surface, p: Params) -> vec3<f32> {\n    return s.normal;\n}\n";
        let e = reflect_str(src).unwrap_err();
        assert!(e.message.contains("`shade` takes (Surface, Params)"), "{e}");
        let at = e.at.as_ref().expect("a place");
        assert_eq!((at.line, at.column, at.width), (1, 9, 23), "{e}");
        let src = "fn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32> { return s.normal; }\nfn ambient(s: Surface, a: f32, p: Params) -> vec3<f32> { return s.normal; }\n";
        let e = reflect_str(src).unwrap_err();
        assert!(
            e.message.contains("`ambient` takes (Surface, f32, Params)"),
            "{e}"
        );
        assert_eq!(e.at.as_ref().map(|a| a.line), Some(2), "{e}");
    }

    #[test]
    fn syntax_error_points_into_the_users_file() {
        let src = "// toon\nfn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32> {\n    let x = ;\n    return s.normal;\n}\n";
        let e = reflect_str(src).unwrap_err();
        let at = e.at.clone().expect("a place");
        assert_eq!((at.line, at.column), (3, 13), "{e}");
        assert_eq!(at.line_text, "    let x = ;");
        let shown = e.to_string();
        let lines: Vec<&str> = shown.lines().collect();
        assert_eq!(lines.len(), 3, "{shown}");
        assert!(lines[0].starts_with("toon.wgsl:3:13: "), "{shown}");
        assert_eq!(lines[1], " 3 |     let x = ;");
        assert_eq!(lines[2], "   |             ^");
    }

    #[test]
    fn params_member_of_another_type() {
        let src = "struct Params { n: vec3<i32> }\nfn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32> { return s.normal; }\n";
        let e = reflect_str(src).unwrap_err();
        assert!(
            e.message
                .contains("Params field `n` has type vec3<i32>; a Params field must be"),
            "{e}"
        );
        let at = e.at.as_ref().expect("a place");
        assert_eq!((at.line, at.column, at.width), (1, 17, 12), "{e}");
        let src = "struct Params { m: mat3x3<f32> }\nfn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32> { return s.normal; }\n";
        let e = reflect_str(src).unwrap_err();
        assert!(e.message.contains("`m` has type mat3x3<f32>"), "{e}");
    }

    #[test]
    fn params_that_is_not_a_struct() {
        let shade =
            "fn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32> { return s.normal; }\n";
        for decl in [
            "alias Params = f32;",
            "struct Other { x: f32 }\nalias Params = Other;",
        ] {
            let e = reflect_str(&format!("{decl}\n{shade}")).unwrap_err();
            assert!(
                e.message
                    .contains("`Params` must be declared as `struct Params"),
                "{decl}: {e}"
            );
            assert!(e.at.is_some(), "{decl}: {e}");
        }
        // A constant named Params: the parse fails where it is used as a type.
        let e = reflect_str(&format!("const Params = 1.0;\n{shade}")).unwrap_err();
        assert_eq!(e.at.map(|a| a.line), Some(2));
    }

    #[test]
    fn reserved_names() {
        let src = "struct Surface { x: f32 }\nfn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32> { return vec3(0.0); }\n";
        let e = reflect_str(src).unwrap_err();
        assert!(e.message.contains("`Surface` is the engine's ("), "{e}");
        assert_eq!(e.at.as_ref().map(|a| (a.line, a.column)), Some((1, 8)));
        let src = "alias LightSample = f32;\nfn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32> { return vec3(0.0); }\n";
        let e = reflect_str(src).unwrap_err();
        assert!(e.message.contains("`LightSample`"), "{e}");
        let src = "const penumbra_gain = 2.0;\nfn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32> { return vec3(penumbra_gain); }\n";
        let e = reflect_str(src).unwrap_err();
        assert!(e.message.contains("reserved for the engine"), "{e}");
        assert_eq!(e.at.as_ref().map(|a| (a.line, a.column)), Some((1, 7)));
        // In a comment the names are harmless.
        let src = "// struct Surface, penumbra_x\n/* fn penumbra_y /* nested */ */\nfn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32> { return s.normal; }\n";
        reflect_str(src).unwrap();
    }

    /// A valid file with `body` as the statements of `shade` before its return.
    fn with_body(body: &str) -> String {
        format!("fn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32> {{\n{body}\n    return s.normal;\n}}\n")
    }

    /// The failing inputs of issue 36 (a multibyte character where the
    /// comment scan sliced the text by bytes) and their relatives: each is
    /// accepted, or refused with an error at a place counted in characters.
    #[test]
    fn multibyte_characters_do_not_panic() {
        let shade = with_body("");
        for ok in [
            format!("/* é */\n{shade}"),
            format!("/* 🦀 /* nested ü */ ß */\n{shade}"),
            format!("// ä ö ü\n{shade}"),
            format!("{shade}// ends in ä"),
            format!("{shade}/* ends in é */"),
            format!("@diagnostic(off, derivative_uniformity) /* ä */\n{shade}"),
        ] {
            reflect_str(&ok).unwrap_or_else(|e| panic!("{ok:?}: {e}"));
        }
        for (bad, line) in [
            (format!("{shade}/* unterminated é"), 5),
            (format!("{shade}é"), 5),
            (format!("é{shade}"), 1),
            (with_body("    let é = \"ü\";"), 2),
            (with_body("    let x = 1.0; /* ä */ let y = ;"), 2),
            (format!("{shade}\u{0}"), 5),
        ] {
            let e = reflect_str(&bad).unwrap_err();
            let at = e.at.as_ref().unwrap_or_else(|| panic!("{bad:?}: {e}"));
            assert_eq!(at.line, line, "{bad:?}: {e}");
            let _ = e.to_string();
        }
        // The column counts characters: the `;` after two multibyte ones.
        let e = reflect_str(&with_body("/*éé*/let x = ;")).unwrap_err();
        let at = e.at.expect("a place");
        assert_eq!((at.line, at.column), (2, 15), "{}", at.line_text);
    }

    /// Each limit refused before naga parses, naming line, column and value.
    #[test]
    fn limits_are_refused_with_their_place_and_value() {
        use super::super::limits::*;
        let cases: Vec<(String, (usize, usize), String)> = vec![
            (
                format!("{}\n{}", with_body(""), "// x\n".repeat(MAX_SOURCE_BYTES / 5)),
                (13095, 4),
                format!("at most {MAX_SOURCE_BYTES} bytes"),
            ),
            (
                with_body(&format!("    let x = {}1.0{};", "(".repeat(2000), ")".repeat(2000))),
                (2, 44),
                format!("more than {MAX_NESTING} deep"),
            ),
            (
                with_body(&format!("    return {};", vec!["a"; 30_000].join("+"))),
                (2, 1035),
                format!("more than {MAX_STATEMENT_TOKENS} tokens"),
            ),
            (
                format!(
                    "{}{}",
                    (0..MAX_FUNCTIONS).map(|i| format!("fn f{i}() {{}}\n")).collect::<String>(),
                    with_body("")
                ),
                (65, 1),
                format!("more than {MAX_FUNCTIONS} functions"),
            ),
            (
                with_body("    var a: array<f32, 100000000>;"),
                (2, 5),
                format!("400000000 bytes; a shader may hold at most {MAX_INVOCATION_BYTES} bytes"),
            ),
            (
                format!("var<private> a: array<f32, 1000000>;\n{}", with_body("")),
                (1, 1),
                "array<f32, 1000000> takes 4000000 bytes".into(),
            ),
            (
                with_body("    var a: array<f32, 3000>;\n    var b: array<f32, 3000>;"),
                (3, 5),
                format!("take 24000 bytes up to here; a shader may hold at most {MAX_INVOCATION_BYTES}"),
            ),
            (
                format!(
                    "const big = array<f32, 4096>();\n{}",
                    with_body("    let a = big[u32(s.uv.x)];\n    let b = array<f32, 4096>();\n    let c = b[u32(s.uv.y)];")
                ),
                // `big` (16 384 bytes) and the arguments of `shade`.
                (3, 13),
                "array values take 16532 bytes up to here".into(),
            ),
            (
                with_body("    let a = array<f32, 100000000>();"),
                (2, 13),
                "takes 400000000 bytes".into(),
            ),
            (
                format!(
                    "struct Params {{\n{}}}\n{}",
                    (0..=MAX_PARAMS_FIELDS).map(|i| format!("f{i}: f32,\n")).collect::<String>(),
                    with_body("")
                ),
                (66, 1),
                format!("more than {MAX_PARAMS_FIELDS} fields"),
            ),
            (
                format!(
                    "struct Params {{\n{}}}\n{}",
                    (0..40).map(|i| format!("f{i}: vec4<f32>,\n")).collect::<String>(),
                    with_body("")
                ),
                (34, 1),
                format!("528 bytes up to field `f32`; its fields may take at most {MAX_PARAMS_BYTES} bytes"),
            ),
        ];
        let mut wrong = Vec::new();
        for (source, (line, column), message) in cases {
            let e = reflect_str(&source).unwrap_err();
            let place = e.at.as_ref().map(|at| (at.line, at.column));
            if !e.message.contains(&message) || place != Some((line, column)) {
                wrong.push(format!(
                    "{message:?} at {line}:{column}, got {place:?}: {}",
                    e.message
                ));
            }
        }
        assert!(wrong.is_empty(), "{wrong:#?}");
    }

    /// Resources, workgroup memory, overrides without a value and
    /// operations a compute shader cannot run: refused at their place.
    #[test]
    fn what_a_file_must_not_declare_or_use() {
        for (source, line, message) in [
            (
                format!(
                    "@group(0) @binding(3) var<storage, read_write> counters: array<u32>;\n{}",
                    with_body("")
                ),
                1,
                "`@group`: a shader file must not declare resources",
            ),
            (
                format!("var<workgroup> w: array<f32, 64>;\n{}", with_body("")),
                1,
                "`var<workgroup>`",
            ),
            (
                format!("override gain: f32;\n{}", with_body("    let g = gain;")),
                1,
                "override `gain` has no value",
            ),
            (
                with_body("    let d = dpdx(s.position.x);"),
                1,
                "`shade` uses an operation that the shade stage, a compute shader, cannot run",
            ),
            (with_body("    let x: u32 = 1.5;"), 2, ""),
        ] {
            let e = reflect_str(&source).unwrap_err();
            assert!(
                e.message.contains(message),
                "{message:?} not in: {}",
                e.message
            );
            assert_eq!(e.at.as_ref().map(|a| a.line), Some(line), "{e}");
        }
        // An override with a default is the file's own business.
        reflect_str(&format!(
            "override gain: f32 = 2.0;\n{}",
            with_body("    let g = gain;")
        ))
        .unwrap();
    }

    /// The limits are far above what the project's own shader files need:
    /// each file's size, nesting, longest statement and functions, against
    /// the limits with at least the margin that scenes/README.md states.
    #[test]
    fn the_project_shaders_are_far_inside_the_limits() {
        use super::super::lexer::{tokens, Kind};
        use super::super::limits::*;
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        let mut files = Vec::new();
        for dir in ["shaders/shading", "scenes/shaders"] {
            for e in std::fs::read_dir(root.join(dir)).unwrap() {
                let p = e.unwrap().path();
                if p.extension().is_some_and(|x| x == "wgsl") && !p.ends_with("interface.wgsl") {
                    files.push(p);
                }
            }
        }
        let (mut bytes, mut depth, mut statement, mut functions) = (0, 0, 0, 0);
        let mut held = 0;
        for p in &files {
            let text = std::fs::read_to_string(p).unwrap();
            match reflect(p, &text) {
                Ok(r) => held = held.max(r.invocation_bytes),
                // checker.wgsl and shader.wgsl are engine files, not shade programs.
                Err(e) => assert!(!p.starts_with(root.join("scenes")), "{e}"),
            }
            bytes = bytes.max(text.len());
            let (mut d, mut n, mut f) = (0usize, 0usize, 0usize);
            for t in tokens(&text) {
                n += 1;
                statement = statement.max(n);
                match t.kind {
                    Kind::Punct('(' | '[' | '{') => {
                        d += 1;
                        depth = depth.max(d);
                    }
                    Kind::Punct(')' | ']' | '}') => d = d.saturating_sub(1),
                    Kind::Ident if t.text(&text) == "fn" => f += 1,
                    _ => {}
                }
                if matches!(t.kind, Kind::Punct(';' | '{' | '}' | ',')) {
                    n = 0;
                }
            }
            functions = functions.max(f);
        }
        eprintln!("largest {bytes} bytes, nesting {depth}, statement {statement} tokens, {functions} functions, {held} bytes an invocation");
        assert!(held * 10 <= MAX_INVOCATION_BYTES, "{held}");
        assert!(bytes * 10 <= MAX_SOURCE_BYTES, "{bytes}");
        assert!(depth * 5 <= MAX_NESTING, "{depth}");
        assert!(statement * 10 <= MAX_STATEMENT_TOKENS, "{statement}");
        assert!(functions * 10 <= MAX_FUNCTIONS, "{functions}");
    }

    /// naga's recursion on the worst file within the limits fits in an
    /// eighth of the parse thread's stack, and `reflect` works from a
    /// caller with a small stack (it parses on a thread of its own).
    #[test]
    fn the_worst_file_within_the_limits_fits_the_stack() {
        use super::super::limits::*;
        let open = MAX_NESTING - 3;
        // `s.normal.x -`: six tokens a term; `return vec3<f32>(` ... `);` eight more.
        let terms = (MAX_STATEMENT_TOKENS - 2 * open - 8) / 6;
        let sum = vec!["s.normal.x"; terms].join(" - ");
        let body = format!(
            "    return vec3<f32>({}{sum}{});",
            "(".repeat(open),
            ")".repeat(open)
        );
        let source = format!(
            "fn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32> {{\n{body}\n}}\n"
        );
        super::super::scan::check(&source).unwrap();
        let text = format!("{TEXTURES}\n{INTERFACE}\n{PLACEHOLDER_PARAMS}{source}");
        let parsed = std::thread::Builder::new()
            .stack_size(PARSE_STACK_BYTES / 8)
            .spawn(move || {
                naga::front::wgsl::parse_str(&text)
                    .map(|_| ())
                    .map_err(|e| e.message().to_string())
            })
            .unwrap()
            .join()
            .expect("no overflow");
        // Parsed and lowered: the whole recursion ran.
        parsed.unwrap();
        let small = std::thread::Builder::new()
            .stack_size(256 * 1024)
            .spawn(move || reflect(Path::new("deep.wgsl"), &source).map(|_| ()))
            .unwrap()
            .join()
            .expect("no overflow");
        small.unwrap();
    }

    #[test]
    fn locate_counts_characters() {
        let at = locate("ab\nxé y\n", 7, 8);
        assert_eq!((at.line, at.column, at.width), (2, 4, 1));
        assert_eq!(at.line_text, "xé y");
    }
}
