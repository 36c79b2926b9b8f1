//! The user's cache directory, where penumbra keeps what it measured or
//! built for this machine (the calibration, the pipeline cache) and where
//! Mesa keeps its shader cache by default.

use std::ffi::OsString;
use std::path::PathBuf;

/// `$XDG_CACHE_HOME`, else `$HOME/.cache` (the XDG base directory rule, as
/// Mesa's own cache follows it); `None` without either. `var` reads the
/// environment.
pub fn user_cache_dir(var: impl Fn(&str) -> Option<OsString>) -> Option<PathBuf> {
    let nonempty = |k: &str| var(k).filter(|v| !v.is_empty()).map(PathBuf::from);
    nonempty("XDG_CACHE_HOME").or_else(|| nonempty("HOME").map(|h| h.join(".cache")))
}

/// penumbra's own folder in it: `penumbra/`.
pub fn penumbra_dir(var: impl Fn(&str) -> Option<OsString>) -> Option<PathBuf> {
    user_cache_dir(var).map(|d| d.join("penumbra"))
}
