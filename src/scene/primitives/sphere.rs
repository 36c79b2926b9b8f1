//! Sphere given by centre and radius.

use glam::DVec3;

/// The sphere `{x : |x − center| = radius}`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    /// Centre, world units.
    pub center: DVec3,
    /// Radius, > 0.
    pub radius: f64,
}

impl Sphere {
    /// Nearest positive distance along a unit-length `dir`.
    ///
    /// Uses the cancellation-free form of Haines et al., "Precision
    /// Improvements for Ray/Sphere Intersection" (Ray Tracing Gems, 2019):
    /// the discriminant from the distance of the centre to the ray line, and
    /// the smaller root as `c / q`.
    pub fn intersect(&self, origin: DVec3, dir: DVec3) -> Option<f64> {
        let f = origin - self.center;
        let b = f.dot(dir);
        let perp = f - b * dir;
        let disc = self.radius * self.radius - perp.length_squared();
        if disc < 0.0 {
            return None;
        }
        let c = f.length_squared() - self.radius * self.radius;
        let q = -b - disc.sqrt().copysign(b);
        let (t0, t1) = if q == 0.0 { (0.0, 0.0) } else { (c / q, q) };
        let (near, far) = if t0 <= t1 { (t0, t1) } else { (t1, t0) };
        if near > 0.0 {
            Some(near)
        } else if far > 0.0 {
            Some(far)
        } else {
            None
        }
    }

    /// Outward unit normal at a surface point: (p − c) / r.
    pub fn normal_at(&self, p: DVec3) -> DVec3 {
        (p - self.center) / self.radius
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hits_front_and_from_inside() {
        let s = Sphere {
            center: DVec3::new(0.0, 0.0, -5.0),
            radius: 1.0,
        };
        assert_eq!(s.intersect(DVec3::ZERO, -DVec3::Z), Some(4.0));
        assert_eq!(s.intersect(s.center, DVec3::X), Some(1.0));
        assert_eq!(s.intersect(DVec3::ZERO, DVec3::Z), None);
        assert_eq!(s.intersect(DVec3::ZERO, DVec3::X), None);
    }

    #[test]
    fn small_sphere_far_away_is_precise() {
        // A naive b² − c discriminant loses every digit here.
        let s = Sphere {
            center: DVec3::new(0.0, 0.0, -1e7),
            radius: 1e-3,
        };
        let t = s.intersect(DVec3::ZERO, -DVec3::Z).unwrap();
        assert!((t - (1e7 - 1e-3)).abs() < 1e-8, "{t}");
    }
}
