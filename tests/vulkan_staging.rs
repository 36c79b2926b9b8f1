//! Runs the buffer and dispatch tests through the staging path (`PENUMBRA_FORCE_STAGING=1`), so
//! the code used on discrete GPUs is exercised on lavapipe too. Its own test binary because the
//! variable is process-global.

mod vulkan_kernel;
use vulkan_kernel as common;

use penumbra::vulkan::*;

#[test]
fn staging_path_round_trip_and_dispatch() {
    std::env::set_var("PENUMBRA_FORCE_STAGING", "1");
    let ctx = Context::new(&ContextOptions::default()).expect("a Vulkan device");

    let data = common::pattern(1 << 20);
    let buffer = ctx
        .create_buffer_with_data("pattern", BufferUsage::Storage, &data)
        .unwrap();
    assert!(!buffer.is_host_visible(), "staging path must be used");
    assert_eq!(ctx.read_buffer(&buffer).unwrap(), data);

    // Odd size: zeroing covers the last partial word too.
    let zeros = ctx
        .create_buffer("zeros", BufferUsage::Storage, 4099)
        .unwrap();
    assert!(!zeros.is_host_visible());
    assert_eq!(ctx.read_buffer(&zeros).unwrap(), vec![0u8; 4099]);

    let empty = ctx
        .create_buffer_with_data("empty", BufferUsage::Uniform, &[])
        .unwrap();
    assert_eq!(ctx.read_buffer(&empty).unwrap(), vec![0u8; 16]);

    let run = common::run_kernel(&ctx);
    assert!(!run.input.is_host_visible() && !run.output.is_host_visible());
    assert!(!run.params.is_host_visible());
    ctx.check_validation().unwrap();
}
