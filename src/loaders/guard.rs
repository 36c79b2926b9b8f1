//! What a scene may make the loader do: which files it may read and how much
//! memory its geometry may take.
//!
//! A renderer that takes untrusted files (thumbnails, CI previews) must not be
//! made to block on a FIFO, read `/dev/zero` until memory runs out, or expand a
//! few hundred bytes of glTF into gigabytes of zeros. Every file a scene names
//! goes through [`Guard::read`], and every primitive is charged to the budget
//! with [`Guard::charge`] *before* its data is expanded, so a file that asks
//! for too much fails at once with an error naming the field that crossed the
//! limit.
//!
//! Paths: by default a scene may reference files anywhere (shared asset
//! folders are common: `../textures/wood.png`, an absolute path in a JSON
//! scene). With [`LoadOptions::restrict_paths`] (`--restrict-paths`) every
//! referenced file must lie inside the folder of the scene file given on the
//! command line, after resolving `..` and symbolic links.

use std::cell::Cell;
use std::io::Read;
use std::path::{Path, PathBuf};

use super::LoadOptions;

/// Default for [`LoadOptions::max_scene_bytes`]: 4 GiB of loaded geometry.
pub const DEFAULT_MAX_SCENE_BYTES: u64 = 4 << 30;

/// Default for [`LoadOptions::max_triangles`]: what 32-bit primitive indices address.
pub const DEFAULT_MAX_TRIANGLES: u64 = u32::MAX as u64;

/// Bytes the loader holds per vertex while reading one: the accessor's values
/// as `f64` (3 × 8) and the world-space `DVec3` (24).
pub const BYTES_PER_VERTEX: u64 = 48;

/// Bytes per vertex normal, counted as for positions.
pub const BYTES_PER_NORMAL: u64 = 48;

/// Bytes per index: its `f64` while reading and its `u32` in the triangle list.
pub const BYTES_PER_INDEX: u64 = 12;

/// The limits of one load, shared by the scene file and every file it references.
#[derive(Debug)]
pub struct Guard {
    /// Canonical folder of the top-level scene file, when paths are restricted.
    root: Option<PathBuf>,
    max_bytes: u64,
    max_triangles: u64,
    max_texture_bytes: u64,
    bytes: Cell<u64>,
    triangles: Cell<u64>,
    /// Device bytes of the textures admitted so far.
    texture_bytes: Cell<u64>,
}

/// Why a file could not be read or a primitive not be admitted; the caller
/// adds the file and the field.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Refused(pub String);

impl Guard {
    /// The limits of `opts` for the scene file `scene`.
    pub fn new(scene: &Path, opts: &LoadOptions) -> Guard {
        let root = opts.restrict_paths.then(|| {
            let folder = scene.parent().filter(|p| !p.as_os_str().is_empty());
            let folder = folder.unwrap_or(Path::new("."));
            folder
                .canonicalize()
                .unwrap_or_else(|_| folder.to_path_buf())
        });
        Guard {
            root,
            max_bytes: opts.max_scene_bytes,
            max_triangles: opts.max_triangles,
            max_texture_bytes: opts.max_texture_bytes,
            bytes: Cell::new(0),
            triangles: Cell::new(0),
            texture_bytes: Cell::new(0),
        }
    }

    /// Reads a whole file that the scene names, after checking that it is a
    /// regular file (not a FIFO, a device or a directory), that it may be read
    /// under [`LoadOptions::restrict_paths`], and that its size fits the
    /// budget. `what` names the kind of file for the message.
    pub fn read(&self, path: &Path, what: &str) -> Result<Vec<u8>, Refused> {
        self.check_path(path, what)?;
        // `metadata` follows symbolic links and does not open the file, so a
        // FIFO is refused before `open` could block on it.
        let meta = std::fs::metadata(path)
            .map_err(|e| Refused(format!("cannot read {what} {}: {e}", path.display())))?;
        if !meta.is_file() {
            return Err(Refused(format!(
                "the {what} {} is not a regular file",
                path.display()
            )));
        }
        let limit = self.max_bytes.saturating_sub(self.bytes.get());
        if meta.len() > limit {
            return Err(Refused(format!(
                "the {what} {} has {} bytes, more than the {limit} bytes left of the scene memory budget of {} ({} bytes, --max-scene-memory)",
                path.display(),
                meta.len(),
                mib(self.max_bytes),
                self.max_bytes
            )));
        }
        let file = std::fs::File::open(path)
            .map_err(|e| Refused(format!("cannot read {what} {}: {e}", path.display())))?;
        let mut data = Vec::with_capacity(meta.len() as usize);
        // The file may grow between the two calls; read no more than was admitted.
        file.take(meta.len())
            .read_to_end(&mut data)
            .map_err(|e| Refused(format!("cannot read {what} {}: {e}", path.display())))?;
        self.bytes.set(self.bytes.get() + data.len() as u64);
        Ok(data)
    }

    /// Refuses `path` when paths are restricted and it resolves outside the
    /// scene's folder; a file that does not exist is left to the read.
    pub fn check_path(&self, path: &Path, what: &str) -> Result<(), Refused> {
        let Some(root) = &self.root else {
            return Ok(());
        };
        let Ok(resolved) = path.canonicalize() else {
            return Ok(());
        };
        if resolved.starts_with(root) {
            return Ok(());
        }
        Err(Refused(format!(
            "the {what} {} lies outside the scene's folder {} (--restrict-paths)",
            path.display(),
            root.display()
        )))
    }

    /// Admits a primitive of `vertices` vertices (with or without normals),
    /// `indices` indices and `triangles` triangles, or refuses it when the
    /// scene would then exceed the memory budget or the triangle limit.
    pub fn charge(
        &self,
        vertices: u64,
        normals: bool,
        indices: u64,
        triangles: u64,
    ) -> Result<(), Refused> {
        let per_vertex = BYTES_PER_VERTEX + if normals { BYTES_PER_NORMAL } else { 0 };
        let bytes = vertices
            .saturating_mul(per_vertex)
            .saturating_add(indices.saturating_mul(BYTES_PER_INDEX))
            .saturating_add(triangles.saturating_mul(12));
        let total = self.bytes.get().saturating_add(bytes);
        if total > self.max_bytes {
            return Err(Refused(format!(
                "the scene would need {} ({total} bytes) with this primitive of {vertices} vertices, more than the scene memory budget of {} ({} bytes, --max-scene-memory)",
                mib(total),
                mib(self.max_bytes),
                self.max_bytes
            )));
        }
        let tris = self.triangles.get().saturating_add(triangles);
        if tris > self.max_triangles {
            return Err(Refused(format!(
                "the scene would have {tris} triangles, more than the {} that the device can hold",
                self.max_triangles
            )));
        }
        self.bytes.set(total);
        self.triangles.set(tris);
        Ok(())
    }

    /// Admits `bytes` of decoded data (texture texels), or refuses them
    /// when the scene would then exceed the memory budget.
    pub fn charge_bytes(&self, bytes: u64) -> Result<(), Refused> {
        let total = self.bytes.get().saturating_add(bytes);
        if total > self.max_bytes {
            return Err(Refused(format!(
                "the scene would need {} ({total} bytes) with this image, more than the scene memory budget of {} ({} bytes, --max-scene-memory)",
                mib(total),
                mib(self.max_bytes),
                self.max_bytes
            )));
        }
        self.bytes.set(total);
        Ok(())
    }

    /// Admits a `width` × `height` texture, read from its image's header
    /// before it is decoded, whose load and upload allocate `transient`
    /// bytes for a while and `kept` bytes until the scene is uploaded
    /// ([`super::texture::texture_bytes`]): refused when its mip chain would
    /// take the scene's textures past the device's texture image
    /// ([`LoadOptions::max_texture_bytes`]) or both would take the scene
    /// past the memory budget; `kept` stays charged.
    pub fn charge_texture(
        &self,
        width: u32,
        height: u32,
        transient: u64,
        kept: u64,
    ) -> Result<(), Refused> {
        let size = format!("is {width}×{height} texels by its header");
        let device = crate::scene::Texture::device_bytes_of(width, height)
            .next_multiple_of(crate::vulkan::TEXEL_BYTES as u64);
        let textures = self.texture_bytes.get().saturating_add(device);
        if textures > self.max_texture_bytes {
            return Err(Refused(format!(
                "{size}: with their mip-maps the scene's textures would need {} up to this one, more than the {} this device's texture image holds (refused before decoding)",
                mib(textures),
                mib(self.max_texture_bytes)
            )));
        }
        let kept_total = self.bytes.get().saturating_add(kept);
        let peak = kept_total.saturating_add(transient);
        if peak > self.max_bytes {
            return Err(Refused(format!(
                "{size}: decoding and uploading it would take the scene to {} ({peak} bytes), more than the scene memory budget of {} ({} bytes, --max-scene-memory; refused before decoding)",
                mib(peak),
                mib(self.max_bytes),
                self.max_bytes
            )));
        }
        self.texture_bytes.set(textures);
        self.bytes.set(kept_total);
        Ok(())
    }

    /// Whether `extra` bytes more than those charged fit the budget, for a
    /// while (decoding images at once: module `gltf::decode`).
    pub fn fits(&self, extra: u64) -> bool {
        self.bytes.get().saturating_add(extra) <= self.max_bytes
    }

    /// Bytes charged so far (files read and geometry admitted).
    pub fn bytes(&self) -> u64 {
        self.bytes.get()
    }
}

/// `n` bytes in MiB for messages.
fn mib(n: u64) -> String {
    format!("{:.1} MiB", n as f64 / 1048576.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn opts(max_scene_bytes: u64, max_triangles: u64, restrict_paths: bool) -> LoadOptions {
        LoadOptions {
            max_scene_bytes,
            max_triangles,
            restrict_paths,
            ..Default::default()
        }
    }

    #[test]
    fn refuses_what_is_not_a_regular_file() {
        let g = Guard::new(Path::new("scene.json"), &LoadOptions::default());
        let err = g.read(Path::new("/dev/zero"), "buffer").unwrap_err();
        assert_eq!(err.0, "the buffer /dev/zero is not a regular file");
        let dir = tempfile::tempdir().unwrap();
        let err = g.read(dir.path(), "buffer").unwrap_err();
        assert!(err.0.ends_with("is not a regular file"), "{}", err.0);
    }

    #[test]
    fn refuses_a_file_larger_than_the_budget() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("big.bin");
        std::fs::write(&file, vec![0u8; 1000]).unwrap();
        let g = Guard::new(&dir.path().join("s.gltf"), &opts(999, 10, false));
        assert!(g
            .read(&file, "buffer")
            .unwrap_err()
            .0
            .contains("1000 bytes"));
        let g = Guard::new(&dir.path().join("s.gltf"), &opts(1000, 10, false));
        assert_eq!(g.read(&file, "buffer").unwrap().len(), 1000);
        assert_eq!(g.bytes(), 1000);
    }

    #[test]
    fn charges_geometry_against_both_limits() {
        let g = Guard::new(Path::new("s.gltf"), &opts(1000, 2, false));
        // 3 vertices with normals (3 * 96), 3 indices (36), 1 triangle (12).
        g.charge(3, true, 3, 1).unwrap();
        assert_eq!(g.bytes(), 336);
        g.charge(3, true, 3, 1).unwrap();
        assert!(g
            .charge(3, false, 3, 1)
            .unwrap_err()
            .0
            .contains("3 triangles"));
        let g = Guard::new(Path::new("s.gltf"), &opts(1000, 100, false));
        let err = g.charge(u64::MAX, true, 0, 0).unwrap_err();
        assert!(err.0.contains("scene memory budget"), "{}", err.0);
        // A refused charge leaves the totals as they were.
        assert_eq!(g.bytes(), 0);
    }

    #[test]
    fn restricted_paths_stay_inside_the_scene_folder() {
        let outer = tempfile::tempdir().unwrap();
        let inner = outer.path().join("scene");
        std::fs::create_dir(&inner).unwrap();
        std::fs::write(inner.join("in.bin"), b"x").unwrap();
        std::fs::write(outer.path().join("out.bin"), b"x").unwrap();
        let scene = inner.join("s.gltf");
        let g = Guard::new(&scene, &opts(1 << 20, 10, true));
        assert!(g.read(&inner.join("in.bin"), "buffer").is_ok());
        let err = g.read(&inner.join("../out.bin"), "buffer").unwrap_err();
        assert!(err.0.contains("outside the scene's folder"), "{}", err.0);
        // Unrestricted, the same file reads.
        let g = Guard::new(&scene, &opts(1 << 20, 10, false));
        assert!(g.read(&inner.join("../out.bin"), "buffer").is_ok());
    }
}
