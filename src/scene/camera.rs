//! The camera as a view frustum: a position, an orthonormal orientation, a
//! projection (vertical field of view, or an orthographic window) and the
//! image size. One primary ray goes through each pixel centre; row 0 is the
//! top of the image.

use glam::{DMat3, DVec3};

/// How camera space maps onto the image plane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Projection {
    /// Pinhole camera with a vertical field of view in degrees, in (0, 180).
    Perspective {
        /// Vertical field of view, degrees.
        vfov_deg: f64,
    },
    /// Parallel rays; `half_height` is half the height of the visible window
    /// in world units (glTF's `ymag`). The width follows the image aspect.
    Orthographic {
        /// Half the window height, world units.
        half_height: f64,
    },
}

/// A camera looking along its local −Z axis with +Y up (the glTF and OpenGL
/// convention), placed in the world by `position` and `orientation`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Eye position, world units.
    pub position: DVec3,
    /// Columns are the camera's right (+X), up (+Y) and backward (+Z) unit
    /// vectors in world space; it looks along −Z.
    pub orientation: DMat3,
    /// Perspective or orthographic.
    pub projection: Projection,
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
}

/// Why a camera orientation could not be built.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OrientationError {
    /// The look-at point equals the position.
    ZeroViewDirection,
    /// The up vector has zero length.
    ZeroUp,
    /// Up is parallel to the view direction, so "right" is undefined.
    UpParallelToView,
}

impl Camera {
    /// Orientation looking from `position` towards `target` with `up`
    /// giving the image's upward direction.
    pub fn look_at(position: DVec3, target: DVec3, up: DVec3) -> Result<DMat3, OrientationError> {
        let forward = target - position;
        if forward.length_squared() == 0.0 || !forward.is_finite() {
            return Err(OrientationError::ZeroViewDirection);
        }
        if up.length_squared() == 0.0 || !up.is_finite() {
            return Err(OrientationError::ZeroUp);
        }
        let back = -forward.normalize();
        let right = up.cross(back);
        // sin of the angle between up and the view direction below ~1e-9 rad.
        if right.length() <= 1e-9 * up.length() {
            return Err(OrientationError::UpParallelToView);
        }
        let right = right.normalize();
        Ok(DMat3::from_cols(right, back.cross(right), back))
    }

    /// Orientation from yaw (about world +Y), pitch (about the camera's X) and
    /// roll (about its view axis), degrees, applied in that order as
    /// `R = Ry(yaw) · Rx(pitch) · Rz(roll)`. All zero looks along −Z with +Y up;
    /// positive yaw turns left, positive pitch looks up.
    pub fn yaw_pitch_roll(yaw_deg: f64, pitch_deg: f64, roll_deg: f64) -> DMat3 {
        DMat3::from_rotation_y(yaw_deg.to_radians())
            * DMat3::from_rotation_x(pitch_deg.to_radians())
            * DMat3::from_rotation_z(roll_deg.to_radians())
    }

    /// Width / height.
    pub fn aspect(&self) -> f64 {
        self.width as f64 / self.height as f64
    }

    /// Half extents of the image plane at distance 1 (perspective) or of the
    /// window (orthographic), as (half width, half height).
    pub fn half_extent(&self) -> (f64, f64) {
        let h = match self.projection {
            Projection::Perspective { vfov_deg } => (vfov_deg.to_radians() * 0.5).tan(),
            Projection::Orthographic { half_height } => half_height,
        };
        (h * self.aspect(), h)
    }

    /// Continuous image coordinates (x right, y down, pixel centres at
    /// `i + 0.5`) where a world point appears, or `None` behind the camera.
    /// The inverse of the primary-ray generation; tests use it to predict
    /// where a point lands.
    pub fn project(&self, world: DVec3) -> Option<(f64, f64)> {
        let local = self.orientation.transpose() * (world - self.position);
        let (hw, hh) = self.half_extent();
        let (sx, sy) = match self.projection {
            Projection::Perspective { .. } => {
                if local.z >= 0.0 {
                    return None;
                }
                (local.x / -local.z, local.y / -local.z)
            }
            Projection::Orthographic { .. } => (local.x, local.y),
        };
        let x = (sx / hw + 1.0) * 0.5 * self.width as f64;
        let y = (1.0 - sy / hh) * 0.5 * self.height as f64;
        Some((x, y))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cam(orientation: DMat3) -> Camera {
        Camera {
            position: DVec3::new(1.0, 2.0, 3.0),
            orientation,
            projection: Projection::Perspective { vfov_deg: 90.0 },
            width: 200,
            height: 100,
        }
    }

    #[test]
    fn look_at_centres_the_target() {
        let target = DVec3::new(4.0, -1.0, 7.0);
        let c = cam(Camera::look_at(DVec3::new(1.0, 2.0, 3.0), target, DVec3::Y).unwrap());
        let (x, y) = c.project(target).unwrap();
        assert!((x - 100.0).abs() < 1e-9 && (y - 50.0).abs() < 1e-9);
    }

    #[test]
    fn yaw_pitch_roll_zero_looks_down_minus_z() {
        let c = cam(Camera::yaw_pitch_roll(0.0, 0.0, 0.0));
        // 90° vfov: a point one unit up at distance 1 lands on the top edge.
        let (x, y) = c.project(DVec3::new(1.0, 3.0, 2.0)).unwrap();
        assert!((x - 100.0).abs() < 1e-9 && y.abs() < 1e-9);
        assert!(c.project(DVec3::new(1.0, 2.0, 4.0)).is_none());
    }

    #[test]
    fn yaw_left_pitch_up() {
        // Yaw 90° turns the camera to look along −X.
        let c = cam(Camera::yaw_pitch_roll(90.0, 0.0, 0.0));
        let (x, y) = c.project(DVec3::new(-5.0, 2.0, 3.0)).unwrap();
        assert!((x - 100.0).abs() < 1e-9 && (y - 50.0).abs() < 1e-9);
        let c = cam(Camera::yaw_pitch_roll(0.0, 90.0, 0.0));
        let (x, y) = c.project(DVec3::new(1.0, 9.0, 3.0)).unwrap();
        assert!((x - 100.0).abs() < 1e-9 && (y - 50.0).abs() < 1e-9);
    }

    #[test]
    fn look_at_rejects_bad_input() {
        let p = DVec3::ZERO;
        assert_eq!(
            Camera::look_at(p, p, DVec3::Y),
            Err(OrientationError::ZeroViewDirection)
        );
        assert_eq!(
            Camera::look_at(p, DVec3::Z, DVec3::ZERO),
            Err(OrientationError::ZeroUp)
        );
        assert_eq!(
            Camera::look_at(p, DVec3::Y * 3.0, DVec3::Y),
            Err(OrientationError::UpParallelToView)
        );
    }
}
