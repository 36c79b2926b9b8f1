//! Runs the buffer and dispatch tests, and whole renders, through the staging path
//! (`PENUMBRA_FORCE_STAGING=1`), so the code used on discrete GPUs (device memory the host cannot
//! map) is exercised on lavapipe too. Its own test binary, and one test, because the variable is
//! process-global and read when a context opens.

#[path = "gpu/support.rs"]
mod support;
#[path = "gpu/vulkan_kernel.rs"]
mod vulkan_kernel;
use vulkan_kernel as common;

use penumbra::render::{Renderer, RendererOptions};
use penumbra::vulkan::*;

#[test]
fn staging_path_round_trip_dispatch_and_renders() {
    // A render of every primitive, light and shader kind through mapped
    // memory, before the variable is set, to compare with staging below.
    let showcase = support::load(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/showcase.json"),
    );
    // Validation on when the suite asks for it (CI), as for the shared renderer.
    let options = RendererOptions {
        validation: std::env::var("PENUMBRA_VALIDATION").as_deref() == Ok("1"),
        ..Default::default()
    };
    let mapped = Renderer::new(&options)
        .expect("a Vulkan device")
        .render_scene(&showcase)
        .expect("mapped render");

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

    // The staging buffers are kept between transfers (vulkan::MAX_KEPT_STAGING): a smaller
    // upload through the 1 MiB one kept from the pattern gets its own bytes and zeros, never
    // the pattern's, and a larger one after it gets a new buffer.
    let short = ctx
        .create_buffer_with_data("short", BufferUsage::Storage, &[0xab; 10])
        .unwrap();
    let mut want = vec![0xab; 10];
    want.resize(16, 0);
    assert_eq!(ctx.read_buffer(&short).unwrap(), want);
    let large = common::pattern(3 << 20);
    let buffer = ctx
        .create_buffer_with_data("large", BufferUsage::Storage, &large)
        .unwrap();
    assert_eq!(ctx.read_buffer(&buffer).unwrap(), large);
    assert_eq!(ctx.read_buffer(&short).unwrap(), want);

    let run = common::run_kernel(&ctx);
    assert!(!run.input.is_host_visible() && !run.output.is_host_visible());
    assert!(!run.params.is_host_visible());
    ctx.check_validation().unwrap();

    // Whole renders through staging: the showcase matches the mapped render
    // exactly, and the benchmark scene matches Embree's independent counts
    // (tests/gpu/bunny.rs).
    let staged = Renderer::new(&options)
        .expect("a Vulkan device")
        .render_scene(&showcase)
        .expect("staging render");
    assert_eq!(staged.image.pixels, mapped.image.pixels);
    assert_eq!(staged.stats.shadow_rays, mapped.stats.shadow_rays);
    let frame = support::render_with(
        &support::tagged_bunny_scene(),
        Default::default(),
        Default::default(),
    );
    let [bunny, ground, _, ground_dark] = support::bunny_counts(&frame.image);
    assert_eq!(bunny + ground, 858_452);
    assert!(ground_dark.abs_diff(31_540) <= 2, "{ground_dark}");
}
