//! A single triangle, and the seminar's ray/triangle test.

use glam::DVec3;

/// Triangle with vertices in counter-clockwise order seen from the side its
/// geometric normal `(b − a) × (c − a)` points to. Surfaces are two-sided.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triangle {
    /// The three vertices.
    pub vertices: [DVec3; 3],
}

/// Where a ray meets a triangle: distance and barycentric coordinates
/// (the hit point is `(1 − u − v)·a + u·b + v·c`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleHit {
    /// Distance along the ray.
    pub t: f64,
    /// Weight of vertex b.
    pub u: f64,
    /// Weight of vertex c.
    pub v: f64,
}

impl Triangle {
    /// Unnormalised geometric normal.
    pub fn geometric_normal(&self) -> DVec3 {
        let [a, b, c] = self.vertices;
        (b - a).cross(c - a)
    }

    /// Möller–Trumbore in the seminar's order: the barycentric u, then v, each
    /// rejecting as early as possible, and only then t (the seminar measured
    /// 0.68 s against 1 s for computing t first).
    pub fn intersect(&self, origin: DVec3, dir: DVec3) -> Option<TriangleHit> {
        let [a, b, c] = self.vertices;
        let e1 = b - a;
        let e2 = c - a;
        let p = dir.cross(e2);
        let det = e1.dot(p);
        if det == 0.0 {
            return None;
        }
        let inv = 1.0 / det;
        let s = origin - a;
        let u = s.dot(p) * inv;
        if !(0.0..=1.0).contains(&u) {
            return None;
        }
        let q = s.cross(e1);
        let v = dir.dot(q) * inv;
        if v < 0.0 || u + v > 1.0 {
            return None;
        }
        let t = e2.dot(q) * inv;
        (t > 0.0 && t.is_finite()).then_some(TriangleHit { t, u, v })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn barycentrics_and_distance() {
        let tri = Triangle {
            vertices: [DVec3::ZERO, DVec3::X, DVec3::Y],
        };
        let h = tri
            .intersect(DVec3::new(0.25, 0.5, 2.0), -DVec3::Z)
            .unwrap();
        assert!(
            (h.t - 2.0).abs() < 1e-12 && (h.u - 0.25).abs() < 1e-12 && (h.v - 0.5).abs() < 1e-12
        );
        assert!(tri
            .intersect(DVec3::new(0.75, 0.5, 2.0), -DVec3::Z)
            .is_none());
        assert!(tri
            .intersect(DVec3::new(0.25, 0.5, 2.0), DVec3::Z)
            .is_none());
        // Degenerate (collinear) triangle: never a hit.
        let flat = Triangle {
            vertices: [DVec3::ZERO, DVec3::X, DVec3::X * 2.0],
        };
        assert!(flat
            .intersect(DVec3::new(0.5, 0.0, 1.0), -DVec3::Z)
            .is_none());
    }
}
