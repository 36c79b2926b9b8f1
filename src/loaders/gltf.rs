//! TEMPORARY STUB (replaced by the real loader).
use std::path::{Path, PathBuf};
use crate::scene::{Light, Mesh, Projection};
use crate::SceneError;
#[derive(Clone, Debug)]
pub struct GltfMesh { pub mesh: Mesh, pub base_color: Option<glam::Vec3>, pub name: String }
#[derive(Clone, Copy, Debug)]
pub struct GltfCamera { pub position: glam::DVec3, pub orientation: glam::DMat3, pub projection: Projection, pub aspect_ratio: Option<f64> }
#[derive(Clone, Debug)]
pub struct GltfDocument { pub meshes: Vec<GltfMesh>, pub camera: Option<GltfCamera>, pub lights: Vec<Light>, pub notes: Vec<String>, pub files: Vec<PathBuf> }
pub fn read(path: &Path) -> Result<GltfDocument, SceneError> { Err(SceneError::new(path, "", "stub")) }
pub fn load(path: &Path, _opts: &super::LoadOptions) -> Result<super::Loaded, SceneError> { Err(SceneError::new(path, "", "stub")) }
