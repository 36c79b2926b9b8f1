//! The tables that host and shaders share: the shader files (with their
//! embedded copies), the stages of a frame with the files each is compiled
//! from, and the bindings of set 0.
//!
//! A frame runs as a chain of compute pipelines, after the wavefront design of
//! pbrt-v4's GPU integrator (Laine, Karras and Aila, "Megakernels Considered
//! Harmful", HPG 2013): camera rays and closest hit write hit records and
//! resolve each hit's material (checkers pick the leaf shader), the shadow
//! stage samples the lights and traces each sample's shadow ray, and one
//! shade pipeline per shader file sums the contributions of the samples that
//! reach the point and writes the image. When one chunk holds every light
//! sample of a pixel, the hit stage traces the shadow rays itself, from the
//! hit in its registers, and the shadow stage does not run ([`Stage::frame`]).
//! Each stage is compiled from only the files it needs, so an edit
//! recompiles only the stages that include the edited file.

use super::compile::Settings;
use crate::vulkan::BindingType;

/// Declares the shader file table: each name next to its `include_str!`, so
/// the list and the embedded copies cannot disagree.
macro_rules! shader_files {
    ($($name:literal),* $(,)?) => {
        /// Every file under `shaders/`, with the copy built into the binary
        /// (an installed `penumbra` needs no source tree).
        pub const SHADER_FILES: &[(&str, &str)] = &[
            $(($name, include_str!(concat!("../../shaders/", $name)))),*
        ];
    };
}

shader_files![
    "render.wgsl",
    "texels.wgsl",
    "camera.wgsl",
    "ray.wgsl",
    "hit.wgsl",
    "primitives/plane.wgsl",
    "primitives/sphere.wgsl",
    "primitives/triangle.wgsl",
    "lights.wgsl",
    "environment.wgsl",
    "shading/shader.wgsl",
    "shading/checker.wgsl",
    "shadows.wgsl",
    "bvh.wgsl",
    "sampling.wgsl",
    "queries.wgsl",
    "aov.wgsl",
    "stages/records.wgsl",
    "stages/hit.wgsl",
    "stages/resolve.wgsl",
    "stages/shadow.wgsl",
    "stages/shade.wgsl",
    "shading/interface.wgsl",
    "shading/phong.wgsl",
    "shading/blinn_phong.wgsl",
    "shading/metallic_roughness.wgsl",
    "shading/specular_glossiness.wgsl",
    "textures.wgsl",
    "attributes.wgsl",
    "surface_maps.wgsl",
    "surface.wgsl",
    "alpha.wgsl",
];

/// The embedded copy of shader file `name` (a name of [`SHADER_FILES`]).
pub fn embedded(name: &str) -> Option<&'static str> {
    SHADER_FILES
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(_, text)| *text)
}

/// Files every engine stage is compiled with.
const BASE: &[&str] = &[
    "render.wgsl",
    "camera.wgsl",
    "ray.wgsl",
    "texels.wgsl",
    "stages/records.wgsl",
];

/// Files of closest-hit and any-hit traversal (the BVH walks both).
const TRAVERSAL: &[&str] = &[
    "textures.wgsl",
    "attributes.wgsl",
    "surface_maps.wgsl",
    "surface.wgsl",
    "alpha.wgsl",
    "sampling.wgsl",
    "hit.wgsl",
    "primitives/plane.wgsl",
    "primitives/sphere.wgsl",
    "primitives/triangle.wgsl",
    "bvh.wgsl",
    "shadows.wgsl",
];

/// The engine's stages (the shade stage is per shader file: [`super::shade`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Stage {
    /// Camera rays and closest hit: writes the hit records, each hit's
    /// resolved material (checkers select the leaf shader), the background
    /// of the pixels that hit nothing, and the AOVs.
    Hit,
    /// Light sampling and the any-hit traversal of each sample's shadow
    /// ray: queues the samples that reach the point.
    Shadow,
    /// Ray queries (tests and tools): the closest hit of given rays.
    Trace,
}

impl Stage {
    /// Every engine stage a frame may run, in order (the shade pipelines run
    /// after them, once per chunk of light samples).
    pub const FRAME: [Stage; 2] = [Stage::Hit, Stage::Shadow];

    /// The engine stages a frame with `settings` runs, in order: without the
    /// shadow stage when the hit stage traces the shadow rays
    /// ([`Settings::fused_shadows`]).
    pub fn frame(settings: &Settings) -> &'static [Stage] {
        match settings.fused_shadows {
            true => &Stage::FRAME[..1],
            false => &Stage::FRAME,
        }
    }

    /// The stage's name in reload reports.
    pub fn name(self) -> &'static str {
        match self {
            Stage::Hit => "hit",
            Stage::Shadow => "shadow",
            Stage::Trace => "trace",
        }
    }

    /// The WGSL entry point.
    pub fn entry_point(self) -> &'static str {
        match self {
            Stage::Hit => "hit_stage",
            Stage::Shadow => "shadow_stage",
            Stage::Trace => "trace",
        }
    }

    /// The files the stage is compiled from, in order.
    pub fn files(self) -> Vec<&'static str> {
        let own: &[&str] = match self {
            Stage::Hit => &[
                "aov.wgsl",
                "shading/shader.wgsl",
                "shading/checker.wgsl",
                "stages/resolve.wgsl",
                "lights.wgsl",
                "environment.wgsl",
                "stages/shadow.wgsl",
                "stages/hit.wgsl",
            ],
            Stage::Shadow => &["lights.wgsl", "environment.wgsl", "stages/shadow.wgsl"],
            Stage::Trace => &["queries.wgsl"],
        };
        let traversal = matches!(self, Stage::Hit | Stage::Shadow | Stage::Trace);
        let mut files = BASE.to_vec();
        if traversal {
            files.extend_from_slice(TRAVERSAL);
        }
        files.extend_from_slice(own);
        files
    }
}

/// The files of every engine stage, each once, in [`SHADER_FILES`] order:
/// one module with all the engine's declarations (layout tests, tools).
pub fn engine_files() -> Vec<&'static str> {
    let all: Vec<&str> = [Stage::Trace]
        .into_iter()
        .chain(Stage::FRAME)
        .flat_map(Stage::files)
        .collect();
    SHADER_FILES
        .iter()
        .map(|(n, _)| *n)
        .filter(|n| all.contains(n))
        .collect()
}

/// The files a shade pipeline is compiled with, before the shader file
/// itself and the generated parameter loader ([`super::shade`]).
pub const SHADE_PRELUDE: &[&str] = &[
    "textures.wgsl",
    "attributes.wgsl",
    "surface_maps.wgsl",
    "shading/interface.wgsl",
    "stages/shade.wgsl",
];

/// The bindings of set 0: what each holds, the name the engine's WGSL gives
/// it (the shade stage's are prefixed `penumbra_`), and its type. Every
/// pipeline's layout has all of them; a stage declares those it uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Binding {
    /// `Globals`: camera, background, counts.
    Globals = 0,
    /// Infinite planes.
    Planes,
    /// Spheres.
    Spheres,
    /// Triangle records (texel image).
    Triangles,
    /// Per-vertex normals.
    VertexNormals,
    /// Lights.
    Lights,
    /// The shader table (leaves and checkers; texel image).
    ShaderNodes,
    /// The accumulated image (or the band of it that a dispatch writes).
    Image,
    /// Ray counters.
    Counters,
    /// BVH records (texel image).
    BvhNodes,
    /// BVH primitive references.
    BvhPrims,
    /// Rays of a ray query.
    QueryRays,
    /// Hits of a ray query.
    QueryHits,
    /// Arbitrary output variables.
    Aovs,
    /// The tile's hit records (texels: `shaders/stages/records.wgsl`).
    HitRecords,
    /// The tile's queued light samples (texels).
    Queue,
    /// Material resolve's result per record (texels).
    Resolved,
    /// The tile's per-pixel colour sums.
    Radiance,
    /// Every leaf shader's parameter words (texels).
    Params,
    /// Each light's colours and intensity for the shade stage (texels).
    LightColours,
    /// Every texture's mip chain, packed RGBA8 (texels).
    TextureTexels,
    /// The texture uses: texture, sampler, coordinates, transform (texels).
    TextureUses,
    /// Each object's normal map, emission and alpha (texels).
    SurfaceMaps,
    /// Each triangle's texture coordinates, colours and tangents (texels).
    Attributes,
    /// The hit records' memory as a storage buffer, for the stage that
    /// writes them ([`super::Settings::stage_words`]; a placeholder otherwise).
    HitRecordWords,
    /// The queue's memory as a storage buffer.
    QueueWords,
    /// The resolved materials' memory as a storage buffer.
    ResolvedWords,
    /// The image again (the same buffer as [`Binding::Image`]), which the
    /// shade stage stores its colours into as 64-bit words where the stages
    /// write words ([`super::Settings::stage_words`]).
    ImageWords,
    /// The first lights again, as a uniform buffer (`shaders/lights.wgsl`:
    /// `light_at`).
    LightBlock,
    /// The BVH records again, as a storage buffer, for the packet traversal
    /// (`KernelOptions::traversal`; a placeholder otherwise): loaded at a
    /// subgroup-uniform index, once for the subgroup.
    BvhNodeWords,
    /// The BVH primitive references again, as a storage buffer, for the
    /// packet traversal.
    BvhPrimWords,
}

/// One binding: its WGSL variable and descriptor type.
#[derive(Clone, Copy, Debug)]
pub struct BindingInfo {
    /// Which binding (its number is `binding as u32`).
    pub binding: Binding,
    /// The variable the engine's WGSL declares there.
    pub name: &'static str,
    /// The descriptor type.
    pub ty: BindingType,
}

const fn b(binding: Binding, name: &'static str, ty: BindingType) -> BindingInfo {
    BindingInfo { binding, name, ty }
}

/// Set 0, in binding order.
pub const BINDINGS: [BindingInfo; 31] = {
    use BindingType::*;
    [
        b(Binding::Globals, "globals", Uniform),
        b(Binding::Planes, "planes", StorageReadOnly),
        b(Binding::Spheres, "spheres", StorageReadOnly),
        b(Binding::Triangles, "triangles", TexelImage),
        b(Binding::VertexNormals, "vertex_normals", StorageReadOnly),
        b(Binding::Lights, "lights", StorageReadOnly),
        b(Binding::ShaderNodes, "shader_nodes", TexelImage),
        b(Binding::Image, "image", StorageReadWrite),
        b(Binding::Counters, "counters", StorageReadWrite),
        b(Binding::BvhNodes, "bvh_nodes", TexelImage),
        b(Binding::BvhPrims, "bvh_prims", TexelImage),
        b(Binding::QueryRays, "query_rays", StorageReadOnly),
        b(Binding::QueryHits, "query_hits", StorageReadWrite),
        b(Binding::Aovs, "aovs", StorageReadWrite),
        b(Binding::HitRecords, "hit_records", StageImage),
        b(Binding::Queue, "queue", StageImage),
        b(Binding::Resolved, "resolved", StageImage),
        b(Binding::Radiance, "radiance", StorageReadWrite),
        b(Binding::Params, "params", TexelImage),
        b(Binding::LightColours, "light_colours", TexelImage),
        b(
            Binding::TextureTexels,
            "penumbra_texture_texels",
            TexelImage,
        ),
        b(Binding::TextureUses, "penumbra_texture_uses", TexelImage),
        b(Binding::SurfaceMaps, "penumbra_surface_maps", TexelImage),
        b(Binding::Attributes, "penumbra_attributes", TexelImage),
        b(
            Binding::HitRecordWords,
            "hit_record_words",
            StorageReadWrite,
        ),
        b(Binding::QueueWords, "queue_words", StorageReadWrite),
        b(Binding::ResolvedWords, "resolved_words", StorageReadWrite),
        b(Binding::ImageWords, "image_words", StorageReadWrite),
        b(Binding::LightBlock, "light_block", Uniform),
        b(Binding::BvhNodeWords, "bvh_node_words", StorageReadOnly),
        b(Binding::BvhPrimWords, "bvh_prim_words", StorageReadOnly),
    ]
};

/// The descriptor types of [`BINDINGS`], for pipeline creation.
pub fn binding_types() -> Vec<BindingType> {
    BINDINGS.iter().map(|b| b.ty).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bindings_are_numbered_in_order() {
        for (i, b) in BINDINGS.iter().enumerate() {
            assert_eq!(b.binding as usize, i, "{}", b.name);
        }
    }

    #[test]
    fn every_shader_file_is_in_the_table_and_every_stage_file_exists() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders");
        let mut on_disk = Vec::new();
        let mut todo = vec![dir.clone()];
        while let Some(d) = todo.pop() {
            for e in std::fs::read_dir(d).unwrap() {
                let p = e.unwrap().path();
                if p.is_dir() {
                    todo.push(p);
                } else if p.extension().is_some_and(|x| x == "wgsl") {
                    let rel = p.strip_prefix(&dir).unwrap().to_string_lossy();
                    on_disk.push(rel.replace('\\', "/"));
                }
            }
        }
        on_disk.sort();
        let mut table: Vec<String> = SHADER_FILES.iter().map(|(n, _)| n.to_string()).collect();
        table.sort();
        assert_eq!(on_disk, table);
        for stage in [Stage::Trace].into_iter().chain(Stage::FRAME) {
            for f in stage.files() {
                assert!(embedded(f).is_some(), "{stage:?}: {f}");
            }
        }
        for f in SHADE_PRELUDE {
            assert!(embedded(f).is_some(), "{f}");
        }
    }
}
