//! The calibration's measurement: the kernel's frame time on a small fixed
//! scene built into the binary (so the binary stands alone), warm (the first
//! frame, which pays the driver's compile, is left out).
//!
//! The scene is a tessellated sphere of 4,096 triangles with vertex normals
//! on a ground plane, beside an analytic sphere, under a point light (so
//! every frame also traces shadow rays), at 640×480: the BVH walk, the
//! triangle and sphere tests and the shade stage all take part, as in a
//! real scene. A frame takes about 40 ms of CPU time on a 2-core Zen 5
//! (at 320×240, about 10 ms, the frames were too short to time well on a
//! busy machine). Its time is the process's CPU time over the frame, which
//! a busy machine disturbs far less than its wall time (docs/drivers.md).

use std::time::Duration;

use glam::{DMat3, DVec3, Vec3};

use crate::render::{RenderError, RenderRequest, Renderer};
use crate::scene::{
    Camera, Light, LightKind, Mesh, Object, Phong, Plane, Projection, Scene, Shader, Shape, Sphere,
};

/// The probe image's size.
pub const WIDTH: u32 = 640;
/// The probe image's height.
pub const HEIGHT: u32 = 480;

/// Rings and segments of the tessellated sphere: 2 × 32 × 64 = 4,096 triangles.
const RINGS: u32 = 32;
const SEGMENTS: u32 = 64;

/// The probe scene.
pub fn scene() -> Scene {
    let phong = |diffuse: Vec3, specular: f32| {
        Shader::Phong(Phong {
            ambient: Vec3::splat(0.1),
            diffuse,
            specular: Vec3::splat(specular),
            shininess: 32.0,
            textures: Default::default(),
        })
    };
    let object = |shape, shader| Object {
        shape,
        shader,
        maps: Default::default(),
    };
    let position = DVec3::new(0.0, 1.5, 5.0);
    let orientation =
        Camera::look_at(position, DVec3::new(0.0, 0.6, 0.0), DVec3::Y).unwrap_or(DMat3::IDENTITY);
    Scene {
        camera: Camera {
            position,
            orientation,
            projection: Projection::Perspective { vfov_deg: 45.0 },
            width: WIDTH,
            height: HEIGHT,
        },
        background: Vec3::new(0.2, 0.3, 0.4),
        shaders: vec![
            phong(Vec3::new(0.8, 0.5, 0.3), 0.5),
            phong(Vec3::splat(0.7), 0.0),
        ],
        objects: vec![
            object(Shape::Mesh(uv_sphere(DVec3::new(-0.6, 1.0, 0.0), 1.0)), 0),
            object(
                Shape::Sphere(Sphere {
                    center: DVec3::new(1.4, 0.6, 0.5),
                    radius: 0.6,
                }),
                0,
            ),
            object(
                Shape::Plane(Plane {
                    point: DVec3::ZERO,
                    normal: DVec3::Y,
                }),
                1,
            ),
        ],
        lights: vec![Light {
            kind: LightKind::Point {
                position: DVec3::new(3.0, 5.0, 4.0),
            },
            intensity: 30.0,
            ambient: Vec3::splat(0.1),
            diffuse: Vec3::ONE,
            specular: Vec3::ONE,
        }],
        textures: vec![],
    }
}

/// A sphere of `RINGS` × `SEGMENTS` quads, two triangles each (the poles'
/// degenerate halves included, so the count stays round), with its normals.
fn uv_sphere(center: DVec3, radius: f64) -> Mesh {
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    for r in 0..=RINGS {
        let theta = std::f64::consts::PI * r as f64 / RINGS as f64;
        for s in 0..=SEGMENTS {
            let phi = std::f64::consts::TAU * s as f64 / SEGMENTS as f64;
            let n = DVec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            );
            positions.push(center + radius * n);
            normals.push(n);
        }
    }
    let at = |r: u32, s: u32| r * (SEGMENTS + 1) + s;
    let mut indices = Vec::new();
    for r in 0..RINGS {
        for s in 0..SEGMENTS {
            indices.push([at(r, s), at(r + 1, s), at(r + 1, s + 1)]);
            indices.push([at(r, s), at(r + 1, s + 1), at(r, s + 1)]);
        }
    }
    Mesh {
        positions,
        normals: Some(normals),
        indices,
        ..Default::default()
    }
}

/// One probe frame: its render phase (wall time) and the CPU time the whole
/// process spent on it (every thread: lavapipe's workers do the work).
#[derive(Clone, Copy, Debug)]
pub struct FrameTime {
    /// The render phase, wall-clock.
    pub wall: Duration,
    /// The process's CPU time over the frame.
    pub cpu: Duration,
}

/// Uploads the probe scene and renders `1 + frames` frames of one sample a
/// pixel, returning the times of each frame after the first.
pub fn frame_times(renderer: &mut Renderer, frames: usize) -> Result<Vec<FrameTime>, RenderError> {
    let uploaded = renderer.upload(&scene())?;
    let mut times = Vec::with_capacity(frames);
    for i in 0..=frames {
        let cpu0 = process_cpu_time();
        let r = renderer.render(&uploaded, RenderRequest::new(WIDTH, HEIGHT))?;
        let cpu = process_cpu_time().saturating_sub(cpu0);
        if i > 0 {
            times.push(FrameTime {
                wall: r.frame.stats.timings.render,
                cpu,
            });
        }
    }
    Ok(times)
}

/// The CPU time (user and system) of every thread of this process so far.
fn process_cpu_time() -> Duration {
    // SAFETY: getrusage writes the struct it is given and nothing else.
    let mut u: libc::rusage = unsafe { std::mem::zeroed() };
    if unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut u) } != 0 {
        return Duration::ZERO;
    }
    let tv =
        |t: libc::timeval| Duration::new(t.tv_sec.max(0) as u64, (t.tv_usec.max(0) as u32) * 1000);
    tv(u.ru_utime) + tv(u.ru_stime)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_scene_is_valid_and_has_its_triangles() {
        let s = scene();
        s.validate().unwrap();
        assert_eq!(s.triangle_count(), (2 * RINGS * SEGMENTS) as usize);
        assert_eq!(s.triangle_count(), 4096);
    }
}
