//! The WGSL layer, below both the loaders and the renderer: what penumbra
//! knows of shader files written as WGSL, before any device is involved.
//!
//! - [`lexer`], [`scan`], [`limits`], [`footprint`], [`stack`]: the bounds a
//!   user's file is held to before and while naga reads it (user shaders
//!   are untrusted code);
//! - [`reflect`]: what a file declares (its `Params`, `ambient`, `prepare`)
//!   and where its errors are, as `FILE:LINE:COL` with the source line.
//!
//! [`reflect()`] runs once per file text: the loader (at load and reload)
//! and the renderer (at upload and pipeline build) share its cache.

pub mod footprint;
pub mod lexer;
pub mod limits;
pub mod reflect;
pub mod scan;
pub mod stack;

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Mutex, OnceLock};

pub use reflect::{Location, Reflection, ShaderFileError};

/// File texts whose reflection the cache keeps; past it, it starts again.
/// Each text is at most [`limits::MAX_SOURCE_BYTES`], so the cache holds at
/// most a few MiB.
const CACHED_TEXTS: usize = 32;

/// Reflections by (path, text): the path is part of the key because error
/// messages name it.
#[derive(Default)]
struct ReflectionCache {
    map: Mutex<HashMap<(PathBuf, String), Result<Reflection, ShaderFileError>>>,
    /// How many reflections were computed (not taken from the cache).
    computed: AtomicUsize,
}

impl ReflectionCache {
    fn reflect(&self, path: &Path, source: &str) -> Result<Reflection, ShaderFileError> {
        let key = (path.to_path_buf(), source.to_string());
        if let Some(r) = self.map.lock().ok().and_then(|c| c.get(&key).cloned()) {
            return r;
        }
        let r = reflect::reflect(path, source);
        self.computed.fetch_add(1, Ordering::Relaxed);
        if let Ok(mut c) = self.map.lock() {
            if c.len() >= CACHED_TEXTS {
                c.clear();
            }
            c.insert(key, r.clone());
        }
        r
    }
}

/// What the shader file `path` with text `source` declares
/// ([`reflect::reflect`]), computed once per (path, text) and then taken
/// from the cache that the loader and the renderer share.
pub fn reflect(path: &Path, source: &str) -> Result<Reflection, ShaderFileError> {
    static CACHE: OnceLock<ReflectionCache> = OnceLock::new();
    CACHE
        .get_or_init(ReflectionCache::default)
        .reflect(path, source)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_file_text_is_reflected_once_and_then_taken_from_the_cache() {
        let cache = ReflectionCache::default();
        let path = Path::new("toon.wgsl");
        let text = "fn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32> { return vec3<f32>(0.25); }\n";
        let first = cache.reflect(path, text);
        assert!(first.is_ok(), "{first:?}");
        assert_eq!(cache.reflect(path, text), first);
        assert_eq!(cache.computed.load(Ordering::Relaxed), 1);
        // Another text of the file, or the text under another name (errors
        // name the file), is reflected on its own.
        let _ = cache.reflect(path, &format!("{text}// edited\n"));
        let _ = cache.reflect(Path::new("other.wgsl"), text);
        assert_eq!(cache.computed.load(Ordering::Relaxed), 3);
        // An error is kept as well.
        let bad = Path::new("bad.wgsl");
        assert!(cache.reflect(bad, "fn shade(").is_err());
        assert!(cache.reflect(bad, "fn shade(").is_err());
        assert_eq!(cache.computed.load(Ordering::Relaxed), 4);
    }
}
