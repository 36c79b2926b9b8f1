//! Which render a part belongs to: a SHA-256 over the scene file and every
//! file it references ([`crate::loaders::Loaded::files`]), the WGSL the
//! kernel is built from and every setting that changes pixels. Parts with
//! the same identity can be merged; the tile and pass range are stored next
//! to it in each part ([`super::part`]).

use std::path::PathBuf;

use sha2::{Digest, Sha256};

use crate::render::{KernelOptions, ShaderSource};

/// Everything besides the files that decides a render's pixels.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderSettings {
    /// Full image width, pixels.
    pub width: u32,
    /// Full image height, pixels.
    pub height: u32,
    /// Passes (samples per pixel) of the whole render.
    pub spp: u32,
    /// Seed of the sample pattern.
    pub seed: u32,
    /// `--area-samples`, when given.
    pub area_samples: Option<u32>,
    /// Acceleration structure, triangle test, sampler.
    pub kernel: KernelOptions,
    /// `--environment` and `--background`.
    pub lighting: crate::loaders::lighting::Lighting,
    /// `--gltf-materials`.
    pub gltf_materials: crate::loaders::GltfMaterials,
}

/// Why an identity could not be computed.
#[derive(Debug, thiserror::Error)]
#[error("{path}: cannot read to identify the render: {error}")]
pub struct IdentityError {
    /// The file that could not be read.
    pub path: String,
    /// Why.
    pub error: String,
}

/// The identity of a render as 64 hex digits: SHA-256 over the files'
/// contents (in the loader's order, each with its length; not their paths,
/// so that nodes that mount the same files elsewhere agree), every shader
/// file of [`crate::render::stages::SHADER_FILES`] (engine stages, shade
/// stage, built-in shading files), the settings and penumbra's version.
pub fn render_id(
    files: &[PathBuf],
    shaders: &ShaderSource,
    settings: &RenderSettings,
) -> Result<String, IdentityError> {
    let mut h = Sha256::new();
    h.update(b"penumbra render identity v1\n");
    h.update(env!("CARGO_PKG_VERSION").as_bytes());
    for path in files {
        let bytes = std::fs::read(path).map_err(|e| IdentityError {
            path: path.display().to_string(),
            error: e.to_string(),
        })?;
        h.update((bytes.len() as u64).to_le_bytes());
        h.update(&bytes);
    }
    // Every shader file: the engine stages', the shade stage's and the
    // built-in shading files (a user's are among `files`).
    for (name, _) in crate::render::stages::SHADER_FILES {
        let (_, text) = shaders.read(name).map_err(|e| IdentityError {
            path: e.location.clone(),
            error: e.message.clone(),
        })?;
        h.update((text.len() as u64).to_le_bytes());
        h.update(text.as_bytes());
    }
    h.update(format!("{settings:?}").as_bytes());
    Ok(h.finalize().iter().map(|b| format!("{b:02x}")).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An edit of any shader file, the built-in shading files included,
    /// gives another identity (parts rendered before and after must not
    /// merge).
    #[test]
    fn every_shader_file_is_part_of_the_identity() {
        let dir = tempfile::tempdir().unwrap();
        for (name, text) in crate::render::stages::SHADER_FILES {
            let path = dir.path().join(name);
            std::fs::create_dir_all(path.parent().unwrap()).unwrap();
            std::fs::write(path, text).unwrap();
        }
        let shaders = ShaderSource::Directory(dir.path().to_path_buf());
        let settings = RenderSettings {
            width: 8,
            height: 8,
            spp: 1,
            seed: 0,
            area_samples: None,
            kernel: KernelOptions::default(),
            lighting: Default::default(),
            gltf_materials: Default::default(),
        };
        let before = render_id(&[], &shaders, &settings).unwrap();
        assert_eq!(
            before,
            render_id(&[], &ShaderSource::Embedded, &settings).unwrap()
        );
        for name in ["shading/phong.wgsl", "stages/shade.wgsl", "bvh.wgsl"] {
            let path = dir.path().join(name);
            let text = std::fs::read_to_string(&path).unwrap();
            std::fs::write(&path, format!("{text}\n// edited\n")).unwrap();
            assert_ne!(
                render_id(&[], &shaders, &settings).unwrap(),
                before,
                "{name}"
            );
            std::fs::write(&path, text).unwrap();
        }
    }
}
