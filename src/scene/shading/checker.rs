//! The seminar's 3D checkerboard: a shader made of two sub-shaders.

use glam::DVec3;

use super::ShaderId;

/// Cubes of edge `size`; `even` shades points where
/// `floor(x/s) + floor(y/s) + floor(z/s)` is even, `odd` the others.
/// Sub-shaders may be checkers themselves (nesting), but not cyclically.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Checker {
    /// Cube edge length, > 0.
    pub size: f64,
    /// Shader of the even cells.
    pub even: ShaderId,
    /// Shader of the odd cells.
    pub odd: ShaderId,
}

impl Checker {
    /// Whether world point `p` lies in an even cell.
    pub fn is_even(&self, p: DVec3) -> bool {
        let c = (p / self.size).floor();
        (c.x + c.y + c.z).rem_euclid(2.0) == 0.0
    }
}
