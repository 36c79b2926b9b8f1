//! Ray queries: trace arbitrary rays through an uploaded scene on the GPU
//! with exactly the render kernel's intersection code, and report the
//! nearest hit. Tests use it to probe the hard cases (shared edges, grazing
//! and degenerate triangles) ray by ray.

use bytemuck::Zeroable;
use glam::DVec3;

use super::layout::{PushConstants, QueryHit, QueryRay};
use super::stages::{Binding, Stage};
use super::{RenderError, Renderer, UploadedScene};
use crate::vulkan::BufferUsage;

/// Rays per dispatch: 64 per workgroup, within every device's 65,535
/// workgroups.
const RAYS_PER_DISPATCH: usize = 64 * 65_535;

/// A ray in world space. `dir` must have unit length (it is rounded to
/// `f32` as given, so tests can pass exact bit patterns).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TraceRay {
    /// Origin, world units.
    pub origin: DVec3,
    /// Unit direction.
    pub dir: DVec3,
}

/// Which kind of primitive a ray hit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HitKind {
    /// An infinite plane.
    Plane,
    /// A sphere.
    Sphere,
    /// A triangle (single or from a mesh).
    Triangle,
}

/// A hit record's kind of primitive, as `shaders/stages/records.wgsl`
/// numbers them (checked by `layout::tests::shared_constants_match_wgsl`).
pub const KIND_PLANE: u32 = 0;
/// See [`KIND_PLANE`].
pub const KIND_SPHERE: u32 = 1;
/// See [`KIND_PLANE`].
pub const KIND_TRIANGLE: u32 = 2;

impl HitKind {
    /// Every kind (`layout::tests` checks that the WGSL has as many).
    pub const ALL: [HitKind; 3] = [HitKind::Plane, HitKind::Sphere, HitKind::Triangle];

    /// The kind's number in a hit record: one exhaustive `match`.
    pub fn code(self) -> u32 {
        match self {
            HitKind::Plane => KIND_PLANE,
            HitKind::Sphere => KIND_SPHERE,
            HitKind::Triangle => KIND_TRIANGLE,
        }
    }

    /// The kind numbered `code`; `None` for no hit or an unknown number.
    pub fn from_code(code: u32) -> Option<HitKind> {
        HitKind::ALL.into_iter().find(|k| k.code() == code)
    }
}

/// The nearest hit of a traced ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TraceHit {
    /// Distance along the ray.
    pub t: f32,
    /// Primitive kind.
    pub kind: HitKind,
    /// Index among the primitives of that kind, in scene order (triangles
    /// of meshes follow their objects).
    pub index: u32,
    /// Barycentric u of a triangle hit.
    pub u: f32,
    /// Barycentric v of a triangle hit.
    pub v: f32,
}

impl Renderer {
    /// Traces `rays` through `scene` and returns each one's nearest hit.
    /// Origins are made relative to the scene's camera in `f64` first, like
    /// all geometry.
    pub fn trace(
        &mut self,
        scene: &UploadedScene,
        rays: &[TraceRay],
    ) -> Result<Vec<Option<TraceHit>>, RenderError> {
        let kernel = super::StageKernel {
            features: scene.features,
            settings: super::Settings::default(),
            options: super::KernelOptions {
                accel: scene.kernel.accel,
                traversal: scene.kernel.traversal,
                ..self.kernel
            },
        };
        self.stage_pipeline(Stage::Trace, kernel, false)?;
        let pipeline = &self.stage_pipelines[&(Stage::Trace, kernel)].pipeline;
        let ctx = &self.context;
        let mut out = Vec::with_capacity(rays.len());
        for chunk in rays.chunks(RAYS_PER_DISPATCH) {
            let query: Vec<QueryRay> = chunk
                .iter()
                .map(|r| QueryRay {
                    origin: (r.origin - scene.eye).as_vec3().to_array(),
                    dir: r.dir.as_vec3().to_array(),
                    ..Zeroable::zeroed()
                })
                .collect();
            let ray_buf = ctx.create_buffer_with_data(
                "query rays",
                BufferUsage::Storage,
                bytemuck::cast_slice(&query),
            )?;
            let hit_buf = ctx.create_buffer(
                "query hits",
                BufferUsage::Storage,
                (chunk.len() * 32) as u64,
            )?;
            let mut refs = scene.bound.resources();
            refs.set(Binding::QueryRays, (&ray_buf).into());
            refs.set(Binding::QueryHits, (&hit_buf).into());
            let push = PushConstants {
                size: [chunk.len() as u32, 1],
                ..Zeroable::zeroed()
            };
            let groups = [chunk.len().div_ceil(64) as u32, 1, 1];
            ctx.dispatch(
                pipeline,
                refs.in_binding_order(),
                bytemuck::bytes_of(&push),
                groups,
            )?;
            let bytes = ctx.read_buffer(&hit_buf)?;
            let hits: Vec<QueryHit> = bytemuck::pod_collect_to_vec(&bytes[..chunk.len() * 32]);
            out.extend(hits.iter().map(|h| {
                let kind = HitKind::from_code(h.kind).filter(|_| h.t >= 0.0)?;
                Some(TraceHit {
                    t: h.t,
                    kind,
                    index: h.index,
                    u: h.u,
                    v: h.v,
                })
            }));
        }
        ctx.check_validation()?;
        Ok(out)
    }
}
