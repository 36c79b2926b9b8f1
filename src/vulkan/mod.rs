//! Vulkan compute backend: the only module in penumbra that talks to Vulkan (through `ash`).
//!
//! A [`Context`] owns the instance, the logical device and one compute queue. Buffers, texel
//! images and pipelines created from it share the device through reference counting, so they may be
//! dropped in any order relative to the context. Every fallible operation returns
//! [`VulkanError`]; nothing in here panics on bad input or a missing driver.

mod buffer;
mod context;
mod dispatch;
mod image;
mod pipeline;

pub use buffer::{Buffer, BufferUsage};
pub use context::{Context, ContextOptions, DeviceInfo, DeviceLimits, DeviceSelector};
pub use dispatch::{Dispatch, Resource};
pub use image::{TexelImage, TEXEL_BYTES, TEXEL_ROW};
pub use pipeline::{BindingType, ComputePipeline};

/// Everything that can go wrong in the Vulkan backend.
#[derive(Debug, thiserror::Error)]
pub enum VulkanError {
    /// The Vulkan loader library could not be opened.
    #[error("cannot load the Vulkan loader ({0}). Install the loader and Mesa's CPU driver lavapipe with `sudo tools/setup.sh` (Debian/Ubuntu: `sudo apt-get install libvulkan1 mesa-vulkan-drivers`)")]
    NoLoader(String),
    /// The loader works but reports no usable device (Vulkan 1.1 with a compute queue).
    #[error("no Vulkan device found. Install Mesa's CPU driver lavapipe with `sudo tools/setup.sh` (Debian/Ubuntu: `sudo apt-get install mesa-vulkan-drivers`)")]
    NoDevice,
    /// A [`DeviceSelector`] matched none of the usable devices.
    #[error("no Vulkan device matches '{wanted}'; available: {available}")]
    NoMatchingDevice {
        /// The selector as the user wrote it.
        wanted: String,
        /// The usable devices, formatted as `0: name, 1: name`.
        available: String,
    },
    /// A Vulkan call returned an error code.
    #[error("{what} failed: {result}")]
    Vk {
        /// The Vulkan function that failed.
        what: &'static str,
        /// The error code it returned.
        result: ash::vk::Result,
    },
    /// A request exceeds a device limit or could not be satisfied for lack of memory; the
    /// message names the resource, the limit and both numbers.
    #[error("{0}")]
    Limit(String),
    /// The caller passed arguments that do not fit together (e.g. buffers that do not match a
    /// pipeline's bindings). Caught here so that the driver never sees invalid usage.
    #[error("{0}")]
    InvalidArgument(String),
    /// Validation was requested but `VK_LAYER_KHRONOS_validation` is not installed.
    #[error("the Khronos validation layer was requested but is not installed (Debian: apt-get install vulkan-validationlayers)")]
    ValidationLayerMissing,
    /// The validation layer reported errors (see [`Context::check_validation`]).
    #[error("Vulkan validation layer reported {count} error(s); first: {first}")]
    Validation {
        /// Number of error-severity messages recorded.
        count: usize,
        /// The first of them.
        first: String,
    },
}

/// Builds a `map_err` closure turning a raw Vulkan result into [`VulkanError::Vk`].
pub(crate) fn vk_err(what: &'static str) -> impl Fn(ash::vk::Result) -> VulkanError {
    move |result| VulkanError::Vk { what, result }
}
