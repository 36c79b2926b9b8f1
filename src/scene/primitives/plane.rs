//! Infinite plane through a point with a normal.

use glam::DVec3;

/// The plane `{x : n · (x − point) = 0}`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plane {
    /// Any point on the plane.
    pub point: DVec3,
    /// Unit normal (loaders normalise it).
    pub normal: DVec3,
}

impl Plane {
    /// Distance along the ray to the plane, if it lies in front of the origin.
    /// A ray parallel to the plane never hits it.
    pub fn intersect(&self, origin: DVec3, dir: DVec3) -> Option<f64> {
        let denom = self.normal.dot(dir);
        if denom == 0.0 {
            return None;
        }
        let t = self.normal.dot(self.point - origin) / denom;
        (t > 0.0 && t.is_finite()).then_some(t)
    }
}
