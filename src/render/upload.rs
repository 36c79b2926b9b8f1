//! Upload: a validated scene laid out for the device (records, BVH,
//! materials, textures), checked against the device's limits and bound by
//! name ([`super::bindings`]).

use std::time::{Duration, Instant};

use bytemuck::Zeroable;

use super::bindings::{BindingSet, Bindings, Bound};
use super::layout::{self, GpuScene};
use super::shade::Materials;
use super::stages::Binding;
use super::{bands, Accel, KernelOptions, RenderError, Renderer, Traversal, MAX_OBJECTS, TILE};
use crate::scene::{Features, Scene};
use crate::vulkan::BufferUsage;

/// A scene laid out and uploaded to the device, ready to render.
pub struct UploadedScene {
    /// What each binding holds (the tile's stage buffers, the image and
    /// the query buffers are placeholders, replaced per render).
    pub(super) bound: Bindings<Bound>,
    /// Tells uploads apart (hit records are reused only for the same one).
    pub(super) id: u64,
    /// The scene's shaders and texture uses, to rebuild the materials
    /// after a shader edit.
    pub(super) shaders: Vec<crate::scene::Shader>,
    pub(super) texture_uses: Vec<crate::scene::TextureRef>,
    /// [`layout::FLAG_ATTRIBUTES`] and [`layout::FLAG_EMISSION`] as the
    /// scene needs them.
    pub(super) shade_flags: u32,
    /// Bytes of textures with their mip chains on the device.
    pub(super) texture_bytes: u64,
    /// Where each texture lies in the texture texels (texture edits).
    pub(super) texture_chains: Vec<layout::textures::TextureChain>,
    /// Shade programs and parameters.
    pub(super) materials: Materials,
    /// Light samples per pixel and pass, over all lights.
    pub(super) light_samples: u32,
    /// Lights (the host uploads a placeholder for a scene without any,
    /// which no stage may count).
    pub(super) light_count: u32,
    pub(super) features: Features,
    pub(super) kernel: KernelOptions,
    /// The camera position the geometry is relative to.
    pub(super) eye: glam::DVec3,
    /// Per object: index of its first triangle (None for planes, spheres).
    pub(super) first_triangle: Vec<Option<u32>>,
    pub(super) width: u32,
    pub(super) height: u32,
    pub(super) accel_build: Duration,
    pub(super) upload: Duration,
    pub(super) bvh_nodes: usize,
    pub(super) bvh_depth: usize,
    pub(super) bvh_bytes: usize,
}

impl UploadedScene {
    /// Lights the stages loop over (the host uploads a placeholder light
    /// for a scene without any, which no stage may count).
    pub(super) fn light_count(&self) -> u32 {
        self.light_count
    }

    /// The scene's full image size.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// The kinds of primitive, light and shader the scene uses.
    pub fn features(&self) -> Features {
        self.features
    }

    /// The user's shader files the scene uses (each once), which a reload
    /// reads again ([`Renderer::reload_shaders`]).
    pub fn user_shader_files(&self) -> Vec<std::path::PathBuf> {
        let mut files: Vec<std::path::PathBuf> = Vec::new();
        for s in &self.shaders {
            if let crate::scene::Shader::Wgsl(w) = s {
                if !files.contains(&w.path) {
                    files.push(w.path.clone());
                }
            }
        }
        files
    }

    /// Time of the BVH build and of the upload.
    pub fn upload_timings(&self) -> (Duration, Duration) {
        (self.accel_build, self.upload)
    }
}

/// Refuses a scene of more than [`MAX_OBJECTS`] objects, naming the field.
pub(super) fn check_objects(n: usize) -> Result<(), RenderError> {
    if n > MAX_OBJECTS {
        return Err(RenderError::Scene {
            field: "objects".into(),
            message: format!("{n} objects, more than the {MAX_OBJECTS} a scene may have"),
        });
    }
    Ok(())
}

impl Renderer {
    /// The most triangles a scene may have on this device: its triangle
    /// records must fit a texel image of `maxImageDimension2D` rows, and its
    /// BVH primitive references one storage buffer. Loaders check this
    /// before expanding a file (`LoadOptions::max_triangles`).
    pub fn max_triangles(&self) -> u64 {
        let limits = self.context.limits();
        let texels_per_triangle =
            (std::mem::size_of::<layout::Triangle>() / crate::vulkan::TEXEL_BYTES) as u64;
        let in_image = limits.max_image_dimension_2d as u64 * crate::vulkan::TEXEL_ROW as u64
            / texels_per_triangle;
        let in_buffer = limits.max_storage_buffer_range / std::mem::size_of::<u32>() as u64;
        in_image.min(in_buffer)
    }

    /// The most bytes the scene's textures may take with their mip chains
    /// on this device: one texel image of `maxImageDimension2D` rows of
    /// [`crate::vulkan::TEXEL_ROW`] texels, within its largest allocation
    /// (and [`Renderer::set_texture_capacity`]). Loaders check each image's
    /// header against it before decoding (`LoadOptions::max_texture_bytes`).
    pub fn texture_capacity(&self) -> u64 {
        let limits = self.context.limits();
        (u64::from(crate::vulkan::TEXEL_ROW)
            * u64::from(limits.max_image_dimension_2d)
            * crate::vulkan::TEXEL_BYTES as u64)
            .min(limits.max_memory_allocation_size)
            .min(self.texture_capacity)
    }

    /// Checks the image against the device's limits and
    /// [`bands::MAX_IMAGE_BYTES`], naming the scene field. An image larger
    /// than one buffer binding is no limit: it is kept in bands of rows
    /// ([`ImageBands`]).
    /// Without `whole`, only the workgroup counts (parts check their rows).
    /// All textures share one texel image: they must fit the device's
    /// `maxImageDimension2D` rows of [`crate::vulkan::TEXEL_ROW`] texels (four
    /// texture texels each) and its largest allocation. The error names the
    /// first texture that does not fit.
    fn check_textures(&self, scene: &Scene) -> Result<(), RenderError> {
        let limits = self.context.limits();
        let capacity = self.texture_capacity();
        let mut total = 0u64;
        for (i, t) in scene.textures.iter().enumerate() {
            total += t
                .device_bytes()
                .next_multiple_of(crate::vulkan::TEXEL_BYTES as u64);
            if total > capacity {
                return Err(RenderError::Scene {
                    field: format!("textures[{i}] ({})", t.label),
                    message: format!(
                        "the scene's textures with their mip-maps need {:.1} MiB up to this one, more than the {:.1} MiB this device's texture image holds (maxImageDimension2D {} rows of {} texels, maxMemoryAllocationSize {})",
                        total as f64 / 1048576.0,
                        capacity as f64 / 1048576.0,
                        limits.max_image_dimension_2d,
                        crate::vulkan::TEXEL_ROW * 4,
                        limits.max_memory_allocation_size
                    ),
                });
            }
        }
        Ok(())
    }

    fn check_size(&self, width: u32, height: u32, whole: bool) -> Result<(), RenderError> {
        let limits = self.context.limits();
        let bytes = width as u64 * height as u64 * bands::PIXEL_BYTES;
        if whole && bytes > bands::MAX_IMAGE_BYTES {
            return Err(RenderError::Scene {
                field: "camera.width/camera.height".into(),
                message: format!(
                    "{width}x{height} pixels need a {:.0} MiB image, more than the {} MiB one render holds: render it in tiles (render --tile I/N, then penumbra merge)",
                    bytes as f64 / 1048576.0,
                    bands::MAX_IMAGE_BYTES >> 20
                ),
            });
        }
        for (field, side, max) in [
            (
                "camera.width",
                width,
                limits.max_compute_work_group_count[0],
            ),
            (
                "camera.height",
                height,
                limits.max_compute_work_group_count[1],
            ),
        ] {
            if side.div_ceil(TILE) > max {
                return Err(RenderError::Scene {
                    field: field.into(),
                    message: format!(
                        "{side} pixels exceed this device's limit of {} workgroups of {TILE}",
                        max
                    ),
                });
            }
        }
        Ok(())
    }

    /// [`Renderer::upload`] for the parts of a split render
    /// ([`RenderRequest::part`](super::RenderRequest::part)): the image may be larger than one render
    /// holds ([`bands::MAX_IMAGE_BYTES`]), since each part renders only its
    /// rows.
    pub fn upload_for_parts(&mut self, scene: &Scene) -> Result<UploadedScene, RenderError> {
        self.upload_inner(scene, false)
    }

    /// Lays out a validated scene, builds its BVH and uploads it. The result
    /// can be rendered many times, at any size up to the scene's own, and
    /// survives shader edits (see [`Renderer::render`]).
    pub fn upload(&mut self, scene: &Scene) -> Result<UploadedScene, RenderError> {
        self.upload_inner(scene, true)
    }

    fn upload_inner(&mut self, scene: &Scene, whole: bool) -> Result<UploadedScene, RenderError> {
        self.reuse_hits = false;
        let (width, height) = (scene.camera.width, scene.camera.height);
        self.check_size(width, height, whole)?;
        self.check_textures(scene)?;
        check_objects(scene.objects.len())?;
        let t0 = Instant::now();
        let mut gpu = GpuScene::new(scene);
        let materials = Materials::new(&scene.shaders, &scene.texture_uses(), &self.shaders, None)?;
        set_leaves(&mut gpu.shaders, &materials);
        let layout = t0.elapsed();
        let t_bvh = Instant::now();
        if self.kernel.accel == Accel::Bvh {
            gpu.build_bvh();
        }
        let accel_build = t_bvh.elapsed();
        let t0 = Instant::now();
        let ctx = &self.context;
        let storage = |label: &str, bytes: &[u8]| {
            ctx.create_buffer_with_data(label, BufferUsage::Storage, bytes)
                .map(Bound::Buffer)
        };
        // The kernel reads the first light before it knows whether there is
        // one (shaders/lights.wgsl, first_light): upload at least one.
        let no_light = [layout::Light::zeroed()];
        let lights = if gpu.lights.is_empty() {
            &no_light[..]
        } else {
            &gpu.lights[..]
        };
        let texels =
            |label: &str, bytes: &[u8]| ctx.create_texel_image(label, bytes).map(Bound::Image);
        let placeholder = |label: &str| {
            ctx.create_buffer(label, BufferUsage::Storage, 16)
                .map(Bound::Buffer)
        };
        let mut set = BindingSet::new();
        set.put(
            Binding::Globals,
            Bound::Buffer(ctx.create_buffer_with_data(
                "globals",
                BufferUsage::Uniform,
                bytemuck::bytes_of(&gpu.globals),
            )?),
        );
        // Primitives and lights.
        set.put(
            Binding::Planes,
            storage("planes", bytemuck::cast_slice(&gpu.planes))?,
        );
        set.put(
            Binding::Spheres,
            storage("spheres", bytemuck::cast_slice(&gpu.spheres))?,
        );
        set.put(
            Binding::Triangles,
            texels("triangles", bytemuck::cast_slice(&gpu.triangles))?,
        );
        set.put(
            Binding::VertexNormals,
            storage("vertex normals", bytemuck::cast_slice(&gpu.vertex_normals))?,
        );
        set.put(
            Binding::Lights,
            storage("lights", bytemuck::cast_slice(lights))?,
        );
        set.put(
            Binding::LightColours,
            texels(
                "light colours",
                bytemuck::cast_slice(&light_colours(lights)),
            )?,
        );
        set.put(
            Binding::LightBlock,
            Bound::Buffer(ctx.create_buffer_with_data(
                "light block",
                BufferUsage::Uniform,
                bytemuck::cast_slice(&layout::light_block(lights)),
            )?),
        );
        // The BVH.
        set.put(
            Binding::BvhNodes,
            texels("BVH nodes", bytemuck::cast_slice(&gpu.bvh_nodes))?,
        );
        set.put(
            Binding::BvhPrims,
            texels("BVH primitives", bytemuck::cast_slice(&gpu.bvh_prims))?,
        );
        // The same again as storage buffers for the packet traversal.
        let packet = self.kernel.traversal == Traversal::Packet && !gpu.bvh_nodes.is_empty();
        let (node_words, prim_words) = match packet {
            true => (
                storage("BVH node words", bytemuck::cast_slice(&gpu.bvh_nodes))?,
                storage("BVH primitive words", bytemuck::cast_slice(&gpu.bvh_prims))?,
            ),
            false => (
                placeholder("BVH node words")?,
                placeholder("BVH primitive words")?,
            ),
        };
        set.put(Binding::BvhNodeWords, node_words);
        set.put(Binding::BvhPrimWords, prim_words);
        // Shaders, their parameters, textures and surface attributes.
        set.put(
            Binding::ShaderNodes,
            texels("shaders", bytemuck::cast_slice(&gpu.shaders))?,
        );
        set.put(
            Binding::Params,
            texels("shader parameters", bytemuck::cast_slice(&materials.words))?,
        );
        set.put(
            Binding::TextureTexels,
            texels("texture texels", bytemuck::cast_slice(&gpu.textures.texels))?,
        );
        set.put(
            Binding::TextureUses,
            texels("texture uses", bytemuck::cast_slice(&gpu.textures.uses))?,
        );
        set.put(
            Binding::SurfaceMaps,
            texels(
                "surface maps",
                bytemuck::cast_slice(&gpu.textures.surface_maps),
            )?,
        );
        set.put(
            Binding::Attributes,
            texels(
                "vertex attributes",
                bytemuck::cast_slice(&gpu.textures.attributes),
            )?,
        );
        set.put(Binding::Counters, placeholder("counters")?);
        // Placeholders, replaced per render: the image and its words
        // (ImageBands), the AOVs when asked for, the tile's stage buffers
        // and their words, and the ray-query buffers (Renderer::trace).
        set.put(Binding::Image, placeholder("image")?);
        set.put(Binding::ImageWords, placeholder("image words")?);
        set.put(Binding::Aovs, placeholder("AOVs")?);
        set.put(Binding::HitRecords, texels("hit records", &[])?);
        set.put(Binding::Queue, texels("queued samples", &[])?);
        set.put(Binding::Resolved, texels("resolved materials", &[])?);
        set.put(Binding::Radiance, placeholder("colour sums")?);
        set.put(Binding::HitRecordWords, placeholder("hit record words")?);
        set.put(Binding::QueueWords, placeholder("queue words")?);
        set.put(Binding::ResolvedWords, placeholder("resolved words")?);
        set.put(Binding::QueryRays, placeholder("query rays")?);
        set.put(Binding::QueryHits, placeholder("query hits")?);
        let bound = set.complete()?;
        // The records' and references' images hold whole rows of texels
        // (brute force binds empty ones, which the BVH's memory does not
        // count).
        let image_bytes = |binding: Binding| match bound.get(binding) {
            Bound::Image(image) if !gpu.bvh_nodes.is_empty() => image.size() as usize,
            _ => 0,
        };
        // (and the packet traversal's copies as words).
        let word_bytes = match packet {
            true => {
                std::mem::size_of_val(&gpu.bvh_nodes[..])
                    + std::mem::size_of_val(&gpu.bvh_prims[..])
            }
            false => 0,
        };
        let bvh_bytes =
            image_bytes(Binding::BvhNodes) + image_bytes(Binding::BvhPrims) + word_bytes;
        // First triangle of each triangle-based object, to number AOV
        // primitives within their object.
        let mut next = 0u32;
        let first_triangle = scene
            .objects
            .iter()
            .map(|o| {
                let n = match &o.shape {
                    crate::scene::Shape::Triangle(_) => 1,
                    crate::scene::Shape::Mesh(m) => m.indices.len() as u32,
                    crate::scene::Shape::Plane(_) | crate::scene::Shape::Sphere(_) => return None,
                };
                next += n;
                Some(next - n)
            })
            .collect();
        self.uploads += 1;
        let light_samples = gpu.lights.iter().map(|l| l.samples).sum();
        Ok(UploadedScene {
            bound,
            id: self.uploads,
            shaders: scene.shaders.clone(),
            texture_uses: scene.texture_uses(),
            shade_flags: layout::shade_flags(scene),
            texture_bytes: gpu.textures.texture_bytes,
            texture_chains: gpu.textures.chains.clone(),
            materials,
            light_samples,
            light_count: gpu.lights.len() as u32,
            features: scene.features(),
            kernel: self.kernel,
            eye: scene.camera.position,
            first_triangle,
            width,
            height,
            accel_build,
            upload: layout + t0.elapsed(),
            bvh_nodes: gpu.bvh_nodes.len(),
            bvh_depth: gpu.bvh_depth,
            bvh_bytes,
        })
    }
}

/// Fills in each leaf node's program and first parameter word.
fn set_leaves(nodes: &mut [layout::ShaderNode], materials: &Materials) {
    for (node, leaf) in nodes.iter_mut().zip(&materials.leaves) {
        if let Some((program, params)) = leaf {
            node.program = *program;
            node.params = *params;
        }
    }
}

/// Each light's colours for the shade stage, three texels a light:
/// (diffuse, intensity), (specular, sample count), (ambient, environment),
/// as bits (the count as an integer: the shade stage finds each queued
/// sample's light from it; environment is 1 for the environment, whose
/// samples an occlusion texture scales, 0 for the others).
fn light_colours(lights: &[layout::Light]) -> Vec<[u32; 4]> {
    let bits = |c: [f32; 3], w: u32| [c[0].to_bits(), c[1].to_bits(), c[2].to_bits(), w];
    lights
        .iter()
        .flat_map(|l| {
            [
                bits(l.diffuse, l.intensity.to_bits()),
                bits(l.specular, l.samples),
                bits(l.ambient, u32::from(l.kind == layout::LIGHT_ENVIRONMENT)),
            ]
        })
        .collect()
}
