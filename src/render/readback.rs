//! The end of a frame: the image (and AOVs) read back band by band, the
//! mean of the passes, the stage buffers kept for the next render, and the
//! frame's statistics.

use std::time::{Duration, Instant};

use super::frame_plan::FramePlan;
use super::layout;
use super::passes::{slot_names, PassTotals};
use super::{
    Aovs, Frame, Image, RenderError, RenderStats, Rendered, Renderer, Timings, UploadedScene,
};
use crate::vulkan::Buffer;

impl Renderer {
    /// Reads the image of `plan`'s bands back (the mean of the passes,
    /// except for a part, whose image is their sum), keeps the stage buffers'
    /// image and hits for the next render, and gives the frame with its
    /// statistics.
    pub(super) fn read_back(
        &mut self,
        scene: &UploadedScene,
        plan: FramePlan,
        mut band_buffers: Vec<(Buffer, Option<Buffer>)>,
        totals: PassTotals,
    ) -> Result<Rendered, RenderError> {
        let ctx = &self.context;
        let t1 = Instant::now();
        let (width, rows) = (plan.width, plan.rows.clone());
        let n = width as usize * (rows.end - rows.start) as usize;
        let mut pixels: Vec<[f32; 4]> = Vec::with_capacity(n);
        let mut aov_bytes = Vec::new();
        for ((image, aovs), band) in band_buffers.iter().zip(&plan.bands.rows) {
            let texels = width as usize * (band.end - band.start) as usize;
            let at = pixels.len();
            pixels.resize(at + texels, [0.0; 4]);
            ctx.read_buffer_into(image, bytemuck::cast_slice_mut(&mut pixels[at..]))?;
            if let Some(b) = aovs {
                let size = texels * std::mem::size_of::<layout::Aov>();
                aov_bytes.extend_from_slice(&ctx.read_buffer(b)?[..size]);
            }
        }
        if totals.passes > 1 && !plan.is_part {
            let inv = 1.0 / totals.passes as f32;
            for p in &mut pixels {
                *p = p.map(|c| c * inv);
            }
        }
        let aovs = plan.with_aovs.then(|| Aovs::from_gpu(&aov_bytes, n, scene));
        let readback = t1.elapsed();
        ctx.check_validation()?;
        let kept = &mut self.stage_buffers[plan.kept];
        if plan.whole {
            kept.image = Some(band_buffers.swap_remove(0).0);
        }
        kept.holds = plan.holds.clone().filter(|_| totals.passes == 1);
        let stage_times = match self.profile_stages {
            false => Vec::new(),
            true => slot_names(scene, &plan)
                .into_iter()
                .zip(totals.stage_times)
                .collect(),
        };
        Ok(Rendered {
            frame: Frame {
                stage_times,
                driver_compiles: plan.compiled.driver_each.clone(),
                image: Image {
                    width,
                    height: rows.end - rows.start,
                    pixels,
                },
                stats: RenderStats {
                    primary_rays: totals.primary_rays,
                    shadow_rays: totals.shadow_rays,
                    passes: totals.passes,
                    bvh_nodes: scene.bvh_nodes,
                    bvh_depth: scene.bvh_depth,
                    bvh_bytes: scene.bvh_bytes,
                    texture_bytes: scene.texture_bytes,
                    hits_reused: plan.reuse,
                    tiles: plan.bands.tiles(&plan.tiles).len(),
                    stage_bytes: plan.tiles.bytes(),
                    timings: Timings {
                        shader_compile: plan.compiled.naga,
                        pipeline_creation: plan.compiled.pipeline,
                        driver_compile: plan.compiled.driver,
                        accel_build: Duration::ZERO,
                        upload: Duration::ZERO,
                        render: totals.render,
                        readback,
                    },
                },
            },
            aovs,
        })
    }
}

impl Aovs {
    pub(super) fn from_gpu(bytes: &[u8], n: usize, scene: &UploadedScene) -> Aovs {
        let raw: Vec<layout::Aov> = bytemuck::pod_collect_to_vec(&bytes[..n * 32]);
        let mut a = Aovs::default();
        for r in raw {
            a.depth.push(r.depth);
            a.normal.push([r.normal_x, r.normal_y, r.normal_z]);
            a.uv.push([r.u, r.v]);
            a.object.push(r.object);
            let first = scene
                .first_triangle
                .get(r.object as usize)
                .copied()
                .flatten();
            a.primitive.push(match (r.object, first) {
                (u32::MAX, _) => u32::MAX,
                (_, Some(f)) => r.primitive.wrapping_sub(f),
                (_, None) => 0,
            });
        }
        a
    }
}
