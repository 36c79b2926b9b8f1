//! The GPU's view of a scene: `#[repr(C)]` mirrors of the WGSL structs in
//! `shaders/`, and the conversion from the `f64` scene model into them, one
//! file per concept of `shaders/` (each struct next to its conversion).
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

mod aov;
mod bvh;
mod camera;
mod lights;
mod primitives;
mod queries;
mod shading;
pub mod textures;

use bytemuck::{Pod, Zeroable};
use glam::{DVec3, Vec3};

pub use aov::Aov;
pub use bvh::{node_bounds, node_bounds_f32, BvhNode, PRIM_SPHERE};
pub use camera::Camera;
pub use lights::{
    light_block, Light, LIGHT_DIRECTIONAL, LIGHT_ENVIRONMENT, LIGHT_POINT, LIGHT_RECT,
    LIGHT_SPHERE, LIGHT_SPOT, UNIFORM_LIGHTS,
};
pub use primitives::{plane_axes, Plane, Sphere, Triangle, VertexNormals, NO_NORMALS};
pub use queries::{QueryHit, QueryRay};
pub use shading::{ShaderNode, SHADER_CHECKER, SHADER_LEAF};
pub use textures::GpuTextures;

use crate::scene::Scene;

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
/// `PushConstants::flags` bit: the shade stage's dispatch of the last chunk
/// of light samples, which writes the image (earlier chunks sum in the
/// colour sums).
pub const FLAG_LAST_CHUNK: u32 = 4;
/// `PushConstants::flags` bit: the shade stage interpolates triangles'
/// vertex attributes (the scene has them).
pub const FLAG_ATTRIBUTES: u32 = 8;
/// `PushConstants::flags` bit: the shade stage adds the objects' emission.
pub const FLAG_EMISSION: u32 = 16;
/// `PushConstants::flags` bit: the shade stage reads vertex colours (some
/// mesh has them; the others' are (1, 1, 1, 1) anyway).
pub const FLAG_COLOURS: u32 = 32;

/// The flags of every dispatch of `scene`'s frames: [`FLAG_ATTRIBUTES`],
/// [`FLAG_EMISSION`] and [`FLAG_COLOURS`] where it needs them.
pub fn shade_flags(scene: &Scene) -> u32 {
    let f = scene.features();
    let mut flags = 0;
    if f.attributes {
        flags |= FLAG_ATTRIBUTES;
    }
    if f.emission {
        flags |= FLAG_EMISSION;
    }
    if f.vertex_colours {
        flags |= FLAG_COLOURS;
    }
    flags
}

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
    /// Textures, their uses, surface maps and vertex attributes.
    pub textures: GpuTextures,
}

pub(super) fn f3(v: DVec3) -> [f32; 3] {
    v.as_vec3().to_array()
}

pub(super) fn c3(v: Vec3) -> [f32; 3] {
    v.to_array()
}

pub(super) fn n4(v: DVec3) -> [f32; 4] {
    v.as_vec3().extend(0.0).to_array()
}

impl GpuScene {
    /// Lays out a validated scene, camera-relative (without a BVH: see
    /// [`GpuScene::build_bvh`]).
    pub fn new(scene: &Scene) -> GpuScene {
        let eye = scene.camera.position;
        let mut g = GpuScene::default();
        for (object, o) in scene.objects.iter().enumerate() {
            primitives::push_object(&mut g, o, object as u32, eye);
        }
        g.lights = scene.lights.iter().map(|l| lights::light(l, eye)).collect();
        g.textures = GpuTextures::new(scene);
        // Leaves get their program and parameters from the shade stage's
        // materials (super::shade), which read the shader files.
        g.shaders = scene
            .shaders
            .iter()
            .map(|sh| shading::node(sh, eye))
            .collect();
        g.globals = Globals {
            camera: camera::camera(&scene.camera),
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
            layout!(
                "Plane",
                Plane,
                [point, shader, normal, object, uv_origin, _pad]
            ),
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

    /// WGSL struct `name` of `module`: its span, its size by naga's
    /// layouter, and its (member, offset) pairs.
    fn wgsl_struct<'m>(
        module: &'m naga::Module,
        name: &str,
    ) -> (usize, usize, Vec<(&'m str, usize)>) {
        let mut layouter = naga::proc::Layouter::default();
        layouter.update(module.to_ctx()).unwrap();
        let (handle, ty) = module
            .types
            .iter()
            .find(|(_, t)| t.name.as_deref() == Some(name))
            .unwrap_or_else(|| panic!("struct {name} not found in the shaders"));
        let naga::TypeInner::Struct { members, span } = &ty.inner else {
            panic!("{name} is not a struct");
        };
        let fields = members
            .iter()
            .map(|m| (m.name.as_deref().unwrap_or(""), m.offset as usize))
            .collect();
        (*span as usize, layouter[handle].size as usize, fields)
    }

    /// Every `#[repr(C)]` struct of this module is in [`host_layouts`], so
    /// that a new mirror of a WGSL struct cannot go unchecked.
    #[test]
    fn every_mirrored_struct_is_in_host_layouts() {
        let sources = [
            include_str!("mod.rs"),
            include_str!("aov.rs"),
            include_str!("bvh.rs"),
            include_str!("camera.rs"),
            include_str!("lights.rs"),
            include_str!("primitives.rs"),
            include_str!("queries.rs"),
            include_str!("shading.rs"),
            include_str!("textures.rs"),
        ];
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src/render/layout");
        let files = std::fs::read_dir(dir).unwrap().count();
        assert_eq!(
            files,
            sources.len(),
            "a file of src/render/layout/ is not read here"
        );
        let listed: Vec<&str> = host_layouts().iter().map(|(name, ..)| *name).collect();
        let mut mirrored = 0;
        for source in sources {
            // A top-level `#[repr(C)]` attribute line, then the struct's line.
            let mut lines = source.lines();
            while let Some(line) = lines.next() {
                if line != "#[repr(C)]" {
                    continue;
                }
                let name = lines
                    .find_map(|l| l.strip_prefix("pub struct "))
                    .and_then(|rest| rest.split(|c: char| !c.is_alphanumeric()).next())
                    .unwrap_or_default();
                assert!(listed.contains(&name), "{name:?} is not in host_layouts()");
                mirrored += 1;
            }
        }
        assert_eq!(mirrored, listed.len());
    }

    #[test]
    fn host_structs_match_wgsl_layout() {
        let source = crate::render::compile::ShaderSource::Embedded
            .assemble()
            .unwrap();
        let module = naga::front::wgsl::parse_str(&source.text).unwrap();
        for (name, size, fields) in host_layouts() {
            let (span, laid_out, wgsl) = wgsl_struct(&module, name);
            // Arrays of these structs stride by the WGSL size, rounded to alignment.
            assert_eq!(span, size, "{name}: size");
            assert_eq!(laid_out, size, "{name}: layouter size");
            assert_eq!(wgsl, fields, "{name}: members and offsets");
        }
    }

    /// The shade stage's prefixed mirrors (`shaders/stages/shade.wgsl`)
    /// have the host's layouts too, and its globals begin with the camera
    /// as the host's do.
    #[test]
    fn shade_stage_mirrors_match_the_host() {
        let module = crate::render::shade::phong_module();
        let layouts = host_layouts();
        for name in ["PushConstants", "Camera"] {
            let (_, size, fields) = layouts.iter().find(|l| l.0 == name).unwrap();
            let prefixed = format!("penumbra_{name}");
            let (span, laid_out, wgsl) = wgsl_struct(&module, &prefixed);
            assert_eq!((span, laid_out), (*size, *size), "{prefixed}: size");
            assert_eq!(&wgsl, fields, "{prefixed}: members and offsets");
        }
        let (_, _, wgsl) = wgsl_struct(&module, "penumbra_Globals");
        assert_eq!(wgsl, [("camera", offset_of!(Globals, camera))]);
    }

    /// The shade stage's copies of engine constants equal the engine's.
    #[test]
    fn shade_stage_constants_match_the_engine() {
        use crate::render::ShaderSource;
        let shade = crate::render::shade::phong_module();
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
            "FLAG_FRESH",
            "FLAG_LAST_CHUNK",
            "FLAG_ATTRIBUTES",
            "FLAG_EMISSION",
            "FLAG_COLOURS",
            "KIND_TRIANGLE",
            "KIND_NONE",
            "KIND_BITS",
            "RECORD_TEXELS",
            "QUEUE_TEXELS",
            "TEXEL_ROW_SHIFT",
            "SHADER_NODE_TEXELS",
        ] {
            assert_eq!(
                value(&shade, &format!("penumbra_{name}")),
                value(&engine, name),
                "{name}"
            );
        }
        // Without checkers the shade stage reads a leaf's program and
        // first parameter word as the x and y of its node's third texel.
        assert_eq!(std::mem::offset_of!(ShaderNode, program), 2 * 16);
        assert_eq!(std::mem::offset_of!(ShaderNode, params), 2 * 16 + 4);
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
            ("FLAG_LAST_CHUNK", FLAG_LAST_CHUNK),
            ("FLAG_ATTRIBUTES", FLAG_ATTRIBUTES),
            ("FLAG_EMISSION", FLAG_EMISSION),
            ("FLAG_COLOURS", FLAG_COLOURS),
            ("penumbra_NO_TEXTURE", textures::NO_TEXTURE),
            ("penumbra_USE_TEXELS", textures::USE_TEXELS as u32),
            (
                "penumbra_SURFACE_MAP_TEXELS",
                textures::SURFACE_MAP_TEXELS as u32,
            ),
            (
                "penumbra_ATTRIBUTE_TEXELS",
                textures::ATTRIBUTE_TEXELS as u32,
            ),
            ("penumbra_TEXTURE_SRGB", textures::TEXTURE_SRGB),
            ("penumbra_TEXTURE_MAG_LINEAR", textures::TEXTURE_MAG_LINEAR),
            ("penumbra_TEXTURE_MIN_LINEAR", textures::TEXTURE_MIN_LINEAR),
            ("penumbra_TEXTURE_MIP_SHIFT", textures::TEXTURE_MIP_SHIFT),
            (
                "penumbra_TEXTURE_WRAP_U_SHIFT",
                textures::TEXTURE_WRAP_U_SHIFT,
            ),
            (
                "penumbra_TEXTURE_WRAP_V_SHIFT",
                textures::TEXTURE_WRAP_V_SHIFT,
            ),
            ("penumbra_TEXTURE_SET_1", textures::TEXTURE_SET_1),
            ("penumbra_ALPHA_OPAQUE", textures::ALPHA_OPAQUE),
            ("penumbra_ALPHA_MASK", textures::ALPHA_MASK),
            ("penumbra_ALPHA_BLEND", textures::ALPHA_BLEND),
            ("SHADER_LEAF", SHADER_LEAF),
            ("SHADER_CHECKER", SHADER_CHECKER),
            ("LIGHT_DIRECTIONAL", LIGHT_DIRECTIONAL),
            ("LIGHT_POINT", LIGHT_POINT),
            ("LIGHT_SPOT", LIGHT_SPOT),
            ("LIGHT_RECT", LIGHT_RECT),
            ("LIGHT_SPHERE", LIGHT_SPHERE),
            ("LIGHT_ENVIRONMENT", LIGHT_ENVIRONMENT),
            ("KIND_PLANE", crate::render::trace::KIND_PLANE),
            ("KIND_SPHERE", crate::render::trace::KIND_SPHERE),
            ("KIND_TRIANGLE", crate::render::trace::KIND_TRIANGLE),
            ("UNIFORM_LIGHTS", lights::UNIFORM_LIGHTS as u32),
            (
                "PRIMS_PER_TEXEL",
                crate::render::quantised_bvh::PRIMS_PER_TEXEL as u32,
            ),
            ("TEXEL_ROW", crate::vulkan::TEXEL_ROW),
            ("RECORD_TEXELS", super::super::tiles::RECORD_TEXELS as u32),
            ("KIND_BITS", super::super::KIND_BITS),
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
            (
                "SHADER_NODE_TEXELS",
                (std::mem::size_of::<ShaderNode>() / crate::vulkan::TEXEL_BYTES) as u32,
            ),
        ];
        assert!(crate::vulkan::TEXEL_ROW.is_power_of_two());
        for size in [
            std::mem::size_of::<BvhNode>(),
            std::mem::size_of::<Triangle>(),
            std::mem::size_of::<ShaderNode>(),
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
        // The other way round: every WGSL constant of the kinds and flags the
        // host also numbers is in the list above, so a new `LIGHT_*` or
        // `KIND_*` constant cannot go unchecked.
        for (_, c) in module.constants.iter() {
            let Some(name) = c.name.as_deref() else {
                continue;
            };
            let numbered = ["LIGHT_", "KIND_", "FLAG_", "SHADER_", "PRIM_"]
                .iter()
                .any(|p| name.starts_with(p));
            let shade_only = ["KIND_NONE", "PRIM_INDEX", "SHADER_NODE_TEXELS"].contains(&name);
            assert!(
                !numbered || shade_only || shared.iter().any(|(n, _)| *n == name),
                "{name} is numbered in the WGSL but not checked against the host here"
            );
        }
        // Every primitive kind fits below the kind bits' all-ones value, so
        // that no hit's kind-and-object word is KIND_NONE (render::MAX_OBJECTS).
        let mut kinds = 0;
        for (_, c) in module.constants.iter() {
            let Some(name) = c.name.as_deref() else {
                continue;
            };
            if !name.starts_with("KIND_") || name == "KIND_NONE" || name == "KIND_BITS" {
                continue;
            }
            let naga::Expression::Literal(naga::Literal::U32(kind)) =
                module.global_expressions[c.init]
            else {
                panic!("{name} is not a u32 literal");
            };
            assert!(kind < (1 << super::super::KIND_BITS) - 1, "{name} = {kind}");
            kinds += 1;
        }
        assert_eq!(
            kinds,
            crate::render::trace::HitKind::ALL.len(),
            "one KIND_ constant per HitKind"
        );
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
