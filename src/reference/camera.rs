//! Primary rays as `shaders/camera.wgsl` makes them, in world coordinates:
//! `right` and `up` scaled by the half extents of the image plane at
//! distance 1 (perspective) or of the window (orthographic).

use glam::DVec3;

use super::intersect::Ray;
use crate::scene::{Camera as SceneCamera, Projection};

/// The camera as a frustum.
#[derive(Clone, Copy, Debug)]
pub struct Camera {
    eye: DVec3,
    right: DVec3,
    up: DVec3,
    forward: DVec3,
    orthographic: bool,
}

impl Camera {
    /// From the scene model (as `render::layout::GpuScene::new` does).
    pub fn new(cam: &SceneCamera) -> Camera {
        let (hw, hh) = cam.half_extent();
        Camera {
            eye: cam.position,
            right: cam.orientation.x_axis * hw,
            up: cam.orientation.y_axis * hh,
            forward: -cam.orientation.z_axis,
            orthographic: matches!(cam.projection, Projection::Orthographic { .. }),
        }
    }

    /// The ray through point `sub` ((0.5, 0.5) is the centre) of pixel
    /// (`x`, `y`) of a `width`×`height` image; row 0 is the top.
    pub fn primary_ray(&self, x: u32, y: u32, width: u32, height: u32, sub: [f64; 2]) -> Ray {
        let ndc_x = (x as f64 + sub[0]) / width as f64 * 2.0 - 1.0;
        let ndc_y = 1.0 - (y as f64 + sub[1]) / height as f64 * 2.0;
        let offset = ndc_x * self.right + ndc_y * self.up;
        if self.orthographic {
            Ray::new(self.eye + offset, self.forward)
        } else {
            Ray::new(self.eye, (self.forward + offset).normalize())
        }
    }
}
