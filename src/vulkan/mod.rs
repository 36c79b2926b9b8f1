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
pub mod pipeline_cache;

pub use buffer::{Buffer, BufferUsage, MAX_KEPT_STAGING};
pub use context::{
    Context, ContextOptions, DeviceInfo, DeviceLimits, DeviceSelector, DEFAULT_TIME_LIMIT,
    DRIVER_COMPILE_LIMIT,
};
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
        result: VkCode,
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
    /// Work on the device ran past the time limit ([`Context::set_time_limit`]). A running
    /// dispatch cannot be cancelled: the device is left running it, every later submit fails
    /// with this error, and only ending the process frees it.
    #[error("the device did not finish within the time limit of {}", crate::vulkan::describe_limit(*.limit))]
    TimedOut {
        /// The limit that was exceeded.
        limit: std::time::Duration,
    },
}

/// A time limit as messages give it: `10 s`, `0.5 s`.
pub fn describe_limit(limit: std::time::Duration) -> String {
    format!("{} s", limit.as_secs_f64())
}

/// A Vulkan result code as the rest of penumbra sees it: the number, its
/// name and its description, so that no caller outside this module depends
/// on `ash`'s types (and on its version).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct VkCode {
    /// The `VkResult` value, e.g. -2 for `VK_ERROR_OUT_OF_DEVICE_MEMORY`.
    pub code: i32,
    /// The name without the `VK_` prefix, e.g. `ERROR_OUT_OF_DEVICE_MEMORY`.
    pub name: String,
    /// The description the error message shows (the specification's text
    /// where the code has one, otherwise the name).
    pub description: String,
}

impl From<ash::vk::Result> for VkCode {
    fn from(result: ash::vk::Result) -> VkCode {
        VkCode {
            code: result.as_raw(),
            name: format!("{result:?}"),
            description: result.to_string(),
        }
    }
}

impl std::fmt::Display for VkCode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.description)
    }
}

impl VulkanError {
    /// [`VulkanError::Vk`] for the Vulkan function `what` that returned `result`.
    pub(crate) fn vk(what: &'static str, result: ash::vk::Result) -> VulkanError {
        VulkanError::Vk {
            what,
            result: result.into(),
        }
    }
}

/// Builds a `map_err` closure turning a raw Vulkan result into [`VulkanError::Vk`].
pub(crate) fn vk_err(what: &'static str) -> impl Fn(ash::vk::Result) -> VulkanError {
    move |result| VulkanError::vk(what, result)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vk_errors_read_as_ash_formats_the_code() {
        let r = ash::vk::Result::ERROR_OUT_OF_DEVICE_MEMORY;
        let e = VulkanError::vk("vkAllocateMemory", r);
        assert_eq!(e.to_string(), format!("vkAllocateMemory failed: {r}"));
        let VulkanError::Vk { result, .. } = e else {
            panic!("not a Vk error")
        };
        assert_eq!(result.code, -2);
        assert_eq!(result.name, "ERROR_OUT_OF_DEVICE_MEMORY");
    }
}
