//! The tests that drive the library's Vulkan renderer in this process: one
//! test binary, one module per concept. They share one device and one kernel
//! cache ([`support::renderer`], opened by the first test that asks for it);
//! a test that switches the shared renderer's kernel, stage memory or band
//! cap holds its lock until it has switched them back. They need a Vulkan
//! device (lavapipe in CI) and fail loudly when there is none; they never
//! skip.
//!
//! One concept: `cargo test --test gpu shading::` (docs/tests.md).

#[path = "../base64/mod.rs"]
mod base64;
mod support;
mod vulkan_kernel;
#[path = "../watch_support/mod.rs"]
mod watch_support;

mod aov;
mod area_lights;
mod bands;
mod bunny;
mod camera;
mod checker;
mod default_light;
mod double_sided;
mod environment;
mod gltf_materials;
mod hard_cases;
mod json_textures;
mod khronos;
mod large_scenes;
mod lights;
mod metallic_roughness;
mod occlusion;
mod output;
mod packet;
mod precision;
mod preview;
mod reference;
mod shading;
mod shadows;
mod stages;
mod textures;
mod tiles;
mod unlit_colours;
mod user_shaders;
mod vulkan;
mod watch_loop;
mod watch_stages;
