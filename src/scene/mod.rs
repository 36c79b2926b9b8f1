//! The scene model: plain, validated data, independent of Vulkan.
//!
//! Loaders ([`crate::loaders`]) build a [`Scene`]; the renderer only reads it.
//! Geometry is kept in `f64` so that the host can move everything into
//! camera-relative coordinates before rounding to the GPU's `f32`
//! (see [`crate::render::layout`]), which keeps far-from-origin scenes precise.

pub mod camera;
pub mod light;
pub mod primitives;
pub mod shading;
pub mod texture;
mod validate;

pub use camera::{Camera, Projection};
pub use light::{
    EnvironmentMixture, Light, LightKind, ENVIRONMENT_GRADIENT, ENVIRONMENT_MIXTURE,
    ENVIRONMENT_SAMPLES, MAX_LIGHT_SAMPLES,
};
pub use primitives::{Mesh, Plane, Sphere, Triangle};
pub use shading::{
    Checker, MetallicRoughness, MetallicRoughnessTextures, ParamField, ParamType, ParamValue,
    Phong, PhongTextures, Shader, ShaderId, SpecularGlossiness, SpecularGlossinessTextures,
    WgslShader,
};
pub use texture::{
    AlphaMode, Filter, Sampler, SurfaceMaps, Texture, TextureId, TextureRef, UvTransform, Wrap,
};
pub use validate::{Invalid, MAX_IMAGE_SIDE};

use glam::Vec3;

/// One shape of the scene.
#[derive(Clone, Debug, PartialEq)]
pub enum Shape {
    /// Infinite plane.
    Plane(Plane),
    /// Sphere.
    Sphere(Sphere),
    /// A single triangle.
    Triangle(Triangle),
    /// A triangle mesh (from glTF).
    Mesh(Mesh),
}

impl Shape {
    /// The shape's `"type"` in a JSON scene (scenes/README.md; a glTF file
    /// gives meshes): one exhaustive `match`, and [`Shape::TYPES`] lists
    /// them.
    pub fn type_name(&self) -> &'static str {
        match self {
            Shape::Plane(_) => "plane",
            Shape::Sphere(_) => "sphere",
            Shape::Triangle(_) => "triangle",
            Shape::Mesh(_) => "mesh",
        }
    }

    /// Every kind's [`Shape::type_name`], for the tests that each kind is
    /// covered (tests/cpu/kinds.rs).
    pub const TYPES: [&'static str; 4] = ["plane", "sphere", "triangle", "mesh"];
}

/// A shape with the shader that colours it.
#[derive(Clone, Debug, PartialEq)]
pub struct Object {
    /// The geometry.
    pub shape: Shape,
    /// Index into [`Scene::shaders`].
    pub shader: ShaderId,
    /// Normal map, emission and alpha of its material.
    pub maps: SurfaceMaps,
}

/// Everything needed to render one image.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// The view frustum and image size.
    pub camera: Camera,
    /// Linear RGB colour of rays that hit nothing.
    pub background: Vec3,
    /// Shading models; objects and checkers refer to them by index.
    pub shaders: Vec<Shader>,
    /// The shapes.
    pub objects: Vec<Object>,
    /// The lights.
    pub lights: Vec<Light>,
    /// Images that materials and shaders sample ([`TextureRef::texture`]
    /// and texture parameters of shader files index them).
    pub textures: Vec<Texture>,
}

/// Which kinds of primitive, light and shader a scene uses: the renderer
/// compiles a kernel with exactly these (a scene without spheres never pays
/// for sphere code).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Features {
    /// At least one infinite plane.
    pub planes: bool,
    /// At least one sphere.
    pub spheres: bool,
    /// At least one triangle (single or from a mesh).
    pub triangles: bool,
    /// Some triangle has per-vertex normals to interpolate.
    pub vertex_normals: bool,
    /// A directional light.
    pub directional_lights: bool,
    /// A point light.
    pub point_lights: bool,
    /// A spot light.
    pub spot_lights: bool,
    /// An area light (rectangle or sphere): light sampling is compiled in.
    pub area_lights: bool,
    /// A checker shader is reachable.
    pub checker: bool,
    /// Something samples a texture: primary hits compute their level of
    /// detail.
    pub textures: bool,
    /// Triangles have vertex attributes (texture coordinates, colours,
    /// tangents), or something samples a texture.
    pub attributes: bool,
    /// Some mesh has vertex colours.
    pub vertex_colours: bool,
    /// Some object emits (an emission colour or texture): the shade stage
    /// adds it.
    pub emission: bool,
    /// Some object has a normal map.
    pub normal_maps: bool,
    /// Some object is masked or blended: traversal tests alpha.
    pub alpha_tests: bool,
    /// Some triangle is single-sided: camera rays skip its back face.
    pub single_sided: bool,
}

impl Scene {
    /// Checks every invariant the renderer relies on (finite numbers, unit-able
    /// directions, valid indices, acyclic checkers...). Loaders call it last;
    /// library users who build a scene by hand should too.
    pub fn validate(&self) -> Result<(), Invalid> {
        validate::scene(self)
    }

    /// The kinds of primitive, light and shader this scene actually uses.
    pub fn features(&self) -> Features {
        let mut f = Features::default();
        for o in &self.objects {
            match &o.shape {
                Shape::Plane(_) => f.planes = true,
                Shape::Sphere(_) => f.spheres = true,
                Shape::Triangle(_) => f.triangles = true,
                Shape::Mesh(m) => {
                    if !m.indices.is_empty() {
                        f.triangles = true;
                        f.vertex_normals |= m.normals.is_some();
                    }
                }
            }
        }
        for l in &self.lights {
            match l.kind {
                LightKind::Directional { .. } => f.directional_lights = true,
                LightKind::Point { .. } => f.point_lights = true,
                LightKind::Spot { .. } => f.spot_lights = true,
                // The environment is sampled like an area light (its samples
                // have no shadow rays: distance 0).
                LightKind::Rect { .. }
                | LightKind::Sphere { .. }
                | LightKind::Environment { .. } => f.area_lights = true,
            }
            // Every area kind (LightKind::samples, an exhaustive match) needs
            // the shadow stage's area sampling code.
            f.area_lights |= l.kind.is_area();
        }
        let uses = self.texture_uses();
        f.textures = !uses.is_empty();
        f.attributes = f.textures
            || self.objects.iter().any(|o| match &o.shape {
                Shape::Mesh(m) => !m.uvs.is_empty() || m.colours.is_some() || m.tangents.is_some(),
                _ => false,
            });
        f.vertex_colours = self.objects.iter().any(|o| match &o.shape {
            Shape::Mesh(m) => m.colours.is_some(),
            _ => false,
        });
        f.emission = self
            .objects
            .iter()
            .any(|o| o.maps.emission != glam::Vec3::ZERO || o.maps.emission_texture.is_some());
        f.normal_maps = self.objects.iter().any(|o| o.maps.normal.is_some());
        f.alpha_tests = self
            .objects
            .iter()
            .any(|o| o.maps.alpha_mode != AlphaMode::Opaque);
        f.single_sided = self.objects.iter().any(|o| {
            !o.maps.double_sided && matches!(o.shape, Shape::Triangle(_) | Shape::Mesh(_))
        });
        let mut seen = vec![false; self.shaders.len()];
        let mut todo: Vec<ShaderId> = self.objects.iter().map(|o| o.shader).collect();
        while let Some(id) = todo.pop() {
            if id >= seen.len() || std::mem::replace(&mut seen[id], true) {
                continue;
            }
            match &self.shaders[id] {
                // Built-in lobes are shade pipelines of their own (shaders/shading/),
                // so no stage kernel is specialised to them.
                Shader::Phong(_)
                | Shader::BlinnPhong(_)
                | Shader::MetallicRoughness(_)
                | Shader::SpecularGlossiness(_) => {}
                Shader::Checker(c) => {
                    f.checker = true;
                    todo.extend([c.even, c.odd]);
                }
                // A WGSL file is its own pipeline, not a built-in kernel feature.
                Shader::Wgsl(_) => {}
            }
        }
        f
    }

    /// Every distinct use of a texture (texture, sampler, coordinates,
    /// transform), in a fixed order: the shaders' textures and texture
    /// parameters in shader order, then the objects' maps in object order.
    /// The GPU's table of texture uses and the index a shader file's
    /// texture parameter receives follow this order.
    pub fn texture_uses(&self) -> Vec<TextureRef> {
        let mut uses: Vec<TextureRef> = Vec::new();
        let mut add = |t: &Option<TextureRef>| {
            if let Some(t) = t {
                if !uses.contains(t) {
                    uses.push(*t);
                }
            }
        };
        for sh in &self.shaders {
            match sh {
                Shader::Phong(p) | Shader::BlinnPhong(p) => {
                    add(&p.textures.ambient);
                    add(&p.textures.diffuse);
                    add(&p.textures.specular);
                }
                Shader::MetallicRoughness(m) => {
                    add(&m.textures.base_colour);
                    add(&m.textures.metallic_roughness);
                }
                Shader::SpecularGlossiness(m) => {
                    add(&m.textures.diffuse);
                    add(&m.textures.specular_glossiness);
                }
                Shader::Wgsl(w) => {
                    for v in &w.values {
                        if let ParamValue::Texture(t) = v {
                            add(&Some(*t));
                        }
                    }
                }
                Shader::Checker(_) => {}
            }
        }
        for o in &self.objects {
            add(&o.maps.normal.map(|(t, _)| t));
            add(&o.maps.emission_texture);
            add(&o.maps.opacity_texture);
        }
        uses
    }

    /// Index of `t` in [`Scene::texture_uses`] (`u32::MAX` if absent).
    pub fn texture_use_index(uses: &[TextureRef], t: &TextureRef) -> u32 {
        uses.iter()
            .position(|u| u == t)
            .map_or(u32::MAX, |i| i as u32)
    }

    /// Number of triangles over all single triangles and meshes.
    pub fn triangle_count(&self) -> usize {
        self.objects
            .iter()
            .map(|o| match &o.shape {
                Shape::Triangle(_) => 1,
                Shape::Mesh(m) => m.indices.len(),
                Shape::Plane(_) | Shape::Sphere(_) => 0,
            })
            .sum()
    }
}
