//! `penumbra devices`: the Vulkan devices the loader finds.

use anyhow::Context as _;

use penumbra::vulkan::Context;

pub fn run() -> anyhow::Result<()> {
    let list = Context::list_devices().context("listing Vulkan devices")?;
    for d in list {
        println!(
            "{}: {} ({}), Vulkan {}, driver {} {}",
            d.index, d.name, d.device_type, d.api_version, d.driver_name, d.driver_info
        );
    }
    Ok(())
}
