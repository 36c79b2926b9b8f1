//! The `--device` argument of the tools that render: an index from
//! `penumbra devices` or part of a device's name, parsed into the library's
//! [`DeviceSelector`] so that every tool accepts and rejects the same
//! spellings as the `penumbra` command.

use penumbra::render::{Renderer, RendererOptions};
use penumbra::vulkan::DeviceSelector;

/// The `--device` option, to flatten into a tool's clap arguments. Kept as
/// the text the user wrote, so that a tool can hand it on to child processes.
#[derive(clap::Args, Clone, Debug, Default)]
pub struct DeviceArg {
    /// Vulkan device: an index from `penumbra devices`, or part of its name.
    #[arg(long)]
    pub device: Option<String>,
}

impl DeviceArg {
    /// The parsed selector; `None` picks the renderer's default device.
    pub fn selector(&self) -> anyhow::Result<Option<DeviceSelector>> {
        parse(self.device.as_deref())
    }

    /// A renderer on the selected device with default options.
    pub fn renderer(&self) -> anyhow::Result<Renderer> {
        Ok(Renderer::new(&RendererOptions {
            device: self.selector()?,
            ..Default::default()
        })?)
    }
}

/// Parses a `--device` value; the error names the option.
pub fn parse(arg: Option<&str>) -> anyhow::Result<Option<DeviceSelector>> {
    arg.map(|d| d.parse::<DeviceSelector>())
        .transpose()
        .map_err(|e| anyhow::anyhow!("--device: {e}"))
}
