//! What penumbra's tools share: statistics of repeated timings, the
//! `--device` argument, the machine's load and CPU from `/proc`, the plots'
//! font and PNG output, and the meshes the benchmarks generate. Each tool is
//! a binary of this package (`tools/measure/Cargo.toml`); this library keeps them
//! from carrying their own copies of these helpers.

pub mod device;
pub mod load;
pub mod machine;
pub mod meshes;
pub mod plot;
pub mod stats;

use std::path::PathBuf;
use std::time::Duration;

pub use stats::Stat;

/// A duration in milliseconds, the unit every tool reports times in.
pub fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

/// The repository root: the tools read `scenes/`, `shaders/` and
/// `tests/data/` from it wherever they are run from.
pub fn repo_root() -> PathBuf {
    // This crate is tools/measure/, two folders below the root.
    let tools = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    tools
        .ancestors()
        .nth(2)
        .map_or(tools.clone(), |p| p.to_path_buf())
}
