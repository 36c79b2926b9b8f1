//! The `f64` CPU reference renderer: the ground truth for every error figure.
//!
//! It renders the scene model ([`crate::scene`]) directly, in world
//! coordinates and `f64`, with exactly the semantics of the compute kernel in
//! `shaders/` — the same primary rays (pixel centres, or the jitter of pass
//! `p` when there are several samples per pixel), closest hit over planes,
//! spheres and triangles, two-sided normals, nested checkers with the same
//! inset, the same light loop (ambient once per light, then per light sample
//! the shadow ray and the Phong or Blinn-Phong lobe), the same shadow rules
//! and, through a bit-exact port of `shaders/sampling.wgsl`, the same sample
//! points. The image is the mean of `spp` passes. Rows are rendered in
//! parallel with rayon; a BVH ([`crate::bvh`]) only speeds the search up.
//! It is not a product path: it is written to be obviously right, not fast.
//!
//! The files follow the concepts of `shaders/`: [`camera`], [`intersect`] (ray,
//! plane, sphere, triangle), [`bvh`], [`hit`], [`lights`], [`shading`],
//! [`shadows`], [`sampling`], and for textures [`texture`] (sampling, level
//! of detail, uv conventions) and [`surface`] (a point's uv, colour and
//! tangent, and the alpha tests of traversal). A scene without textures,
//! vertex colours or surface maps takes none of those paths: its results
//! are bit for bit what they were before textures.
//!
//! # Why it can still differ from the GPU
//!
//! The GPU rounds everything to `f32` (relative precision 2⁻²⁴ ≈ 6·10⁻⁸):
//! vertices and light positions (camera-relative, after an `f64`
//! subtraction), the camera's frustum vectors, colours times intensities,
//! every intermediate of the ray, hit and shading arithmetic. A smooth pixel
//! therefore differs by a few dozen roundings of quantities of order 1, about
//! 10⁻⁶, far below 1/255. Where a decision flips — a primary ray within
//! rounding of a silhouette or triangle edge, a shadow ray within rounding of
//! an occluder's edge, a point within rounding of a checker boundary, or
//! rays a different triangle test or offset treats differently (the GPU's
//! shadow-ray offset is 256 `f32` ulps, this one 2⁻³² relative: see
//! [`shadows`]) — the two can differ by a whole colour step on that pixel.
//! Such pixels are few, and they sit on edges.
//!
//! Of the GPU's kernel options only the [`Sampler`] applies here: it decides
//! where samples go. The other options choose how the GPU approximates this same image
//! (BVH or brute force, the triangle test, the shadow-ray offset); the
//! reference always computes the exact version (watertight test in `f64`,
//! robust shadow rays), which is what they are measured against.
//!
//! Textures add decisions of the same kind: a `Nearest` lookup within
//! rounding of a texel edge, a level of detail within rounding of a
//! `Nearest` mip switch (λ = k + ½), an alpha within rounding of its
//! `Mask` cutoff or its `Blend` threshold. Filtered values themselves
//! differ only by the GPU's arithmetic (`f32`, and the fixed-point filter
//! weights of a hardware sampler where one is used).

mod aov;
pub mod bvh;
pub mod camera;
pub mod environment;
pub mod hit;
pub mod intersect;
pub mod lights;
pub mod sampling;
pub mod shading;
pub mod shadows;
pub mod surface;
pub mod texture;

use std::time::Instant;

use glam::DVec3;
use rayon::prelude::*;

use crate::frame::{Aovs, Frame, Image, RenderStats, Sampler, Sampling, Timings};
use crate::scene::{Scene, Shader, Shape};

/// A plane: a point on it and its unit normal.
#[derive(Clone, Copy, Debug)]
pub struct Plane {
    /// Any point of the plane.
    pub point: DVec3,
    /// Unit normal.
    pub normal: DVec3,
    /// Index into the scene's shaders.
    pub shader: u32,
}

/// A sphere.
#[derive(Clone, Copy, Debug)]
pub struct Sphere {
    /// Centre.
    pub center: DVec3,
    /// Radius.
    pub radius: f64,
    /// Index into the scene's shaders.
    pub shader: u32,
}

/// A scene prepared for the reference: flat primitive lists, lights in the
/// form the shader sees them, and the BVH.
pub struct World {
    camera: camera::Camera,
    background: DVec3,
    planes: Vec<Plane>,
    spheres: Vec<Sphere>,
    triangles: Vec<intersect::Triangle>,
    vertex_normals: Vec<[DVec3; 3]>,
    lights: Vec<lights::Light>,
    shaders: Vec<Shader>,
    accel: bvh::Accel,
    sampler: Sampler,
    seed: u32,
    /// Each texture's mip chain, built once here.
    textures: Vec<texture::Mips>,
    /// Per scene object: maps and mesh attributes.
    objects: Vec<surface::ObjectInfo>,
    /// The object of each plane, sphere and triangle.
    plane_objects: Vec<u32>,
    sphere_objects: Vec<u32>,
    triangle_objects: Vec<u32>,
    /// Some texture, vertex colour or surface map is in use: hits carry a
    /// [`surface::Surface`]. Otherwise shading is exactly as without
    /// textures.
    textured: bool,
    /// Some object is `Mask` or `Blend`: traversal tests alpha.
    alpha: bool,
    /// What one pixel spans: an angle (perspective) or a world height
    /// (orthographic), for the ray cone ([`texture::cone_width`]).
    pixel_spread: f64,
    orthographic: bool,
    /// The environment's samples cast shadow rays ([`environment::Options`]).
    shadowed_environment: bool,
}

impl World {
    /// Prepares a validated scene for rendering with `sampler` and `seed`.
    pub fn new(scene: &Scene, sampler: Sampler, seed: u32) -> World {
        let mut planes = Vec::new();
        let mut spheres = Vec::new();
        let mut triangles = Vec::new();
        let mut vertex_normals = Vec::new();
        let textured = !scene.textures.is_empty()
            || scene.objects.iter().any(|o| {
                !o.maps.is_none() || matches!(&o.shape, Shape::Mesh(m) if m.colours.is_some())
            });
        let (mut objects, mut plane_objects, mut sphere_objects, mut triangle_objects) =
            (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for (oi, o) in scene.objects.iter().enumerate() {
            let shader = o.shader as u32;
            objects.push(surface::ObjectInfo {
                maps: o.maps,
                first_triangle: triangles.len() as u32,
                mesh: match &o.shape {
                    Shape::Mesh(m) if textured => Some(surface::MeshAttributes::new(m)),
                    _ => None,
                },
            });
            match &o.shape {
                Shape::Plane(_) => plane_objects.push(oi as u32),
                Shape::Sphere(_) => sphere_objects.push(oi as u32),
                Shape::Triangle(_) => triangle_objects.push(oi as u32),
                Shape::Mesh(m) => {
                    triangle_objects.extend(std::iter::repeat_n(oi as u32, m.indices.len()))
                }
            }
            match &o.shape {
                Shape::Plane(p) => planes.push(Plane {
                    point: p.point,
                    normal: p.normal,
                    shader,
                }),
                Shape::Sphere(s) => spheres.push(Sphere {
                    center: s.center,
                    radius: s.radius,
                    shader,
                }),
                Shape::Triangle(t) => {
                    triangles.push(intersect::Triangle::new(t.vertices, shader, None))
                }
                Shape::Mesh(m) => {
                    for (i, idx) in m.indices.iter().enumerate() {
                        let normals = m.normals.as_ref().map(|n| {
                            vertex_normals.push(idx.map(|k| n[k as usize]));
                            vertex_normals.len() as u32 - 1
                        });
                        triangles.push(intersect::Triangle::new(
                            m.triangle(i).vertices,
                            shader,
                            normals,
                        ));
                    }
                }
            }
        }
        let accel = bvh::Accel::build(&triangles, &spheres);
        let cam = &scene.camera;
        World {
            textures: scene.textures.iter().map(texture::Mips::new).collect(),
            objects,
            plane_objects,
            sphere_objects,
            triangle_objects,
            textured,
            alpha: scene
                .objects
                .iter()
                .any(|o| o.maps.alpha_mode != crate::scene::AlphaMode::Opaque),
            pixel_spread: 2.0 * cam.half_extent().1 / f64::from(cam.height),
            orthographic: matches!(
                cam.projection,
                crate::scene::Projection::Orthographic { .. }
            ),
            camera: camera::Camera::new(&scene.camera),
            background: scene.background.as_dvec3(),
            planes,
            spheres,
            triangles,
            vertex_normals,
            lights: scene.lights.iter().map(lights::Light::new).collect(),
            shaders: scene.shaders.clone(),
            accel,
            sampler,
            seed,
            shadowed_environment: false,
        }
    }

    /// Draws the environment's samples as `options` say.
    pub fn set_environment(&mut self, options: &environment::Options) {
        for l in &mut self.lights {
            if let lights::Kind::Environment { mixture, .. } = &mut l.kind {
                *mixture = options.mixture;
            }
        }
        self.shadowed_environment = options.shadowed;
    }

    /// The closest hit of `ray` (for tests and tools), taken as a camera
    /// ray of pixel 0 in pass 0 (its `Blend` decisions and level of detail).
    pub fn closest_hit(&self, ray: &intersect::Ray) -> Option<hit::Hit> {
        hit::closest_hit(self, ray, surface::AlphaRay::camera(0, 0))
    }

    /// Colour and alpha of one sample of pixel (`x`, `y`) of a
    /// `width`×`height` image in pass `pass` (`render` in
    /// `shaders/render.wgsl`); `jitter` places the sample by stream 0 instead
    /// of the pixel centre. Adds the shadow rays cast to `shadow_rays`.
    #[allow(clippy::too_many_arguments)]
    pub fn sample(
        &self,
        x: u32,
        y: u32,
        width: u32,
        height: u32,
        pass: u32,
        jitter: bool,
        shadow_rays: &mut u64,
    ) -> [f64; 4] {
        let pixel = y.wrapping_mul(width).wrapping_add(x);
        let sub = if jitter {
            sampling::sample_2d(self.sampler, self.seed, pixel, 0, pass)
        } else {
            [0.5, 0.5]
        };
        let ray = self.camera.primary_ray(x, y, width, height, sub);
        match hit::closest_hit(self, &ray, surface::AlphaRay::camera(pixel, pass)) {
            Some(h) => {
                let c = shading::shade(self, &ray, &h, pixel, pass, shadow_rays);
                [c.x, c.y, c.z, 1.0]
            }
            None => [self.background.x, self.background.y, self.background.z, 0.0],
        }
    }
}

/// Whether the reference can render `scene`: it runs only the built-in
/// shaders, so a scene whose objects reach a WGSL shader (directly or through
/// a checker) is refused with a message naming that shader and its file.
pub fn supports(scene: &Scene) -> Result<(), String> {
    let mut seen = vec![false; scene.shaders.len()];
    let mut todo: Vec<usize> = scene.objects.iter().map(|o| o.shader).collect();
    while let Some(id) = todo.pop() {
        if id >= seen.len() || std::mem::replace(&mut seen[id], true) {
            continue;
        }
        match &scene.shaders[id] {
            Shader::Checker(c) => todo.extend([c.even, c.odd]),
            Shader::Wgsl(w) => {
                return Err(format!(
                    "the f64 reference renders only the built-in shaders (phong, blinn_phong, metallic_roughness, checker); shader `shaders[{id}]` is a WGSL file ({})",
                    w.path.display()
                ))
            }
            Shader::Phong(_)
            | Shader::BlinnPhong(_)
            | Shader::MetallicRoughness(_)
            | Shader::SpecularGlossiness(_) => {}
        }
    }
    Ok(())
}

/// Renders a validated scene at its camera's size: the mean of
/// `sampling.spp` passes (fewer if `sampling.time_budget` runs out, checked
/// after each pass as on the GPU), each one sample per pixel, rows in
/// parallel, samples placed by `sampler` (see the module docs).
///
/// The stats count rays as the GPU does (one primary ray per pixel and pass,
/// one shadow ray per light sample that faces the surface and has a non-zero
/// falloff); `timings.accel_build` is the preparation (BVH build),
/// `timings.render` the wall time of the passes; `bvh_bytes` is 0.
///
/// # Panics
///
/// If `sampling.spp` is not in `1..=MAX_SPP` ([`Sampling::check`]) (the command line rejects such
/// values before), or if the scene uses a WGSL shader ([`supports`], which
/// the command line checks before).
pub fn render(scene: &Scene, sampling: &Sampling, sampler: Sampler) -> Frame {
    render_with_environment(scene, sampling, sampler, &environment::Options::default())
}

/// [`render`], with the environment's samples drawn and traced as
/// `options` say (for measurements; [`render`] is the GPU's estimator).
///
/// # Panics
///
/// As [`render`].
pub fn render_with_environment(
    scene: &Scene,
    sampling: &Sampling,
    sampler: Sampler,
    options: &environment::Options,
) -> Frame {
    if let Err(why) = sampling.check() {
        panic!("spp {why}");
    }
    if let Err(why) = supports(scene) {
        panic!("{why}");
    }
    let t0 = Instant::now();
    let mut world = World::new(scene, sampler, sampling.seed);
    world.set_environment(options);
    let accel_build = t0.elapsed();
    let (width, height) = (scene.camera.width, scene.camera.height);
    let jitter = sampling.spp > 1;
    let mut sum = vec![[0.0f64; 4]; width as usize * height as usize];
    let mut shadow_rays = 0u64;
    let mut passes = 0u32;
    let start = Instant::now();
    while passes < sampling.spp {
        let pass = passes;
        shadow_rays += sum
            .par_chunks_mut(width as usize)
            .enumerate()
            .map(|(y, row)| {
                let mut rays = 0u64;
                for (x, acc) in row.iter_mut().enumerate() {
                    let s =
                        world.sample(x as u32, y as u32, width, height, pass, jitter, &mut rays);
                    for (a, c) in acc.iter_mut().zip(s) {
                        *a += c;
                    }
                }
                rays
            })
            .sum::<u64>();
        passes += 1;
        if sampling.time_budget.is_some_and(|b| start.elapsed() >= b) {
            break;
        }
    }
    let render = start.elapsed();
    let inv = 1.0 / passes as f64;
    let pixels = sum.iter().map(|p| p.map(|c| (c * inv) as f32)).collect();
    Frame {
        stage_times: Vec::new(),
        driver_compiles: Vec::new(),
        image: Image {
            width,
            height,
            pixels,
        },
        stats: RenderStats {
            primary_rays: width as u64 * height as u64 * passes as u64,
            shadow_rays,
            passes,
            bvh_nodes: world.accel.node_count(),
            bvh_depth: world.accel.depth,
            bvh_bytes: 0,
            texture_bytes: 0,
            timings: Timings {
                accel_build,
                render,
                ..Timings::default()
            },
            ..RenderStats::default()
        },
    }
}

/// [`render`], plus the arbitrary output variables (depth, normal, uv, ids)
/// of each pixel's first primary ray, numbered like the GPU's.
pub fn render_with_aovs(scene: &Scene, sampling: &Sampling, sampler: Sampler) -> (Frame, Aovs) {
    let frame = render(scene, sampling, sampler);
    let world = World::new(scene, sampler, sampling.seed);
    (frame, aov::aovs(&world, scene, sampling))
}
