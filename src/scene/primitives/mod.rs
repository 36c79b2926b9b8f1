//! The seminar's primitives: infinite plane, sphere, single triangle and
//! triangle mesh. Each file holds the data and its `f64` ray intersection,
//! which tests and host-side checks use; the GPU versions live in
//! `shaders/primitives/` under the same names.

pub mod mesh;
pub mod plane;
pub mod sphere;
pub mod triangle;

pub use mesh::Mesh;
pub use plane::Plane;
pub use sphere::Sphere;
pub use triangle::Triangle;
