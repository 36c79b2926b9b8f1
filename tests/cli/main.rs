//! The tests that run a program as a user would: the `penumbra` binary
//! (`CARGO_BIN_EXE_penumbra`) on good and bad input, the farm commands, the
//! watch command and its live page, and `tools/setup.sh`. One test binary,
//! one module per command or concern; each test starts its own processes,
//! so nothing is shared between them in this process.
//!
//! One concern: `cargo test --test cli bad_input::` (docs/tests.md).

#[path = "../base64/mod.rs"]
mod base64;
#[path = "../watch_support/mod.rs"]
mod watch_support;

mod area_light_input;
mod bad_input;
mod calibrate;
mod default_lighting;
mod docs_flags;
mod environment;
mod escaping;
mod farm_batch;
mod farm_slurm;
mod farm_split;
mod gltf_materials;
mod gltf_render;
mod json_textures;
mod metrics;
mod pipeline_cache;
mod preview_process;
mod setup_script;
mod vector_width;
mod watch;
mod watch_browser;
mod watchdog;
