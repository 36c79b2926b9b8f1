//! Loaders turn files into a validated [`Scene`]: JSON scene files
//! ([`json`], documented in `scenes/README.md`) and glTF 2.0 files
//! ([`gltf`]), chosen by the file extension.

pub mod gltf;
pub mod guard;
pub mod json;
pub mod ktx2;
pub mod lighting;
pub mod texture;

use std::path::{Path, PathBuf};

use crate::scene::Scene;
use crate::SceneError;

/// Settings from the command line that override the file, and the limits of
/// what a scene may make the loader do ([`guard`]).
#[derive(Clone, Debug)]
pub struct LoadOptions {
    /// Image width in pixels (overrides the scene's).
    pub width: Option<u32>,
    /// Image height in pixels (overrides the scene's).
    pub height: Option<u32>,
    /// Refuse every referenced file outside the scene file's folder (`--restrict-paths`).
    pub restrict_paths: bool,
    /// Most bytes that the files read and the loaded geometry may take
    /// (`--max-scene-memory`), checked before any data is expanded.
    pub max_scene_bytes: u64,
    /// Most triangles in the scene: the device's limit when a renderer is known.
    pub max_triangles: u64,
    /// Most bytes the scene's textures may take on the device with their
    /// mip chains (the renderer's texture image), checked from each image's
    /// header before it is decoded; `u64::MAX` when no device is known.
    pub max_texture_bytes: u64,
    /// Which shader glTF materials become (`--gltf-materials`).
    pub gltf_materials: GltfMaterials,
    /// Which of a glTF file's cameras to render from (`--camera`).
    pub camera: gltf::CameraChoice,
    /// `--environment` and `--background`.
    pub lighting: lighting::Lighting,
}

/// The shader of a glTF file's materials (`--gltf-materials`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum GltfMaterials {
    /// glTF's own model (`metallic_roughness`): the default.
    #[default]
    MetallicRoughness,
    /// The seminar's mapping: diffuse Phong of the base colour
    /// (`phong`), as penumbra rendered glTF files before issue 38.
    Phong,
}

impl std::str::FromStr for GltfMaterials {
    type Err = String;

    /// `metallic-roughness` or `phong` (`--gltf-materials`).
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "metallic-roughness" => Ok(GltfMaterials::MetallicRoughness),
            "phong" => Ok(GltfMaterials::Phong),
            _ => Err("expected `metallic-roughness` or `phong`".into()),
        }
    }
}

impl Default for LoadOptions {
    fn default() -> Self {
        LoadOptions {
            width: None,
            height: None,
            restrict_paths: false,
            max_scene_bytes: guard::DEFAULT_MAX_SCENE_BYTES,
            max_triangles: guard::DEFAULT_MAX_TRIANGLES,
            max_texture_bytes: u64::MAX,
            camera: gltf::CameraChoice::File,
            gltf_materials: GltfMaterials::default(),
            lighting: lighting::Lighting::default(),
        }
    }
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
    /// The file has no lights and the loader lit it with the default
    /// environment ([`lighting::light_by_default`]): shown tone-mapped as
    /// viewers show models.
    pub lit_by_default: bool,
}

/// Loads a `.json`, `.gltf` or `.glb` scene.
pub fn load_scene(path: &Path, opts: &LoadOptions) -> Result<Loaded, SceneError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    let loaded = match ext.as_str() {
        "json" if opts.camera != gltf::CameraChoice::File => {
            let message =
                "--camera chooses among a glTF file's cameras; a JSON scene has one camera";
            return Err(SceneError::new(path, "camera", message));
        }
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

/// Reads a user's shader file through `guard` (its checks and budget) as
/// UTF-8 text: the one reader of shader files, at load and at reload
/// (`penumbra watch`).
pub fn read_shader_file(path: &Path, guard: &guard::Guard) -> Result<String, guard::Refused> {
    let bytes = guard.read(path, "shader file")?;
    String::from_utf8(bytes)
        .map_err(|e| guard::Refused(format!("cannot read shader file {}: {e}", path.display())))
}
