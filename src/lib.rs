#![warn(missing_docs)]
//! penumbra: a headless ray tracer whose rendering runs entirely in Vulkan
//! compute shaders — on Mesa's CPU driver lavapipe by default, and on any
//! Vulkan 1.1 GPU when there is one.
//!
//! The crate follows the seminar "Shaders, shading and shadows":
//!
//! * [`scene`] is the plain, validated scene model (camera, primitives, lights,
//!   shading models), independent of Vulkan;
//! * [`bvh`] builds the bounding volume hierarchy the kernel traverses;
//! * [`loaders`] build it from JSON scene files and glTF 2.0 files;
//! * [`render`] turns it into GPU buffers and a specialised compute kernel
//!   (WGSL from `shaders/`, compiled by naga) and runs it through
//! * [`vulkan`], the only module that talks to Vulkan (`ash`);
//! * [`reference`](mod@reference) renders the same image on the CPU in `f64`
//!   (the ground truth for error figures);
//! * [`output`] writes PNG (sRGB) and OpenEXR (linear) files atomically;
//! * [`farm`] splits a render into parts for a batch engine and merges them.
//!
//! ```no_run
//! use penumbra::{loaders, render::{Renderer, RendererOptions}};
//! let loaded = loaders::load_scene(std::path::Path::new("scenes/showcase.json"), &Default::default())?;
//! let mut renderer = Renderer::new(&RendererOptions::default())?;
//! let frame = renderer.render_scene(&loaded.scene)?;
//! penumbra::output::write_image(std::path::Path::new("showcase.png"), &frame.image)?;
//! # Ok::<(), anyhow::Error>(())
//! ```

pub mod brdf;
pub mod bvh;
pub mod calibration;
pub mod error;
pub mod farm;
pub mod frame;
pub mod loaders;
pub mod metrics;
pub mod output;
pub mod panics;
pub mod reference;
pub mod render;
pub mod scene;
pub mod terminal;
pub mod tonemap;
pub mod user_cache;
pub mod vector_width;
pub mod vulkan;
pub mod watch;
pub mod wgsl;

pub use error::SceneError;
