//! Integration tests of the Vulkan backend. They need a Vulkan device (lavapipe in CI) and fail,
//! rather than skip, when none is found.

use crate::vulkan_kernel as common;

use penumbra::vulkan::*;

fn context() -> Context {
    Context::new(&ContextOptions::default()).expect("a Vulkan device (install lavapipe)")
}

#[test]
fn lists_lavapipe() {
    let devices = Context::list_devices().expect("device list");
    assert!(!devices.is_empty());
    for (i, d) in devices.iter().enumerate() {
        assert_eq!(d.index, i);
        assert!(d.api_version.starts_with("1."), "{d:?}");
    }
    let lavapipe = devices
        .iter()
        .find(|d| d.name.contains("llvmpipe"))
        .expect("lavapipe is listed");
    assert_eq!(lavapipe.device_type, "CPU");
    assert!(lavapipe.driver_info.contains("Mesa"), "{lavapipe:?}");
    assert_eq!(lavapipe.driver_name, "llvmpipe");
}

#[test]
fn context_reports_device_and_limits() {
    let ctx = context();
    let limits = ctx.limits();
    assert!(limits.max_storage_buffer_range >= 1 << 27);
    assert!(limits.max_uniform_buffer_range >= 16 << 10);
    assert!(limits.max_push_constants_size >= 128);
    assert!(limits.max_compute_work_group_invocations >= 128);
    assert!(limits.max_memory_allocation_size >= 1 << 30);
    assert!(limits.max_compute_work_group_count[0] >= 65535);
    assert!(!ctx.info().name.is_empty());
}

#[test]
fn buffer_round_trip() {
    let ctx = context();
    let data = common::pattern(1 << 20);
    let buffer = ctx
        .create_buffer_with_data("pattern", BufferUsage::Storage, &data)
        .unwrap();
    assert_eq!(buffer.size(), 1 << 20);
    assert_eq!(buffer.label(), "pattern");
    assert_eq!(ctx.read_buffer(&buffer).unwrap(), data);

    let zeros = ctx
        .create_buffer("zeros", BufferUsage::Storage, 4099)
        .unwrap();
    assert_eq!(ctx.read_buffer(&zeros).unwrap(), vec![0u8; 4099]);

    let empty = ctx
        .create_buffer_with_data("empty", BufferUsage::Storage, &[])
        .unwrap();
    assert_eq!(empty.size(), 16);
    assert_eq!(ctx.read_buffer(&empty).unwrap(), vec![0u8; 16]);
    let small = ctx.create_buffer("small", BufferUsage::Uniform, 0).unwrap();
    assert_eq!(ctx.read_buffer(&small).unwrap(), vec![0u8; 16]);
    ctx.check_validation().unwrap();
}

#[test]
fn compute_dispatch() {
    let ctx = context();
    let run = common::run_kernel(&ctx);
    // On lavapipe all memory is host-visible, so the direct path runs here.
    if ctx.info().device_type == "CPU" {
        assert!(run.output.is_host_visible());
    }
    ctx.check_validation().unwrap();
}

#[test]
fn compute_dispatch_with_validation() {
    let ctx = Context::new(&ContextOptions {
        validation: true,
        ..Default::default()
    })
    .expect("a Vulkan device with the validation layer");
    common::run_kernel(&ctx);
    ctx.check_validation().unwrap();
}

#[test]
fn limits_are_enforced() {
    let ctx = context();
    let limits = *ctx.limits();
    let too_big = limits.max_storage_buffer_range + 1;
    match ctx.create_buffer("huge", BufferUsage::Storage, too_big) {
        Err(VulkanError::Limit(msg)) => {
            assert!(
                msg.contains("'huge'") && msg.contains("maxStorageBufferRange"),
                "{msg}"
            );
        }
        other => panic!("expected a Limit error, got {:?}", other.map(|b| b.size())),
    }
    let too_big = limits.max_uniform_buffer_range + 1;
    let err = ctx
        .create_buffer("ubo", BufferUsage::Uniform, too_big)
        .err();
    assert!(matches!(err, Some(VulkanError::Limit(_))), "{err:?}");

    let spirv = common::compile(common::KERNEL);
    let bindings = common::BINDINGS;
    let pipeline = ctx
        .create_compute_pipeline(&spirv, "main", &bindings, 8)
        .unwrap();
    let storage = ctx.create_buffer("s", BufferUsage::Storage, 64).unwrap();
    let uniform = ctx.create_buffer("u", BufferUsage::Uniform, 16).unwrap();
    let buffers: [Resource; 3] = [(&storage).into(), (&storage).into(), (&uniform).into()];
    let push = [0u8; 8];

    let over = limits.max_compute_work_group_count[0].checked_add(1);
    if let Some(over) = over {
        let err = ctx.dispatch(&pipeline, &buffers, &push, [over, 1, 1]).err();
        assert!(matches!(err, Some(VulkanError::Limit(_))), "{err:?}");
    }
    let err = ctx
        .dispatch(&pipeline, &buffers[..2], &push, [1, 1, 1])
        .err();
    assert!(
        matches!(err, Some(VulkanError::InvalidArgument(_))),
        "{err:?}"
    );
    let wrong_usage: [Resource; 3] = [(&storage).into(), (&storage).into(), (&storage).into()];
    let err = ctx
        .dispatch(&pipeline, &wrong_usage, &push, [1, 1, 1])
        .err();
    assert!(
        matches!(err, Some(VulkanError::InvalidArgument(_))),
        "{err:?}"
    );
    let err = ctx
        .dispatch(&pipeline, &buffers, &push[..4], [1, 1, 1])
        .err();
    assert!(
        matches!(err, Some(VulkanError::InvalidArgument(_))),
        "{err:?}"
    );
    // A correct dispatch still works after the rejected ones.
    ctx.dispatch(&pipeline, &buffers, &push, [1, 1, 1]).unwrap();

    // Bad shader input is reported, not passed to the driver.
    let err = ctx
        .create_compute_pipeline(&spirv, "nope", &bindings, 8)
        .err();
    assert!(
        matches!(err, Some(VulkanError::InvalidArgument(_))),
        "{err:?}"
    );
    let err = ctx
        .create_compute_pipeline(&[1, 2, 3], "main", &bindings, 8)
        .err();
    assert!(
        matches!(err, Some(VulkanError::InvalidArgument(_))),
        "{err:?}"
    );
    let mut truncated = spirv[..5].to_vec();
    truncated.push((10 << 16) | 15); // an OpEntryPoint claiming 10 words
    let err = ctx
        .create_compute_pipeline(&truncated, "main", &bindings, 8)
        .err();
    assert!(
        matches!(err, Some(VulkanError::InvalidArgument(_))),
        "{err:?}"
    );
    let push_limit = limits.max_push_constants_size + 4;
    let err = ctx
        .create_compute_pipeline(&spirv, "main", &bindings, push_limit)
        .err();
    assert!(matches!(err, Some(VulkanError::Limit(_))), "{err:?}");

    // Objects of another context are rejected.
    let other = context();
    let foreign = other
        .create_buffer("foreign", BufferUsage::Storage, 64)
        .unwrap();
    let err = ctx.read_buffer(&foreign).err();
    assert!(
        matches!(err, Some(VulkanError::InvalidArgument(_))),
        "{err:?}"
    );
    let err = other
        .dispatch(
            &pipeline,
            &[(&foreign).into(), (&foreign).into(), (&uniform).into()],
            &push,
            [1, 1, 1],
        )
        .err();
    assert!(
        matches!(err, Some(VulkanError::InvalidArgument(_))),
        "{err:?}"
    );
    ctx.check_validation().unwrap();
    other.check_validation().unwrap();
}

#[test]
fn device_selection() {
    assert_eq!(
        "0".parse::<DeviceSelector>().unwrap(),
        DeviceSelector::Index(0)
    );
    assert_eq!(
        "llvm".parse::<DeviceSelector>().unwrap(),
        DeviceSelector::Name("llvm".into())
    );
    assert_eq!(
        "".parse::<DeviceSelector>().unwrap(),
        DeviceSelector::Name(String::new())
    );

    let by_name = Context::new(&ContextOptions {
        device: Some("LLVMpipe".parse().unwrap()),
        validation: false,
    })
    .unwrap();
    assert!(by_name.info().name.contains("llvmpipe"));
    let index = by_name.info().index;
    let by_index = Context::new(&ContextOptions {
        device: Some(DeviceSelector::Index(index)),
        validation: false,
    })
    .unwrap();
    assert_eq!(by_index.info().name, by_name.info().name);

    for wanted in [
        DeviceSelector::Name("no such gpu".into()),
        DeviceSelector::Index(99),
    ] {
        let opts = ContextOptions {
            device: Some(wanted),
            validation: false,
        };
        match Context::new(&opts) {
            Err(e @ VulkanError::NoMatchingDevice { .. }) => {
                let msg = e.to_string();
                assert!(msg.contains("0: ") && msg.contains("llvmpipe"), "{msg}");
            }
            other => panic!("expected NoMatchingDevice, got {:?}", other.err()),
        }
    }
}

#[test]
fn objects_outlive_their_context() {
    let ctx = context();
    let buffer = ctx.create_buffer("late", BufferUsage::Storage, 64).unwrap();
    let spirv = common::compile(common::KERNEL);
    let pipeline = ctx
        .create_compute_pipeline(&spirv, "main", &common::BINDINGS, 8)
        .unwrap();
    drop(ctx);
    drop(pipeline);
    drop(buffer);
}

#[test]
fn types_are_thread_safe() {
    fn send_sync<T: Send + Sync>() {}
    send_sync::<Context>();
    send_sync::<Buffer>();
    send_sync::<ComputePipeline>();
    send_sync::<VulkanError>();
}

#[test]
fn validation_errors_are_reported() {
    let ctx = Context::new(&ContextOptions {
        validation: true,
        ..Default::default()
    })
    .unwrap();
    // SPIR-V 1.6 is not allowed with Vulkan 1.1: the layer flags it, the driver copes.
    let mut spirv = common::compile(common::KERNEL);
    spirv[1] = 0x0001_0600;
    let bindings = common::BINDINGS;
    let _ = ctx.create_compute_pipeline(&spirv, "main", &bindings, 8);
    match ctx.check_validation() {
        Err(VulkanError::Validation { count, first }) => assert!(count >= 1 && !first.is_empty()),
        other => panic!("expected validation errors, got {other:?}"),
    }
    // Reading the errors clears them.
    ctx.check_validation().unwrap();
}

/// Copies texel `i` of a texel image (at the coordinates the renderer's
/// kernel computes, `i % TEXEL_ROW`, `i / TEXEL_ROW`) to `output[i]`.
const TEXEL_COPY: &str = r#"
@group(0) @binding(0) var texels: texture_storage_2d<rgba32uint, read>;
@group(0) @binding(1) var<storage, read_write> output: array<vec4<u32>>;
@compute @workgroup_size(256)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&output) { return; }
    output[i] = textureLoad(texels, vec2<u32>(i % 4096u, i / 4096u));
}
"#;

/// A texel image larger than one staging band ([`MAX_KEPT_STAGING`]) is
/// uploaded band by band (issue 36: a gigabyte of textures is not staged
/// whole): every texel reads back, across the band boundary and in the
/// last, partial band.
#[test]
fn texel_image_larger_than_a_staging_band_round_trips() {
    let ctx = context();
    let bindings = [BindingType::TexelImage, BindingType::StorageReadWrite];
    let pipeline = ctx
        .create_compute_pipeline(&common::compile(TEXEL_COPY), "main", &bindings, 0)
        .unwrap();
    let band_rows = (MAX_KEPT_STAGING / (TEXEL_ROW as u64 * TEXEL_BYTES as u64)) as usize;
    let texels = (band_rows + 1) * TEXEL_ROW as usize + TEXEL_ROW as usize / 2;
    let data = common::pattern(texels * TEXEL_BYTES);
    let image = ctx.create_texel_image("two bands", &data).unwrap();
    let output = ctx
        .create_buffer("output", BufferUsage::Storage, data.len() as u64)
        .unwrap();
    let groups = (texels as u32).div_ceil(256);
    ctx.dispatch(
        &pipeline,
        &[(&image).into(), (&output).into()],
        &[],
        [groups, 1, 1],
    )
    .unwrap();
    let got = ctx.read_buffer(&output).unwrap();
    assert!(got == data, "texels differ after the first band");
}

/// Texel images: every texel reads back through `textureLoad` at the
/// coordinates the renderer's kernel computes (`i % TEXEL_ROW`,
/// `i / TEXEL_ROW`), across a row boundary and in the zero-padded tail; an
/// empty image still binds; and bad sizes and mismatched bindings are errors.
#[test]
fn texel_image_round_trip() {
    assert_eq!(TEXEL_ROW, 4096, "TEXEL_COPY hard-codes the row length");
    let ctx = context();
    let bindings = [BindingType::TexelImage, BindingType::StorageReadWrite];
    let pipeline = ctx
        .create_compute_pipeline(&common::compile(TEXEL_COPY), "main", &bindings, 0)
        .unwrap();
    // One and a half rows of texels, then half a row of the padding.
    let texels = TEXEL_ROW as usize * 3 / 2;
    let read = texels + TEXEL_ROW as usize / 2;
    let data = common::pattern(texels * TEXEL_BYTES);
    let image = ctx.create_texel_image("pattern", &data).unwrap();
    assert_eq!(image.texels(), texels as u64);
    assert_eq!(image.label(), "pattern");
    assert_eq!(image.size(), 2 * TEXEL_ROW as u64 * TEXEL_BYTES as u64);
    let output = ctx
        .create_buffer("output", BufferUsage::Storage, (read * TEXEL_BYTES) as u64)
        .unwrap();
    let groups = (read as u32).div_ceil(256);
    ctx.dispatch(
        &pipeline,
        &[(&image).into(), (&output).into()],
        &[],
        [groups, 1, 1],
    )
    .unwrap();
    let got = ctx.read_buffer(&output).unwrap();
    assert_eq!(&got[..data.len()], &data[..], "stored texels");
    assert!(got[data.len()..].iter().all(|&b| b == 0), "padding reads 0");

    let empty = ctx.create_texel_image("empty", &[]).unwrap();
    assert_eq!(empty.texels(), 0);
    ctx.dispatch(
        &pipeline,
        &[(&empty).into(), (&output).into()],
        &[],
        [1, 1, 1],
    )
    .unwrap();
    assert!(ctx.read_buffer(&output).unwrap()[..16]
        .iter()
        .all(|&b| b == 0));

    let err = ctx.create_texel_image("odd", &[0u8; 20]).err();
    assert!(
        matches!(&err, Some(VulkanError::InvalidArgument(m)) if m.contains("'odd'")),
        "{err:?}"
    );
    // A buffer where the pipeline wants an image, and the other way round.
    let err = ctx
        .dispatch(
            &pipeline,
            &[(&output).into(), (&output).into()],
            &[],
            [1, 1, 1],
        )
        .err();
    assert!(
        matches!(&err, Some(VulkanError::InvalidArgument(m)) if m.contains("binding 0 is TexelImage but 'output' is a storage buffer")),
        "{err:?}"
    );
    let err = ctx
        .dispatch(
            &pipeline,
            &[(&image).into(), (&image).into()],
            &[],
            [1, 1, 1],
        )
        .err();
    assert!(
        matches!(&err, Some(VulkanError::InvalidArgument(m)) if m.contains("binding 1 is StorageReadWrite but 'pattern' is a texel image")),
        "{err:?}"
    );
    // An image of another context is rejected.
    let other = context();
    let foreign = other.create_texel_image("foreign", &data).unwrap();
    let err = ctx
        .dispatch(
            &pipeline,
            &[(&foreign).into(), (&output).into()],
            &[],
            [1, 1, 1],
        )
        .err();
    assert!(
        matches!(&err, Some(VulkanError::InvalidArgument(m)) if m.contains("'foreign'")),
        "{err:?}"
    );
    ctx.check_validation().unwrap();
    other.check_validation().unwrap();
}
