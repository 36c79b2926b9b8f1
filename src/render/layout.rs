//! The GPU's view of a scene: `#[repr(C)]` mirrors of the WGSL structs in
//! `shaders/`, and the conversion from the `f64` scene model into them.
//!
//! WGSL aligns `vec3<f32>` to 16 bytes, so every `vec3` is followed by a
//! 4-byte scalar or explicit padding. The test at the bottom compares every
//! struct's size and member offsets with naga's layouter on the real shader
//! source, so host and shader cannot drift apart.
//!
//! All positions are made camera-relative in `f64` before rounding to `f32`:
//! precision then depends on the distance from the eye, not from the world
//! origin.

// The fields mirror the WGSL struct named in each struct's documentation,
// member by member (the test at the bottom checks them); they need no docs
// of their own.
#![allow(missing_docs)]

use bytemuck::{Pod, Zeroable};
use glam::{DVec3, Vec3};

use crate::bvh::{Aabb, Bvh, Chunked};
use crate::scene::{LightKind, Projection, Scene, Shader, Shape};

/// Mirrors `Camera` in `shaders/camera.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct Camera {
    pub right: [f32; 3],
    pub orthographic: u32,
    pub up: [f32; 3],
    pub _pad0: u32,
    pub forward: [f32; 3],
    pub _pad1: u32,
}

/// Mirrors `Globals` in `shaders/render.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct Globals {
    pub camera: Camera,
    pub background: [f32; 3],
    pub num_planes: u32,
    pub num_spheres: u32,
    pub num_triangles: u32,
    pub num_lights: u32,
    pub num_shaders: u32,
    pub num_bvh_nodes: u32,
    pub _pad0: u32,
    pub _pad1: u32,
    pub _pad2: u32,
}

/// Mirrors `PushConstants` in `shaders/render.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct PushConstants {
    pub origin: [u32; 2],
    pub size: [u32; 2],
    pub flags: u32,
    pub pass_index: u32,
    pub seed: u32,
    pub slot_base: u32,
    pub tile_origin: [u32; 2],
    pub tile_width: u32,
    pub program: u32,
    pub sample_first: u32,
    pub sample_count: u32,
    pub light_count: u32,
    pub _pad0: u32,
}

/// `PushConstants::flags` bit: return at once (driver warm-up dispatch).
pub const FLAG_WARM_UP: u32 = 1;
/// `PushConstants::flags` bit: this pass overwrites the image whatever its
/// `pass_index` (the first pass of a sample split that does not start at 0).
pub const FLAG_FRESH: u32 = 2;

/// Mirrors `Plane` in `shaders/primitives/plane.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct Plane {
    pub point: [f32; 3],
    pub shader: u32,
    pub normal: [f32; 3],
    pub object: u32,
}

/// Mirrors `Sphere` in `shaders/primitives/sphere.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct Sphere {
    pub center: [f32; 3],
    pub radius: f32,
    pub shader: u32,
    pub object: u32,
    pub _pad: [u32; 2],
}

/// Mirrors `Triangle` in `shaders/primitives/triangle.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct Triangle {
    pub v0: [f32; 3],
    pub shader: u32,
    pub v1: [f32; 3],
    pub object: u32,
    pub v2: [f32; 3],
    pub normals: u32,
}

/// `Triangle::normals` value for flat-shaded triangles.
pub const NO_NORMALS: u32 = u32::MAX;

/// Mirrors `VertexNormals` in `shaders/primitives/triangle.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct VertexNormals {
    pub n0: [f32; 4],
    pub n1: [f32; 4],
    pub n2: [f32; 4],
}

/// Mirrors `Light` in `shaders/lights.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct Light {
    pub position: [f32; 3],
    pub kind: u32,
    pub direction: [f32; 3],
    pub cone_scale: f32,
    pub ambient: [f32; 3],
    pub cone_offset: f32,
    pub diffuse: [f32; 3],
    pub samples: u32,
    pub specular: [f32; 3],
    pub radius: f32,
    pub edge1: [f32; 3],
    pub intensity: f32,
    pub edge2: [f32; 3],
    pub _pad1: u32,
}

/// Mirrors `ShaderNode` in `shaders/shading/shader.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct ShaderNode {
    pub cell_offset: [f32; 3],
    pub inv_size: f32,
    pub kind: u32,
    pub parity: u32,
    pub even: u32,
    pub odd: u32,
    pub program: u32,
    pub params: u32,
    pub _pad0: u32,
    pub _pad1: u32,
}

/// Mirrors `BvhNode` in `shaders/bvh.wgsl`: an interior node's two
/// children, their boxes quantised in the node's frame (see
/// [`super::quantised_bvh`]); 32 bytes, two texels.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct BvhNode {
    /// The frame's lower corner, per axis `k·2^e` in one word: the signed
    /// step count `k` in the upper 24 bits, the step's biased exponent
    /// `e + 127` (as in an `f32`) in the low 8.
    pub origin: [u32; 3],
    /// Child reference: a record index, or `LEAF | first primitive`.
    pub left: u32,
    /// Twelve steps, a byte each: the left child's lower then upper corner
    /// (x, y, z), then the right child's.
    pub quantised: [u32; 3],
    /// The right child's reference.
    pub right: u32,
}

/// Mirrors `QueryRay` in `shaders/queries.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct QueryRay {
    pub origin: [f32; 3],
    pub _pad0: u32,
    pub dir: [f32; 3],
    pub _pad1: u32,
}

/// Mirrors `QueryHit` in `shaders/queries.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct QueryHit {
    pub t: f32,
    pub kind: u32,
    pub index: u32,
    pub u: f32,
    pub v: f32,
    pub _pad0: u32,
    pub _pad1: u32,
    pub _pad2: u32,
}

/// Mirrors `Aov` in `shaders/aov.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct Aov {
    pub depth: f32,
    pub normal_x: f32,
    pub normal_y: f32,
    pub normal_z: f32,
    pub u: f32,
    pub v: f32,
    pub object: u32,
    pub primitive: u32,
}

pub use crate::bvh::PRIM_SPHERE;

/// Shader kinds, as in `shaders/shading/shader.wgsl`: a leaf (a shader
/// file with its parameters).
pub const SHADER_LEAF: u32 = 0;
/// Checker shader kind.
pub const SHADER_CHECKER: u32 = 2;
/// Light kinds, as in `shaders/lights.wgsl`.
pub const LIGHT_DIRECTIONAL: u32 = 0;
/// Point light kind.
pub const LIGHT_POINT: u32 = 1;
/// Spot light kind.
pub const LIGHT_SPOT: u32 = 2;
/// Rectangular area light kind.
pub const LIGHT_RECT: u32 = 3;
/// Sphere area light kind.
pub const LIGHT_SPHERE: u32 = 4;

/// A scene laid out for the GPU.
#[derive(Clone, Debug, Default)]
pub struct GpuScene {
    pub globals: Globals,
    pub planes: Vec<Plane>,
    pub spheres: Vec<Sphere>,
    pub triangles: Vec<Triangle>,
    pub vertex_normals: Vec<VertexNormals>,
    pub lights: Vec<Light>,
    pub shaders: Vec<ShaderNode>,
    pub bvh_nodes: Vec<BvhNode>,
    pub bvh_prims: Vec<u32>,
    /// Depth of the BVH (0 when built without one).
    pub bvh_depth: usize,
}

fn f3(v: DVec3) -> [f32; 3] {
    v.as_vec3().to_array()
}

fn c3(v: Vec3) -> [f32; 3] {
    v.to_array()
}

fn n4(v: DVec3) -> [f32; 4] {
    v.as_vec3().extend(0.0).to_array()
}

impl GpuScene {
    /// Lays out a validated scene, camera-relative (without a BVH: see
    /// [`GpuScene::build_bvh`]).
    pub fn new(scene: &Scene) -> GpuScene {
        let cam = &scene.camera;
        let eye = cam.position;
        let (hw, hh) = cam.half_extent();
        let camera = Camera {
            right: f3(cam.orientation.x_axis * hw),
            orthographic: matches!(cam.projection, Projection::Orthographic { .. }) as u32,
            up: f3(cam.orientation.y_axis * hh),
            _pad0: 0,
            forward: f3(-cam.orientation.z_axis),
            _pad1: 0,
        };
        let mut g = GpuScene::default();
        for (object, o) in scene.objects.iter().enumerate() {
            let (shader, object) = (o.shader as u32, object as u32);
            let push_triangle = |v: [DVec3; 3], normals: Option<[DVec3; 3]>, g: &mut GpuScene| {
                let normals = match normals {
                    Some([a, b, c]) => {
                        g.vertex_normals.push(VertexNormals {
                            n0: n4(a),
                            n1: n4(b),
                            n2: n4(c),
                        });
                        g.vertex_normals.len() as u32 - 1
                    }
                    None => NO_NORMALS,
                };
                // Camera-relative in f64, then rounded: a vertex shared by
                // several triangles gets the same bits in each (watertight).
                g.triangles.push(Triangle {
                    v0: f3(v[0] - eye),
                    shader,
                    v1: f3(v[1] - eye),
                    object,
                    v2: f3(v[2] - eye),
                    normals,
                });
            };
            match &o.shape {
                Shape::Plane(p) => g.planes.push(Plane {
                    point: f3(closest_point_to(p.point, p.normal, eye) - eye),
                    shader,
                    normal: f3(p.normal),
                    object,
                }),
                Shape::Sphere(s) => g.spheres.push(Sphere {
                    center: f3(s.center - eye),
                    radius: s.radius as f32,
                    shader,
                    object,
                    _pad: [0; 2],
                }),
                Shape::Triangle(t) => push_triangle(t.vertices, None, &mut g),
                Shape::Mesh(m) => {
                    for (i, idx) in m.indices.iter().enumerate() {
                        let normals = m.normals.as_ref().map(|n| idx.map(|k| n[k as usize]));
                        push_triangle(m.triangle(i).vertices, normals, &mut g);
                    }
                }
            }
        }
        for l in &scene.lights {
            let mut gl = Light {
                ambient: c3(l.ambient),
                diffuse: c3(l.diffuse),
                specular: c3(l.specular),
                intensity: l.intensity,
                samples: 1,
                ..Default::default()
            };
            match l.kind {
                LightKind::Directional { direction } => {
                    gl.kind = LIGHT_DIRECTIONAL;
                    gl.direction = f3(direction);
                }
                LightKind::Point { position } => {
                    gl.kind = LIGHT_POINT;
                    gl.position = f3(position - eye);
                }
                LightKind::Spot {
                    position,
                    direction,
                    inner_angle,
                    outer_angle,
                } => {
                    let (scale, offset) =
                        LightKind::spot_cone_scale_offset(inner_angle, outer_angle);
                    gl.kind = LIGHT_SPOT;
                    gl.position = f3(position - eye);
                    gl.direction = f3(direction);
                    gl.cone_scale = scale as f32;
                    gl.cone_offset = offset as f32;
                }
                LightKind::Rect {
                    corner,
                    edge1,
                    edge2,
                    samples,
                } => {
                    gl.kind = LIGHT_RECT;
                    gl.position = f3(corner - eye);
                    gl.edge1 = f3(edge1);
                    gl.edge2 = f3(edge2);
                    gl.direction = f3(edge1.cross(edge2).normalize());
                    gl.samples = samples;
                }
                LightKind::Sphere {
                    center,
                    radius,
                    samples,
                } => {
                    gl.kind = LIGHT_SPHERE;
                    gl.position = f3(center - eye);
                    gl.radius = radius as f32;
                    gl.samples = samples;
                }
            }
            g.lights.push(gl);
        }
        // Leaves get their program and parameters from the shade stage's
        // materials (super::materials), which read the shader files.
        for sh in &scene.shaders {
            g.shaders.push(match sh {
                Shader::Checker(c) => {
                    // Split the eye's position in cells into whole cells (whose
                    // parity we keep) and a fraction, in f64.
                    let cells = eye / c.size;
                    let whole = cells.floor();
                    let parity = (whole.x + whole.y + whole.z).rem_euclid(2.0) as u32;
                    ShaderNode {
                        kind: SHADER_CHECKER,
                        inv_size: (1.0 / c.size) as f32,
                        cell_offset: f3(cells - whole),
                        parity,
                        even: c.even as u32,
                        odd: c.odd as u32,
                        ..Default::default()
                    }
                }
                _ => ShaderNode {
                    kind: SHADER_LEAF,
                    ..Default::default()
                },
            });
        }
        g.globals = Globals {
            camera,
            background: c3(scene.background),
            num_planes: g.planes.len() as u32,
            num_spheres: g.spheres.len() as u32,
            num_triangles: g.triangles.len() as u32,
            num_lights: g.lights.len() as u32,
            num_shaders: g.shaders.len() as u32,
            num_bvh_nodes: 0,
            _pad0: 0,
            _pad1: 0,
            _pad2: 0,
        };
        g
    }

    /// Builds the BVH over the primitives exactly as the GPU sees them (the
    /// rounded `f32` values), with boxes rounded outwards to `f32` and padded
    /// by a few ulps so that no hit the intersection routines report can lie
    /// outside its box ([`node_bounds`]), and encodes it for the kernel
    /// ([`super::quantised_bvh`]).
    pub fn build_bvh(&mut self) {
        let built = self.build_chunked();
        self.encode_bvh(&built);
    }

    /// The second half of [`GpuScene::build_bvh`]: the kernel's primitive
    /// references and records of `built`, from [`GpuScene::build_chunked`].
    pub fn encode_bvh(&mut self, built: &Chunked) {
        let mut prims = built.prim_refs(self.triangles.len());
        self.bvh_nodes = super::quantised_bvh::encode(built, &mut prims);
        self.bvh_prims = prims;
        self.bvh_depth = built.depth;
        self.globals.num_bvh_nodes = self.bvh_nodes.len() as u32;
    }

    /// The host tree [`GpuScene::build_bvh`] encodes, flattened: over the
    /// triangles, then the spheres (the build is deterministic, so calling
    /// this again gives the same tree).
    pub fn build_tree(&self) -> Bvh {
        self.build_chunked().flatten()
    }

    /// The first half of [`GpuScene::build_bvh`]: the host tree as the
    /// builder leaves it (see [`GpuScene::build_tree`]).
    pub fn build_chunked(&self) -> Chunked {
        // Triangle boxes straight from the f32 vertices (exact); sphere
        // boxes computed in f64 and rounded outwards.
        let spheres: Vec<([f32; 3], [f32; 3])> = self
            .spheres
            .iter()
            .map(|s| {
                let c = DVec3::from_array(s.center.map(f64::from));
                let r = DVec3::splat(s.radius as f64);
                node_bounds_f32(Aabb {
                    min: c - r,
                    max: c + r,
                })
            })
            .collect();
        let triangles = &self.triangles;
        Bvh::build_f32_chunked(triangles.len() + spheres.len(), |i| {
            let Some(t) = triangles.get(i) else {
                return spheres[i - triangles.len()];
            };
            let (a, b, c) = (Vec3::from(t.v0), Vec3::from(t.v1), Vec3::from(t.v2));
            (a.min(b).min(c).to_array(), a.max(b).max(c).to_array())
        })
    }
}

/// A box padded by 2⁻²⁰ of its largest coordinate magnitude (a few `f32`
/// ulps), so it contains the rounding error of the ray/primitive tests: the
/// boxes the kernel's BVH records contain.
pub fn node_bounds(b: Aabb) -> Aabb {
    let pad = b.min.abs().max(b.max.abs()).max_element() * (1.0 / (1u64 << 20) as f64);
    Aabb {
        min: b.min - pad,
        max: b.max + pad,
    }
}

/// [`node_bounds`] rounded outwards to `f32`: it contains the `f64` box and
/// the rounding error of the ray/primitive tests.
pub fn node_bounds_f32(b: Aabb) -> ([f32; 3], [f32; 3]) {
    node_bounds(b).outward_f32()
}

/// The point of a plane nearest to `eye`: a far-away `point` on the plane
/// would lose precision when rounded; this one is as close as the plane gets.
fn closest_point_to(point: DVec3, normal: DVec3, eye: DVec3) -> DVec3 {
    eye - normal * normal.dot(eye - point)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::mem::{offset_of, size_of};

    /// A mirrored struct: its WGSL name, Rust size, and (member, offset).
    type HostLayout = (&'static str, usize, Vec<(&'static str, usize)>);

    fn host_layouts() -> Vec<HostLayout> {
        macro_rules! layout {
            ($wgsl:literal, $t:ty, [$($f:ident),*]) => {
                ($wgsl, size_of::<$t>(), vec![$((stringify!($f), offset_of!($t, $f))),*])
            };
        }
        vec![
            layout!(
                "Camera",
                Camera,
                [right, orthographic, up, _pad0, forward, _pad1]
            ),
            layout!(
                "Globals",
                Globals,
                [
                    camera,
                    background,
                    num_planes,
                    num_spheres,
                    num_triangles,
                    num_lights,
                    num_shaders,
                    num_bvh_nodes,
                    _pad0,
                    _pad1,
                    _pad2
                ]
            ),
            layout!("BvhNode", BvhNode, [origin, left, quantised, right]),
            layout!("QueryRay", QueryRay, [origin, _pad0, dir, _pad1]),
            layout!(
                "Aov",
                Aov,
                [depth, normal_x, normal_y, normal_z, u, v, object, primitive]
            ),
            layout!(
                "QueryHit",
                QueryHit,
                [t, kind, index, u, v, _pad0, _pad1, _pad2]
            ),
            layout!(
                "PushConstants",
                PushConstants,
                [
                    origin,
                    size,
                    flags,
                    pass_index,
                    seed,
                    slot_base,
                    tile_origin,
                    tile_width,
                    program,
                    sample_first,
                    sample_count,
                    light_count,
                    _pad0
                ]
            ),
            layout!("Plane", Plane, [point, shader, normal, object]),
            layout!("Sphere", Sphere, [center, radius, shader, object, _pad]),
            layout!("Triangle", Triangle, [v0, shader, v1, object, v2, normals]),
            layout!("VertexNormals", VertexNormals, [n0, n1, n2]),
            layout!(
                "Light",
                Light,
                [
                    position,
                    kind,
                    direction,
                    cone_scale,
                    ambient,
                    cone_offset,
                    diffuse,
                    samples,
                    specular,
                    radius,
                    edge1,
                    intensity,
                    edge2,
                    _pad1
                ]
            ),
            layout!(
                "ShaderNode",
                ShaderNode,
                [
                    cell_offset,
                    inv_size,
                    kind,
                    parity,
                    even,
                    odd,
                    program,
                    params,
                    _pad0,
                    _pad1
                ]
            ),
        ]
    }

    #[test]
    fn host_structs_match_wgsl_layout() {
        let source = crate::render::compile::ShaderSource::Embedded
            .assemble()
            .unwrap();
        let module = naga::front::wgsl::parse_str(&source.text).unwrap();
        let mut layouter = naga::proc::Layouter::default();
        layouter.update(module.to_ctx()).unwrap();
        for (name, size, fields) in host_layouts() {
            let (handle, ty) = module
                .types
                .iter()
                .find(|(_, t)| t.name.as_deref() == Some(name))
                .unwrap_or_else(|| panic!("struct {name} not found in the shaders"));
            let naga::TypeInner::Struct { members, span } = &ty.inner else {
                panic!("{name} is not a struct");
            };
            // Arrays of these structs stride by the WGSL size, rounded to alignment.
            assert_eq!(*span as usize, size, "{name}: size");
            assert_eq!(
                layouter[handle].size as usize, size,
                "{name}: layouter size"
            );
            let wgsl: Vec<(&str, usize)> = members
                .iter()
                .map(|m| (m.name.as_deref().unwrap_or(""), m.offset as usize))
                .collect();
            assert_eq!(wgsl, fields, "{name}: members and offsets");
        }
    }

    /// The shade stage's prefixed mirrors (`shaders/stages/shade.wgsl`)
    /// have the host's layouts too.
    #[test]
    fn shade_stage_mirrors_match_the_host() {
        use crate::render::shade::{assemble, read_program, ProgramFile};
        use crate::render::ShaderSource;
        let file = ProgramFile::Builtin("shading/phong.wgsl");
        let text = read_program(&ShaderSource::Embedded, &file).unwrap();
        let source = assemble(&ShaderSource::Embedded, &file, &text).unwrap();
        let module = source.assembled.parse().unwrap();
        let mut layouter = naga::proc::Layouter::default();
        layouter.update(module.to_ctx()).unwrap();
        let layouts = host_layouts();
        let name = "PushConstants";
        let (_, size, fields) = layouts.iter().find(|l| l.0 == name).unwrap();
        let prefixed = format!("penumbra_{name}");
        let (_, ty) = module
            .types
            .iter()
            .find(|(_, t)| t.name.as_deref() == Some(prefixed.as_str()))
            .unwrap_or_else(|| panic!("{prefixed} not in shade.wgsl"));
        let naga::TypeInner::Struct { members, span } = &ty.inner else {
            panic!("{prefixed} is not a struct");
        };
        assert_eq!(*span as usize, *size, "{prefixed}: size");
        let wgsl: Vec<(&str, usize)> = members
            .iter()
            .map(|m| (m.name.as_deref().unwrap_or(""), m.offset as usize))
            .collect();
        assert_eq!(&wgsl, fields, "{prefixed}: members and offsets");
    }

    /// The shade stage's copies of engine constants equal the engine's.
    #[test]
    fn shade_stage_constants_match_the_engine() {
        use crate::render::shade::{assemble, read_program, ProgramFile};
        use crate::render::ShaderSource;
        let file = ProgramFile::Builtin("shading/phong.wgsl");
        let text = read_program(&ShaderSource::Embedded, &file).unwrap();
        let shade = assemble(&ShaderSource::Embedded, &file, &text)
            .unwrap()
            .assembled
            .parse()
            .unwrap();
        let engine = ShaderSource::Embedded.assemble().unwrap().parse().unwrap();
        let value = |m: &naga::Module, name: &str| {
            let (_, c) = m
                .constants
                .iter()
                .find(|(_, c)| c.name.as_deref() == Some(name))
                .unwrap_or_else(|| panic!("const {name} not found"));
            match m.global_expressions[c.init] {
                naga::Expression::Literal(naga::Literal::U32(v)) => v,
                _ => panic!("{name} is not a u32 literal"),
            }
        };
        for name in [
            "FLAG_WARM_UP",
            "KIND_NONE",
            "RECORD_TEXELS",
            "QUEUE_TEXELS",
            "TEXEL_ROW_SHIFT",
        ] {
            assert_eq!(
                value(&shade, &format!("penumbra_{name}")),
                value(&engine, name),
                "{name}"
            );
        }
    }

    /// Every constant the host and the kernel both use has the same value
    /// in both (the WGSL `const`s, read back through naga).
    #[test]
    fn shared_constants_match_wgsl() {
        use crate::render::quantised_bvh::{LEAF, NONE, PRIM_LAST};
        let source = crate::render::compile::ShaderSource::Embedded
            .assemble()
            .unwrap();
        let module = naga::front::wgsl::parse_str(&source.text).unwrap();
        let shared = [
            ("PRIM_SPHERE", PRIM_SPHERE),
            ("PRIM_LAST", PRIM_LAST),
            ("BVH_LEAF", LEAF),
            ("BVH_NONE", NONE),
            ("NO_NORMALS", NO_NORMALS),
            ("FLAG_WARM_UP", FLAG_WARM_UP),
            ("FLAG_FRESH", FLAG_FRESH),
            ("SHADER_LEAF", SHADER_LEAF),
            ("SHADER_CHECKER", SHADER_CHECKER),
            ("LIGHT_DIRECTIONAL", LIGHT_DIRECTIONAL),
            ("LIGHT_POINT", LIGHT_POINT),
            ("LIGHT_SPOT", LIGHT_SPOT),
            ("LIGHT_RECT", LIGHT_RECT),
            ("LIGHT_SPHERE", LIGHT_SPHERE),
            ("TEXEL_ROW", crate::vulkan::TEXEL_ROW),
            ("RECORD_TEXELS", super::super::tiles::RECORD_TEXELS as u32),
            ("QUEUE_TEXELS", super::super::tiles::QUEUE_TEXELS as u32),
            ("TEXEL_ROW_SHIFT", crate::vulkan::TEXEL_ROW.trailing_zeros()),
            (
                "BVH_RECORD_TEXELS",
                (std::mem::size_of::<BvhNode>() / crate::vulkan::TEXEL_BYTES) as u32,
            ),
            (
                "TRIANGLE_TEXELS",
                (std::mem::size_of::<Triangle>() / crate::vulkan::TEXEL_BYTES) as u32,
            ),
        ];
        assert!(crate::vulkan::TEXEL_ROW.is_power_of_two());
        for size in [
            std::mem::size_of::<BvhNode>(),
            std::mem::size_of::<Triangle>(),
        ] {
            assert_eq!(size % crate::vulkan::TEXEL_BYTES, 0, "whole texels");
        }
        for (name, host) in shared {
            let (_, c) = module
                .constants
                .iter()
                .find(|(_, c)| c.name.as_deref() == Some(name))
                .unwrap_or_else(|| panic!("const {name} not found in the shaders"));
            let naga::Expression::Literal(naga::Literal::U32(wgsl)) =
                module.global_expressions[c.init]
            else {
                panic!("{name} is not a u32 literal");
            };
            assert_eq!(wgsl, host, "{name}");
        }
        // PRIM_INDEX masks off exactly the two flag bits.
        let prim_index = module
            .constants
            .iter()
            .find(|(_, c)| c.name.as_deref() == Some("PRIM_INDEX"))
            .map(|(_, c)| &module.global_expressions[c.init]);
        assert!(matches!(
            prim_index,
            Some(naga::Expression::Literal(naga::Literal::U32(m))) if *m == !(PRIM_SPHERE | PRIM_LAST)
        ));
    }

    #[test]
    fn checker_offset_keeps_parity_far_away() {
        use crate::scene::Checker;
        let c = Checker {
            size: 0.5,
            even: 0,
            odd: 1,
        };
        for eye in [
            DVec3::new(1e7 + 0.3, -2.2e5, 3.7),
            DVec3::new(-0.1, 0.2, 0.3),
        ] {
            let cells = eye / c.size;
            let whole = cells.floor();
            let parity = (whole.x + whole.y + whole.z).rem_euclid(2.0) as u32;
            let frac = cells - whole;
            for p in [DVec3::new(0.01, 0.2, -0.7), DVec3::new(-1.3, 0.9, 2.1)] {
                let cell = (p / c.size + frac).floor();
                let even = (cell.x + cell.y + cell.z + parity as f64).rem_euclid(2.0) == 0.0;
                assert_eq!(even, c.is_even(eye + p));
            }
        }
    }
}
