//! Helpers shared by the Vulkan integration tests: a small WGSL kernel compiled with naga and a
//! dispatch that checks every output value.
#![allow(dead_code)]

use penumbra::vulkan::*;

/// Uses a read-only storage input, a read-write storage output, a uniform and push constants.
pub const KERNEL: &str = r#"
struct Params { scale: f32, offset: f32, count: u32, pad: u32 }
struct Push { add: u32, mul: f32 }
@group(0) @binding(0) var<storage, read> input: array<f32>;
@group(0) @binding(1) var<storage, read_write> output: array<f32>;
@group(0) @binding(2) var<uniform> params: Params;
var<immediate> pc: Push;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= params.count { return; }
    output[i] = input[i] * params.scale + params.offset + f32(i + pc.add) * pc.mul;
}
"#;

/// The kernel's bindings, in binding order.
pub const BINDINGS: [BindingType; 3] = [
    BindingType::StorageReadOnly,
    BindingType::StorageReadWrite,
    BindingType::Uniform,
];
pub const N: u32 = 1000;
const SCALE: f32 = 2.0;
const OFFSET: f32 = 3.0;
const ADD: u32 = 7;
const MUL: f32 = 0.25;

/// Compiles WGSL to SPIR-V 1.3 without debug info.
pub fn compile(source: &str) -> Vec<u32> {
    use naga::back::spv;
    use naga::proc::{BoundsCheckPolicies, BoundsCheckPolicy};
    use naga::valid::{Capabilities, ValidationFlags, Validator};
    let module = naga::front::wgsl::parse_str(source).expect("WGSL parses");
    let info = Validator::new(ValidationFlags::all(), Capabilities::IMMEDIATES)
        .validate(&module)
        .expect("WGSL validates");
    let policy = BoundsCheckPolicy::ReadZeroSkipWrite;
    let options = spv::Options {
        lang_version: (1, 3),
        flags: spv::WriterFlags::empty(),
        bounds_check_policies: BoundsCheckPolicies {
            index: policy,
            buffer: policy,
            image_load: policy,
            binding_array: policy,
        },
        ..Default::default()
    };
    spv::write_vec(&module, &info, &options, None).expect("SPIR-V generation")
}

/// The buffers of one kernel run, returned so that callers can inspect them.
pub struct Run {
    pub input: Buffer,
    pub output: Buffer,
    pub params: Buffer,
}

/// Runs the kernel over N elements in workgroups of 64 and checks every output value.
pub fn run_kernel(ctx: &Context) -> Run {
    let spirv = compile(KERNEL);
    let pipeline = ctx
        .create_compute_pipeline(&spirv, "main", &BINDINGS, 8)
        .expect("pipeline");
    let input_values: Vec<f32> = (0..N).map(|i| i as f32 * 0.5).collect();
    let input = ctx
        .create_buffer_with_data(
            "input",
            BufferUsage::Storage,
            bytemuck::cast_slice(&input_values),
        )
        .expect("input buffer");
    let output = ctx
        .create_buffer("output", BufferUsage::Storage, u64::from(N) * 4)
        .expect("output buffer");
    let params: [u32; 4] = [SCALE.to_bits(), OFFSET.to_bits(), N, 0];
    let params = ctx
        .create_buffer_with_data(
            "params",
            BufferUsage::Uniform,
            bytemuck::cast_slice(&params),
        )
        .expect("uniform buffer");
    let push: [u32; 2] = [ADD, MUL.to_bits()];
    let groups = N.div_ceil(64);
    ctx.dispatch(
        &pipeline,
        &[(&input).into(), (&output).into(), (&params).into()],
        bytemuck::cast_slice(&push),
        [groups, 1, 1],
    )
    .expect("dispatch");
    let bytes = ctx.read_buffer(&output).expect("readback");
    assert_eq!(bytes.len(), N as usize * 4);
    let got: &[f32] = bytemuck::cast_slice(&bytes);
    for (i, (&g, &x)) in got.iter().zip(&input_values).enumerate() {
        // All values are exactly representable, so the comparison can be exact.
        let want = x * SCALE + OFFSET + (i as u32 + ADD) as f32 * MUL;
        assert_eq!(g, want, "output[{i}]");
    }
    Run {
        input,
        output,
        params,
    }
}

/// 1 MiB of bytes with a pattern that differs between neighbouring and distant positions.
pub fn pattern(len: usize) -> Vec<u8> {
    (0..len).map(|i| (i * 7 + i / 251) as u8).collect()
}
