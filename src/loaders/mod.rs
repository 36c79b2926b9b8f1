//! Loaders turn files into a validated [`Scene`]: JSON scene files
//! ([`json`], documented in `scenes/README.md`) and glTF 2.0 files
//! ([`gltf`]), chosen by the file extension.

pub mod gltf;
pub mod json;

use std::path::{Path, PathBuf};

use crate::scene::Scene;
use crate::SceneError;

/// Settings from the command line that override the file.
#[derive(Clone, Debug, Default)]
pub struct LoadOptions {
    /// Image width in pixels (overrides the scene's).
    pub width: Option<u32>,
    /// Image height in pixels (overrides the scene's).
    pub height: Option<u32>,
}

/// A loaded scene with what the loader wants the user to know.
#[derive(Clone, Debug)]
pub struct Loaded {
    /// The validated scene.
    pub scene: Scene,
    /// Notes for the user (defaults chosen, parts of the file not used);
    /// each is one line, printed once.
    pub notes: Vec<String>,
    /// Every file that was read: the scene file first, then referenced
    /// files (glTF, buffers). A watcher reloads when any of them changes.
    pub files: Vec<PathBuf>,
}

/// Loads a `.json`, `.gltf` or `.glb` scene.
pub fn load_scene(path: &Path, opts: &LoadOptions) -> Result<Loaded, SceneError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    let loaded = match ext.as_str() {
        "json" => json::load(path, opts)?,
        "gltf" | "glb" => gltf::load(path, opts)?,
        _ => {
            return Err(SceneError::new(
                path,
                "",
                "unknown scene format: expected a .json, .gltf or .glb file",
            ))
        }
    };
    loaded
        .scene
        .validate()
        .map_err(|e| SceneError::new(path, e.field, e.message))?;
    Ok(loaded)
}

/// Applies `--width`/`--height` to a size read from a file.
pub(crate) fn override_size(opts: &LoadOptions, width: u32, height: u32) -> (u32, u32) {
    (opts.width.unwrap_or(width), opts.height.unwrap_or(height))
}
