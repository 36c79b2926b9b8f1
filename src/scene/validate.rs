//! Scene invariants. Loaders check values as they read them (with their own
//! field paths); this is the last line of defence, also for scenes built in
//! code.

use std::fmt;

use glam::{DVec3, Vec3};

use super::{
    AlphaMode, Camera, Light, LightKind, Object, ParamValue, Projection, Scene, Shader, Shape,
    SurfaceMaps, Texture, TextureRef,
};
use crate::loaders::texture::MAX_TEXTURE_SIDE;

/// A violated invariant: the field path within the scene model
/// (e.g. `objects[3].radius`) and what is wrong.
#[derive(Clone, Debug, PartialEq)]
pub struct Invalid {
    /// Path of the field, e.g. `lights[0].direction`.
    pub field: String,
    /// What is wrong.
    pub message: String,
}

impl Invalid {
    /// An invalid `field`.
    pub fn new(field: impl Into<String>, message: impl Into<String>) -> Self {
        Invalid {
            field: field.into(),
            message: message.into(),
        }
    }
}

impl fmt::Display for Invalid {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.field, self.message)
    }
}

/// The largest image side we accept before asking the device; the device's
/// own limits are checked by the renderer.
pub const MAX_IMAGE_SIDE: u32 = 16384;

/// The largest coordinate magnitude a scene may use (positions, vectors,
/// radii). The kernel computes in `f32`, relative to the camera, and
/// squares distances: beyond about 1e19 those squares overflow `f32`
/// (3.4e38), and a coordinate beyond 3.4e38 cannot be stored at all.
pub const MAX_COORDINATE: f64 = 1e18;

/// A position or vector: finite, and within ±[`MAX_COORDINATE`].
fn bounded3(field: &str, v: DVec3) -> Result<(), Invalid> {
    if !v.is_finite() {
        Err(Invalid::new(field, format!("must be finite, got {v}")))
    } else if v.abs().max_element() > MAX_COORDINATE {
        Err(Invalid::new(
            field,
            format!(
                "must lie within ±{MAX_COORDINATE:e} (the kernel computes in f32), got [{}, {}, {}]",
                num(v.x),
                num(v.y),
                num(v.z)
            ),
        ))
    } else {
        Ok(())
    }
}

/// `x` for a message: huge numbers in exponent form, not 30 digits.
fn num(x: f64) -> String {
    if x.abs() >= 1e16 {
        format!("{x:e}")
    } else {
        format!("{x}")
    }
}

/// A radius: positive and at most [`MAX_COORDINATE`].
fn radius_ok(field: &str, r: f64) -> Result<(), Invalid> {
    if !(r > 0.0 && r <= MAX_COORDINATE) {
        return Err(Invalid::new(
            field,
            format!(
                "must be positive and at most {MAX_COORDINATE:e}, got {}",
                num(r)
            ),
        ));
    }
    Ok(())
}

fn unit(field: &str, v: DVec3) -> Result<(), Invalid> {
    bounded3(field, v)?;
    if (v.length() - 1.0).abs() > 1e-6 {
        return Err(Invalid::new(
            field,
            format!("must have unit length, got {v}"),
        ));
    }
    Ok(())
}

fn colour(field: &str, c: Vec3) -> Result<(), Invalid> {
    if !c.is_finite() || c.min_element() < 0.0 {
        return Err(Invalid::new(
            field,
            format!("must be finite and non-negative, got {c}"),
        ));
    }
    Ok(())
}

fn samples_ok(field: &str, n: u32) -> Result<(), Invalid> {
    let max = super::MAX_LIGHT_SAMPLES;
    if n == 0 || n > max {
        return Err(Invalid::new(
            field,
            format!("must be in 1..={max}, got {n}"),
        ));
    }
    Ok(())
}

/// The camera: a bounded position, a rotation, the projection's angle or
/// size, and the image size.
pub(super) fn camera(c: &Camera) -> Result<(), Invalid> {
    bounded3("camera.position", c.position)?;
    let o = c.orientation;
    let ortho = (o.transpose() * o - glam::DMat3::IDENTITY).to_cols_array();
    if !o.is_finite() || ortho.iter().any(|x| x.abs() > 1e-6) || o.determinant() < 0.0 {
        return Err(Invalid::new("camera.orientation", "must be a rotation"));
    }
    match c.projection {
        Projection::Perspective { vfov_deg } => {
            if !(vfov_deg > 0.0 && vfov_deg < 180.0) {
                return Err(Invalid::new(
                    "camera.fov",
                    format!("must be in (0, 180) degrees, got {vfov_deg}"),
                ));
            }
        }
        Projection::Orthographic { half_height } => {
            if !(half_height > 0.0 && half_height.is_finite()) {
                return Err(Invalid::new(
                    "camera.half_height",
                    format!("must be positive, got {half_height}"),
                ));
            }
        }
    }
    for (name, v) in [("camera.width", c.width), ("camera.height", c.height)] {
        if v == 0 || v > MAX_IMAGE_SIDE {
            return Err(Invalid::new(
                name,
                format!("must be in 1..={MAX_IMAGE_SIDE} pixels, got {v}"),
            ));
        }
    }
    Ok(())
}

/// The whole scene, concept by concept in this order (the first violation
/// is reported): camera, background, textures, shaders, checker cycles,
/// objects, lights.
pub(super) fn scene(s: &Scene) -> Result<(), Invalid> {
    camera(&s.camera)?;
    colour("background", s.background)?;
    for (i, t) in s.textures.iter().enumerate() {
        texture(i, t)?;
    }
    let n = s.shaders.len();
    let nt = s.textures.len();
    for (i, sh) in s.shaders.iter().enumerate() {
        shader(i, sh, n, nt)?;
    }
    checker_cycles(&s.shaders)?;
    for (i, o) in s.objects.iter().enumerate() {
        object(i, o, n, nt)?;
    }
    for (i, l) in s.lights.iter().enumerate() {
        light(i, l)?;
    }
    Ok(())
}

/// Texture `i`: a size the loaders and the device accept, and one texel
/// per pixel of it.
fn texture(i: usize, t: &Texture) -> Result<(), Invalid> {
    let f = |k: &str| format!("textures[{i}].{k}");
    for (k, v) in [("width", t.width), ("height", t.height)] {
        if v == 0 || v > MAX_TEXTURE_SIDE {
            return Err(Invalid::new(
                f(k),
                format!("must be in 1..={MAX_TEXTURE_SIDE} texels, got {v}"),
            ));
        }
    }
    let want = u64::from(t.width) * u64::from(t.height);
    if t.texels.len() as u64 != want {
        return Err(Invalid::new(
            f("texels"),
            format!(
                "need width × height = {want} texels, got {}",
                t.texels.len()
            ),
        ));
    }
    Ok(())
}

/// A use of a texture at `field`: an existing texture among the `nt`, uv
/// set 0 or 1, and a finite transform that does not collapse uv (the level
/// of detail takes the log of its scale).
fn texture_ref(field: &str, t: &TextureRef, nt: usize) -> Result<(), Invalid> {
    if t.texture >= nt {
        return Err(Invalid::new(
            format!("{field}.texture"),
            format!("texture index {} out of range ({nt} textures)", t.texture),
        ));
    }
    if t.tex_coord > 1 {
        return Err(Invalid::new(
            format!("{field}.tex_coord"),
            format!(
                "must be 0 or 1 (TEXCOORD_0 or TEXCOORD_1), got {}",
                t.tex_coord
            ),
        ));
    }
    let tr = &t.transform;
    if !(tr.offset.is_finite() && tr.rotation.is_finite() && tr.scale.is_finite()) {
        return Err(Invalid::new(
            format!("{field}.transform"),
            format!(
                "must be finite, got offset {}, rotation {}, scale {}",
                tr.offset, tr.rotation, tr.scale
            ),
        ));
    }
    if tr.scale.x == 0.0 || tr.scale.y == 0.0 {
        return Err(Invalid::new(
            format!("{field}.transform.scale"),
            format!("must be non-zero in u and v, got {}", tr.scale),
        ));
    }
    Ok(())
}

/// Shader `i` of `n`: colours, sizes and Params values in range, a
/// checker's children among the `n` shaders, and its textures among the
/// `nt`.
fn shader(i: usize, sh: &Shader, n: usize, nt: usize) -> Result<(), Invalid> {
    let f = |k: &str| format!("shaders[{i}].{k}");
    match sh {
        Shader::Phong(p) | Shader::BlinnPhong(p) => {
            colour(&f("ambient"), p.ambient)?;
            colour(&f("diffuse"), p.diffuse)?;
            colour(&f("specular"), p.specular)?;
            for (k, t) in [
                ("textures.ambient", &p.textures.ambient),
                ("textures.diffuse", &p.textures.diffuse),
                ("textures.specular", &p.textures.specular),
            ] {
                if let Some(t) = t {
                    texture_ref(&f(k), t, nt)?;
                }
            }
            if !(p.shininess >= 0.0 && p.shininess.is_finite()) {
                return Err(Invalid::new(
                    f("shininess"),
                    format!("must be finite and >= 0, got {}", p.shininess),
                ));
            }
        }
        Shader::MetallicRoughness(m) => {
            colour(&f("base_colour"), m.base_colour)?;
            for (k, x) in [("metallic", m.metallic), ("roughness", m.roughness)] {
                if !(0.0..=1.0).contains(&x) {
                    return Err(Invalid::new(f(k), format!("must be in [0, 1], got {x}")));
                }
            }
            for (k, t) in [
                ("textures.base_colour", &m.textures.base_colour),
                (
                    "textures.metallic_roughness",
                    &m.textures.metallic_roughness,
                ),
            ] {
                if let Some(t) = t {
                    texture_ref(&f(k), t, nt)?;
                }
            }
        }
        Shader::SpecularGlossiness(m) => {
            colour(&f("diffuse"), m.diffuse)?;
            colour(&f("specular"), m.specular)?;
            if !(0.0..=1.0).contains(&m.glossiness) {
                return Err(Invalid::new(
                    f("glossiness"),
                    format!("must be in [0, 1], got {}", m.glossiness),
                ));
            }
            for (k, t) in [
                ("textures.diffuse", &m.textures.diffuse),
                (
                    "textures.specular_glossiness",
                    &m.textures.specular_glossiness,
                ),
            ] {
                if let Some(t) = t {
                    texture_ref(&f(k), t, nt)?;
                }
            }
        }
        Shader::Checker(c) => {
            if !(c.size > 0.0 && c.size.is_finite()) {
                return Err(Invalid::new(
                    f("size"),
                    format!("must be positive, got {}", c.size),
                ));
            }
            for (k, id) in [("even", c.even), ("odd", c.odd)] {
                if id >= n {
                    return Err(Invalid::new(
                        f(k),
                        format!("shader index {id} out of range ({n} shaders)"),
                    ));
                }
            }
        }
        Shader::Wgsl(w) => {
            if w.values.len() != w.fields.len() {
                return Err(Invalid::new(
                    f("values"),
                    format!(
                        "need one value per Params field: {} fields, {} values",
                        w.fields.len(),
                        w.values.len()
                    ),
                ));
            }
            for (field, value) in w.fields.iter().zip(&w.values) {
                let at = f(&format!("values.{}", field.name));
                if !value.fits(field.ty) {
                    return Err(Invalid::new(
                        at,
                        format!(
                            "Params field `{}` is {}, got {value:?}",
                            field.name, field.ty
                        ),
                    ));
                }
                if !value.is_finite() {
                    return Err(Invalid::new(at, format!("must be finite, got {value:?}")));
                }
                if let ParamValue::Texture(t) = value {
                    texture_ref(&at, t, nt)?;
                }
            }
        }
    }
    Ok(())
}

/// No cycle among the checker shaders (their children are in range).
fn checker_cycles(shaders: &[Shader]) -> Result<(), Invalid> {
    // Checkers nest; a cycle would make shading loop forever. Kahn-style
    // peeling: repeatedly drop shaders whose children are all resolved.
    let mut resolved = vec![false; shaders.len()];
    loop {
        let mut progress = false;
        for (i, sh) in shaders.iter().enumerate() {
            if resolved[i] {
                continue;
            }
            let ready = match sh {
                Shader::Checker(c) => resolved[c.even] && resolved[c.odd],
                _ => true,
            };
            if ready {
                resolved[i] = true;
                progress = true;
            }
        }
        if !progress {
            break;
        }
    }
    if let Some(i) = resolved.iter().position(|r| !r) {
        return Err(Invalid::new(
            format!("shaders[{i}]"),
            "checker shaders refer to each other in a cycle",
        ));
    }
    Ok(())
}

/// Object `i`: its shader among the `n` shaders, its shape's positions,
/// normals, radii, indices and vertex attributes, and its surface maps
/// (textures among the `nt`).
fn object(i: usize, o: &Object, n: usize, nt: usize) -> Result<(), Invalid> {
    let f = |k: &str| format!("objects[{i}].{k}");
    if o.shader >= n {
        return Err(Invalid::new(
            f("shader"),
            format!("shader index {} out of range ({n} shaders)", o.shader),
        ));
    }
    match &o.shape {
        Shape::Plane(p) => {
            bounded3(&f("point"), p.point)?;
            unit(&f("normal"), p.normal)?;
        }
        Shape::Sphere(sp) => {
            bounded3(&f("center"), sp.center)?;
            radius_ok(&f("radius"), sp.radius)?;
        }
        Shape::Triangle(t) => {
            for (k, v) in t.vertices.iter().enumerate() {
                bounded3(&f(&format!("vertices[{k}]")), *v)?;
            }
        }
        Shape::Mesh(m) => {
            // Formats a field name only for the first bad position.
            let bad = |p: &DVec3| !p.is_finite() || p.abs().max_element() > MAX_COORDINATE;
            if let Some(k) = m.positions.iter().position(bad) {
                bounded3(&f(&format!("positions[{k}]")), m.positions[k])?;
            }
            if let Some(ns) = &m.normals {
                if ns.len() != m.positions.len() {
                    return Err(Invalid::new(f("normals"), "need one normal per position"));
                }
                if let Some(k) = ns.iter().position(|v| !v.is_finite()) {
                    return Err(Invalid::new(f(&format!("normals[{k}]")), "must be finite"));
                }
            }
            let nv = m.positions.len() as u64;
            if let Some(k) = m
                .indices
                .iter()
                .position(|t| t.iter().any(|&x| x as u64 >= nv))
            {
                return Err(Invalid::new(
                    f(&format!("indices[{k}]")),
                    format!("vertex index out of range ({nv} vertices)"),
                ));
            }
            let np = m.positions.len();
            for (set, uvs) in m.uvs.iter().enumerate() {
                per_vertex(&f(&format!("uvs[{set}]")), uvs, np, |v| v.is_finite())?;
            }
            if let Some(cs) = &m.colours {
                per_vertex(&f("colours"), cs, np, |c| c.is_finite())?;
            }
            if let Some(ts) = &m.tangents {
                per_vertex(&f("tangents"), ts, np, |t| t.is_finite())?;
            }
        }
    }
    maps(i, &o.maps, &o.shape, nt)
}

/// A vertex attribute at `field`: one finite entry per each of the `np`
/// positions.
fn per_vertex<T>(
    field: &str,
    values: &[T],
    np: usize,
    finite: impl Fn(&T) -> bool,
) -> Result<(), Invalid> {
    if values.len() != np {
        return Err(Invalid::new(
            field,
            format!(
                "need one entry per position: {np} positions, {} entries",
                values.len()
            ),
        ));
    }
    if let Some(k) = values.iter().position(|v| !finite(v)) {
        return Err(Invalid::new(format!("{field}[{k}]"), "must be finite"));
    }
    Ok(())
}

/// The surface maps of object `i`: textures among the `nt`, a finite
/// normal scale (and tangents to tilt along), finite non-negative emission,
/// opacity in [0, 1], alpha tests only on triangles, a finite mask cutoff.
fn maps(i: usize, m: &SurfaceMaps, shape: &Shape, nt: usize) -> Result<(), Invalid> {
    let f = |k: &str| format!("objects[{i}].maps.{k}");
    if let Some((t, scale)) = &m.normal {
        texture_ref(&f("normal"), t, nt)?;
        if !scale.is_finite() {
            return Err(Invalid::new(
                f("normal.scale"),
                format!("must be finite, got {scale}"),
            ));
        }
        let tangents = matches!(shape, Shape::Mesh(mesh) if mesh.tangents.is_some());
        if !tangents {
            return Err(Invalid::new(
                f("normal"),
                "a normal map needs tangents: only a mesh with tangents can have one",
            ));
        }
    }
    colour(&f("emission"), m.emission)?;
    if let Some(t) = &m.emission_texture {
        texture_ref(&f("emission_texture"), t, nt)?;
    }
    if !(0.0..=1.0).contains(&m.opacity) {
        return Err(Invalid::new(
            f("opacity"),
            format!("must be in [0, 1], got {}", m.opacity),
        ));
    }
    if let Some(t) = &m.opacity_texture {
        texture_ref(&f("opacity_texture"), t, nt)?;
    }
    if let Some((t, strength)) = &m.occlusion {
        texture_ref(&f("occlusion"), t, nt)?;
        if !(0.0..=1.0).contains(strength) {
            return Err(Invalid::new(
                f("occlusion.strength"),
                format!("must be in [0, 1], got {strength}"),
            ));
        }
    }
    if m.alpha_mode != AlphaMode::Opaque && matches!(shape, Shape::Plane(_) | Shape::Sphere(_)) {
        return Err(Invalid::new(
            f("alpha_mode"),
            "only meshes and triangles can be masked or blended; planes and spheres are opaque",
        ));
    }
    if let AlphaMode::Mask { cutoff } = m.alpha_mode {
        if !cutoff.is_finite() {
            return Err(Invalid::new(
                f("alpha_mode.cutoff"),
                format!("must be finite, got {cutoff}"),
            ));
        }
    }
    Ok(())
}

/// Light `i`: intensity and colours, and its kind's geometry, angles and
/// sample count.
fn light(i: usize, l: &Light) -> Result<(), Invalid> {
    let f = |k: &str| format!("lights[{i}].{k}");
    if !(l.intensity >= 0.0 && l.intensity.is_finite()) {
        return Err(Invalid::new(
            f("intensity"),
            format!("must be finite and >= 0, got {}", l.intensity),
        ));
    }
    colour(&f("ambient"), l.ambient)?;
    colour(&f("diffuse"), l.diffuse)?;
    colour(&f("specular"), l.specular)?;
    match l.kind {
        LightKind::Directional { direction } => unit(&f("direction"), direction)?,
        LightKind::Point { position } => bounded3(&f("position"), position)?,
        LightKind::Spot {
            position,
            direction,
            inner_angle,
            outer_angle,
        } => {
            bounded3(&f("position"), position)?;
            unit(&f("direction"), direction)?;
            if !(inner_angle >= 0.0 && inner_angle < outer_angle) {
                return Err(Invalid::new(
                    f("inner_angle"),
                    format!(
                        "must satisfy 0 <= inner_angle < outer_angle, got {} and {} degrees",
                        inner_angle.to_degrees(),
                        outer_angle.to_degrees()
                    ),
                ));
            }
            if outer_angle > std::f64::consts::FRAC_PI_2 + 1e-12 {
                return Err(Invalid::new(
                    f("outer_angle"),
                    format!(
                        "must be at most 90 degrees, got {}",
                        outer_angle.to_degrees()
                    ),
                ));
            }
        }
        LightKind::Rect {
            corner,
            edge1,
            edge2,
            samples,
        } => {
            bounded3(&f("corner"), corner)?;
            bounded3(&f("edge1"), edge1)?;
            bounded3(&f("edge2"), edge2)?;
            let area = edge1.cross(edge2).length();
            let spans_area = area > 1e-12 * edge1.length_squared().max(edge2.length_squared());
            if !spans_area {
                return Err(Invalid::new(
                    f("edge2"),
                    "the rectangle has zero area (an edge is zero or the edges are parallel)",
                ));
            }
            samples_ok(&f("samples"), samples)?;
        }
        LightKind::Sphere {
            center,
            radius,
            samples,
        } => {
            bounded3(&f("center"), center)?;
            radius_ok(&f("radius"), radius)?;
            samples_ok(&f("samples"), samples)?;
        }
        LightKind::Environment { up, samples } => {
            unit(&f("up"), up)?;
            samples_ok(&f("samples"), samples)?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use glam::{DMat3, DVec2, DVec4, Vec4};

    use super::*;
    use crate::scene::{
        Filter, Mesh, ParamField, ParamType, Phong, PhongTextures, Sampler, TextureRef, Triangle,
        UvTransform, WgslShader,
    };

    /// A valid scene that uses every texture field: a 2×1 texture, a Phong
    /// shader with all three textures, a WGSL shader with a texture
    /// parameter, and a one-triangle mesh with two uv sets, colours,
    /// tangents and every map.
    fn textured() -> Scene {
        let t = TextureRef::new(0);
        let mesh = Mesh {
            positions: vec![DVec3::ZERO, DVec3::X, DVec3::Y],
            normals: None,
            indices: vec![[0, 1, 2]],
            uvs: vec![vec![DVec2::ZERO, DVec2::X, DVec2::Y]; 2],
            colours: Some(vec![Vec4::ONE; 3]),
            tangents: Some(vec![DVec4::new(1.0, 0.0, 0.0, 1.0); 3]),
        };
        Scene {
            camera: Camera {
                position: DVec3::new(0.0, 0.0, 5.0),
                orientation: DMat3::IDENTITY,
                projection: Projection::Perspective { vfov_deg: 40.0 },
                width: 8,
                height: 8,
            },
            background: Vec3::ZERO,
            shaders: vec![
                Shader::Phong(Phong {
                    ambient: Vec3::splat(0.1),
                    diffuse: Vec3::splat(0.5),
                    specular: Vec3::splat(0.2),
                    shininess: 10.0,
                    textures: PhongTextures {
                        ambient: Some(t),
                        diffuse: Some(t),
                        specular: Some(t),
                    },
                }),
                Shader::Wgsl(WgslShader {
                    path: "s.wgsl".into(),
                    source: String::new(),
                    fields: vec![ParamField {
                        name: "tex".into(),
                        ty: ParamType::U32,
                    }],
                    values: vec![ParamValue::Texture(t)],
                    has_ambient: false,
                }),
            ],
            objects: vec![Object {
                shape: Shape::Mesh(mesh),
                shader: 0,
                maps: SurfaceMaps {
                    normal: Some((t, 1.0)),
                    emission: Vec3::splat(0.5),
                    emission_texture: Some(t),
                    alpha_mode: AlphaMode::Mask { cutoff: 0.5 },
                    opacity: 1.0,
                    opacity_texture: Some(t),
                    double_sided: true,
                    occlusion: Some((t, 1.0)),
                    emission_by_colour: false,
                },
            }],
            lights: vec![],
            textures: vec![Texture {
                label: "t.png".into(),
                file: None,
                width: 2,
                height: 1,
                texels: vec![[255; 4]; 2],
                srgb: true,
            }],
        }
    }

    fn mesh(s: &mut Scene) -> &mut Mesh {
        match &mut s.objects[0].shape {
            Shape::Mesh(m) => m,
            _ => unreachable!(),
        }
    }

    fn phong(s: &mut Scene) -> &mut Phong {
        match &mut s.shaders[0] {
            Shader::Phong(p) => p,
            _ => unreachable!(),
        }
    }

    /// `edit` makes the textured scene invalid at exactly `field`.
    fn refused(field: &str, edit: impl FnOnce(&mut Scene)) {
        let mut s = textured();
        edit(&mut s);
        match s.validate() {
            Err(e) => assert_eq!(e.field, field, "{e}"),
            Ok(()) => panic!("accepted, expected an error at {field}"),
        }
    }

    #[test]
    fn the_textured_scene_is_valid() {
        assert_eq!(textured().validate(), Ok(()));
        // A sampler and transform of every kind are fine too.
        let mut s = textured();
        phong(&mut s).textures.diffuse = Some(TextureRef {
            texture: 0,
            sampler: Sampler {
                mag: Filter::Nearest,
                min: Filter::Nearest,
                mip: None,
                wrap_u: crate::scene::Wrap::ClampToEdge,
                wrap_v: crate::scene::Wrap::MirroredRepeat,
            },
            tex_coord: 1,
            transform: UvTransform {
                offset: DVec2::new(0.5, -3.0),
                rotation: 1.0,
                scale: DVec2::new(-2.0, 0.25),
            },
        });
        assert_eq!(s.validate(), Ok(()));
    }

    #[test]
    fn texture_sizes_and_texels() {
        refused("textures[0].width", |s| s.textures[0].width = 0);
        refused("textures[0].height", |s| s.textures[0].height = 0);
        refused("textures[0].width", |s| {
            s.textures[0].width = MAX_TEXTURE_SIDE + 1;
        });
        refused("textures[0].height", |s| {
            s.textures[0].height = MAX_TEXTURE_SIDE + 1;
        });
        refused("textures[0].texels", |s| {
            s.textures[0].texels.pop();
        });
        refused("textures[0].texels", |s| s.textures[0].texels.push([0; 4]));
    }

    #[test]
    fn texture_refs_index_existing_textures() {
        refused("shaders[0].textures.ambient.texture", |s| {
            phong(s).textures.ambient = Some(TextureRef::new(1));
        });
        refused("shaders[0].textures.diffuse.texture", |s| {
            phong(s).textures.diffuse = Some(TextureRef::new(7));
        });
        refused("shaders[0].textures.specular.texture", |s| {
            phong(s).textures.specular = Some(TextureRef::new(1));
        });
        refused("shaders[1].values.tex.texture", |s| {
            if let Shader::Wgsl(w) = &mut s.shaders[1] {
                w.values[0] = ParamValue::Texture(TextureRef::new(1));
            }
        });
        refused("objects[0].maps.normal.texture", |s| {
            s.objects[0].maps.normal = Some((TextureRef::new(1), 1.0));
        });
        refused("objects[0].maps.emission_texture.texture", |s| {
            s.objects[0].maps.emission_texture = Some(TextureRef::new(1));
        });
        refused("objects[0].maps.opacity_texture.texture", |s| {
            s.objects[0].maps.opacity_texture = Some(TextureRef::new(1));
        });
        refused("objects[0].maps.occlusion.texture", |s| {
            s.objects[0].maps.occlusion = Some((TextureRef::new(1), 1.0));
        });
        // No textures at all: index 0 is out of range too.
        refused("shaders[0].textures.ambient.texture", |s| {
            s.textures.clear()
        });
    }

    #[test]
    fn texture_refs_tex_coord_and_transform() {
        let bad = |edit: fn(&mut TextureRef)| {
            move |s: &mut Scene| {
                let mut t = TextureRef::new(0);
                edit(&mut t);
                s.objects[0].maps.emission_texture = Some(t);
            }
        };
        refused(
            "objects[0].maps.emission_texture.tex_coord",
            bad(|t| t.tex_coord = 2),
        );
        refused(
            "objects[0].maps.emission_texture.transform",
            bad(|t| t.transform.offset.x = f64::NAN),
        );
        refused(
            "objects[0].maps.emission_texture.transform",
            bad(|t| t.transform.rotation = f64::INFINITY),
        );
        refused(
            "objects[0].maps.emission_texture.transform",
            bad(|t| t.transform.scale.y = f64::NEG_INFINITY),
        );
        refused(
            "objects[0].maps.emission_texture.transform.scale",
            bad(|t| t.transform.scale.x = 0.0),
        );
        refused(
            "objects[0].maps.emission_texture.transform.scale",
            bad(|t| t.transform.scale.y = -0.0),
        );
    }

    #[test]
    fn mesh_attributes_one_finite_entry_per_position() {
        refused("objects[0].uvs[1]", |s| {
            mesh(s).uvs[1].pop();
        });
        refused("objects[0].uvs[0][2]", |s| mesh(s).uvs[0][2].y = f64::NAN);
        refused("objects[0].colours", |s| {
            mesh(s).colours.as_mut().unwrap().push(Vec4::ONE);
        });
        refused("objects[0].colours[1]", |s| {
            mesh(s).colours.as_mut().unwrap()[1].w = f32::INFINITY;
        });
        refused("objects[0].tangents", |s| {
            mesh(s).tangents.as_mut().unwrap().clear();
        });
        refused("objects[0].tangents[0]", |s| {
            mesh(s).tangents.as_mut().unwrap()[0].x = f64::NAN;
        });
    }

    #[test]
    fn surface_maps_in_range() {
        refused("objects[0].maps.emission", |s| {
            s.objects[0].maps.emission.y = -0.1;
        });
        refused("objects[0].maps.emission", |s| {
            s.objects[0].maps.emission.x = f32::NAN;
        });
        refused("objects[0].maps.opacity", |s| {
            s.objects[0].maps.opacity = 1.5
        });
        refused("objects[0].maps.opacity", |s| {
            s.objects[0].maps.opacity = -0.1
        });
        refused("objects[0].maps.opacity", |s| {
            s.objects[0].maps.opacity = f32::NAN;
        });
        for strength in [1.5, -0.1, f32::NAN] {
            refused("objects[0].maps.occlusion.strength", move |s| {
                s.objects[0].maps.occlusion = Some((TextureRef::new(0), strength));
            });
        }
        refused("objects[0].maps.alpha_mode.cutoff", |s| {
            s.objects[0].maps.alpha_mode = AlphaMode::Mask {
                cutoff: f32::INFINITY,
            };
        });
        refused("objects[0].maps.normal.scale", |s| {
            s.objects[0].maps.normal = Some((TextureRef::new(0), f32::NAN));
        });
    }

    #[test]
    fn only_triangles_are_masked_or_blended() {
        let plane = Shape::Plane(crate::scene::Plane {
            point: DVec3::ZERO,
            normal: DVec3::Y,
        });
        let sphere = Shape::Sphere(crate::scene::Sphere {
            center: DVec3::ZERO,
            radius: 1.0,
        });
        for shape in [plane, sphere] {
            for mode in [AlphaMode::Mask { cutoff: 0.5 }, AlphaMode::Blend] {
                let shape = shape.clone();
                refused("objects[0].maps.alpha_mode", move |s| {
                    s.objects[0].shape = shape;
                    s.objects[0].maps.normal = None;
                    s.objects[0].maps.alpha_mode = mode;
                });
            }
            // Opaque, with emission and textures, is fine.
            let mut s = textured();
            s.objects[0].shape = shape;
            s.objects[0].maps.normal = None;
            s.objects[0].maps.alpha_mode = AlphaMode::Opaque;
            assert_eq!(s.validate(), Ok(()));
        }
    }

    #[test]
    fn normal_maps_need_tangents() {
        refused("objects[0].maps.normal", |s| mesh(s).tangents = None);
        refused("objects[0].maps.normal", |s| {
            s.objects[0].shape = Shape::Triangle(Triangle {
                vertices: [DVec3::ZERO, DVec3::X, DVec3::Y],
            });
        });
        // Without a normal map a triangle with the other maps is fine.
        // (The mask stays: triangles can be cut out.)
        let mut s = textured();
        s.objects[0].shape = Shape::Triangle(Triangle {
            vertices: [DVec3::ZERO, DVec3::X, DVec3::Y],
        });
        s.objects[0].maps.normal = None;
        assert_eq!(s.validate(), Ok(()));
    }
}
