//! Scene invariants. Loaders check values as they read them (with their own
//! field paths); this is the last line of defence, also for scenes built in
//! code.

use std::fmt;

use glam::{DVec3, Vec3};

use super::{Camera, Light, LightKind, Object, Projection, Scene, Shader, Shape};

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
/// is reported): camera, background, shaders, checker cycles, objects,
/// lights.
pub(super) fn scene(s: &Scene) -> Result<(), Invalid> {
    camera(&s.camera)?;
    colour("background", s.background)?;
    let n = s.shaders.len();
    for (i, sh) in s.shaders.iter().enumerate() {
        shader(i, sh, n)?;
    }
    checker_cycles(&s.shaders)?;
    for (i, o) in s.objects.iter().enumerate() {
        object(i, o, n)?;
    }
    for (i, l) in s.lights.iter().enumerate() {
        light(i, l)?;
    }
    Ok(())
}

/// Shader `i` of `n`: colours, sizes and Params values in range, and a
/// checker's children among the `n` shaders.
fn shader(i: usize, sh: &Shader, n: usize) -> Result<(), Invalid> {
    let f = |k: &str| format!("shaders[{i}].{k}");
    match sh {
        Shader::Phong(p) | Shader::BlinnPhong(p) => {
            colour(&f("ambient"), p.ambient)?;
            colour(&f("diffuse"), p.diffuse)?;
            colour(&f("specular"), p.specular)?;
            if !(p.shininess >= 0.0 && p.shininess.is_finite()) {
                return Err(Invalid::new(
                    f("shininess"),
                    format!("must be finite and >= 0, got {}", p.shininess),
                ));
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

/// Object `i`: its shader among the `n` shaders, and its shape's
/// positions, normals, radii and indices.
fn object(i: usize, o: &Object, n: usize) -> Result<(), Invalid> {
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
    }
    Ok(())
}
