//! Why a frame could not be rendered.

use std::path::PathBuf;
use std::time::Duration;

use super::compile::CompileError;
use crate::vulkan::VulkanError;

/// Why a frame could not be rendered.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// Vulkan failed or a device limit was exceeded.
    #[error(transparent)]
    Vulkan(#[from] VulkanError),
    /// The WGSL did not compile.
    /// (Not a `source()` as well: `anyhow`'s `{:#}` would print it twice.)
    #[error("shader error: {0}")]
    Compile(CompileError),
    /// The scene asks for more than the device can do; `field` names the
    /// scene field (e.g. `camera.width`).
    #[error("{field}: {message}")]
    Scene {
        /// The offending scene field.
        field: String,
        /// What limit it exceeds.
        message: String,
    },
    /// A user shader file's `struct Params` no longer matches the parameters
    /// uploaded with the scene: the scene must be loaded again (`penumbra
    /// watch` does so).
    #[error("shader error: {file}: its Params changed since the scene was loaded: save the scene file to reload it")]
    ParamsChanged {
        /// The shader file.
        file: String,
    },
    /// The request's `cancel` said to stop ([`super::RenderRequest::cancel`]):
    /// no frame, and nothing is wrong.
    #[error("the render was cancelled")]
    Cancelled,
    /// Work on the device ran past its time limit: a shader that does not
    /// end or far too much work in one submission, or (`compile`) a driver
    /// compile that did not end. The device keeps running it
    /// ([`VulkanError::TimedOut`]): only ending the process frees it.
    #[error("{}", timed_out_message(what, *.compile, *.limit))]
    TimedOut {
        /// What was running: `scenes/shaders/loop.wgsl: the shade stage` for
        /// user files, else the engine stages.
        what: String,
        /// The user shader files among them (empty: only engine stages).
        user_files: Vec<PathBuf>,
        /// Whether it was the driver's compile (the first dispatch of a
        /// pipeline) rather than a frame's work.
        compile: bool,
        /// The limit.
        limit: Duration,
    },
}

fn timed_out_message(what: &str, compile: bool, limit: Duration) -> String {
    let limit = crate::vulkan::describe_limit(limit);
    match compile {
        true => {
            format!("{what}: the driver's compile ran past {limit}: is the shader far too large?")
        }
        false => format!(
            "{what} ran past the time limit of {limit} (--time-limit): a loop that never ends?"
        ),
    }
}

impl RenderError {
    /// Whether the device is left running work it could not finish in time
    /// ([`RenderError::TimedOut`] or a [`VulkanError::TimedOut`] of a
    /// transfer): the process must end to free it.
    pub fn is_timeout(&self) -> bool {
        matches!(
            self,
            RenderError::TimedOut { .. } | RenderError::Vulkan(VulkanError::TimedOut { .. })
        )
    }
}

/// Whether `e` (or an error it wraps) is a time-out of the device
/// ([`RenderError::is_timeout`]).
pub fn is_timeout(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<RenderError>()
            .is_some_and(RenderError::is_timeout)
            || matches!(
                c.downcast_ref::<VulkanError>(),
                Some(VulkanError::TimedOut { .. })
            )
    })
}

impl From<CompileError> for RenderError {
    fn from(e: CompileError) -> Self {
        RenderError::Compile(e)
    }
}
