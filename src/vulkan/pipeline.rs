//! Compute pipelines built from SPIR-V words, with one descriptor set (set 0) of buffers and
//! texel images.

use super::context::{Context, DeviceShared};
use super::{vk_err, VulkanError};
use ash::vk;
use std::ffi::CString;
use std::sync::Arc;

/// How binding `i` of set 0 is declared in the shader.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BindingType {
    /// `var<storage, read>`: a storage buffer the shader only reads.
    StorageReadOnly,
    /// `var<storage, read_write>`: a storage buffer the shader writes.
    StorageReadWrite,
    /// `var<uniform>`: a uniform buffer.
    Uniform,
    /// `texture_storage_2d<rgba32uint, read>`: a [`super::TexelImage`].
    TexelImage,
    /// A [`super::TexelImage`] that some pipelines write
    /// (`texture_storage_2d<rgba32uint, write>`) and others read.
    StageImage,
}

impl BindingType {
    pub(crate) fn descriptor_type(self) -> vk::DescriptorType {
        match self {
            BindingType::StorageReadOnly | BindingType::StorageReadWrite => {
                vk::DescriptorType::STORAGE_BUFFER
            }
            BindingType::Uniform => vk::DescriptorType::UNIFORM_BUFFER,
            BindingType::TexelImage | BindingType::StageImage => vk::DescriptorType::STORAGE_IMAGE,
        }
    }
}

/// A compute pipeline plus the descriptor set it is dispatched with.
pub struct ComputePipeline {
    pub(crate) shared: Arc<DeviceShared>,
    pub(crate) pipeline: vk::Pipeline,
    pub(crate) layout: vk::PipelineLayout,
    set_layout: vk::DescriptorSetLayout,
    pool: vk::DescriptorPool,
    /// Rewritten by every dispatch; safe because dispatches are serialised and waited for.
    pub(crate) set: vk::DescriptorSet,
    pub(crate) bindings: Vec<BindingType>,
    pub(crate) push_constant_size: u32,
}

impl Drop for ComputePipeline {
    fn drop(&mut self) {
        if self.shared.is_hung() {
            // Work that may use it still runs on the device: leak it.
            return;
        }
        // SAFETY: dispatches wait for completion, so nothing is in flight; null handles are no-ops.
        unsafe {
            let device = &self.shared.device;
            device.destroy_pipeline(self.pipeline, None);
            device.destroy_pipeline_layout(self.layout, None);
            device.destroy_descriptor_pool(self.pool, None);
            device.destroy_descriptor_set_layout(self.set_layout, None);
        }
    }
}

/// Checks the SPIR-V header and that it declares a GLCompute entry point named `name`, so that
/// malformed input is reported here instead of crashing the driver.
fn check_spirv(spirv: &[u32], name: &str) -> Result<(), VulkanError> {
    const MAGIC: u32 = 0x0723_0203;
    const OP_ENTRY_POINT: u32 = 15;
    const GL_COMPUTE: u32 = 5;
    if spirv.len() < 5 || spirv[0] != MAGIC {
        return Err(VulkanError::InvalidArgument(
            "shader is not SPIR-V (bad header)".into(),
        ));
    }
    let mut rest = &spirv[5..];
    let mut entry_points = Vec::new();
    while let Some(&first) = rest.first() {
        let (count, opcode) = ((first >> 16) as usize, first & 0xffff);
        let Some(instruction) = rest.get(..count).filter(|_| count > 0) else {
            return Err(VulkanError::InvalidArgument(
                "shader SPIR-V is truncated".into(),
            ));
        };
        if opcode == OP_ENTRY_POINT && instruction.len() > 3 && instruction[1] == GL_COMPUTE {
            // The name is a nul-terminated UTF-8 literal packed little-endian into words.
            let bytes: Vec<u8> = instruction[3..]
                .iter()
                .flat_map(|w| w.to_le_bytes())
                .collect();
            let end = bytes.iter().position(|&b| b == 0).unwrap_or(bytes.len());
            entry_points.push(String::from_utf8_lossy(&bytes[..end]).into_owned());
        }
        rest = &rest[count..];
    }
    if entry_points.iter().any(|e| e == name) {
        Ok(())
    } else {
        Err(VulkanError::InvalidArgument(format!(
            "shader has no compute entry point '{name}' (found: {})",
            entry_points.join(", ")
        )))
    }
}

impl Context {
    /// Creates a compute pipeline with one descriptor set (set 0) whose binding i has type
    /// `bindings[i]`, and a push-constant range of `push_constant_size` bytes (0 = none) visible to
    /// the compute stage.
    pub fn create_compute_pipeline(
        &self,
        spirv: &[u32],
        entry_point: &str,
        bindings: &[BindingType],
        push_constant_size: u32,
    ) -> Result<ComputePipeline, VulkanError> {
        check_spirv(spirv, entry_point)?;
        let max_push = self.limits().max_push_constants_size;
        if !push_constant_size.is_multiple_of(4) || push_constant_size > max_push {
            return Err(VulkanError::Limit(format!(
                "push constants of {push_constant_size} bytes must be a multiple of 4 and at most this device's maxPushConstantsSize of {max_push} bytes"
            )));
        }
        let entry = CString::new(entry_point).map_err(|_| {
            VulkanError::InvalidArgument("entry point name contains a nul byte".into())
        })?;

        let device = &self.shared.device;
        // Each handle is stored in `result` as soon as it exists, so an early return destroys it.
        let mut result = ComputePipeline {
            shared: self.shared.clone(),
            pipeline: vk::Pipeline::null(),
            layout: vk::PipelineLayout::null(),
            set_layout: vk::DescriptorSetLayout::null(),
            pool: vk::DescriptorPool::null(),
            set: vk::DescriptorSet::null(),
            bindings: bindings.to_vec(),
            push_constant_size,
        };
        let layout_bindings: Vec<_> = bindings
            .iter()
            .enumerate()
            .map(|(i, b)| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(i as u32)
                    .descriptor_type(b.descriptor_type())
                    .descriptor_count(1)
                    .stage_flags(vk::ShaderStageFlags::COMPUTE)
            })
            .collect();
        let info = vk::DescriptorSetLayoutCreateInfo::default().bindings(&layout_bindings);
        // SAFETY (this block and below): create infos point to locals that outlive each call.
        result.set_layout = unsafe { device.create_descriptor_set_layout(&info, None) }
            .map_err(vk_err("vkCreateDescriptorSetLayout"))?;

        if !bindings.is_empty() {
            // One pool size per binding: simpler than summing per type, and equally valid.
            let pool_sizes: Vec<_> = bindings
                .iter()
                .map(|b| vk::DescriptorPoolSize {
                    ty: b.descriptor_type(),
                    descriptor_count: 1,
                })
                .collect();
            let info = vk::DescriptorPoolCreateInfo::default()
                .max_sets(1)
                .pool_sizes(&pool_sizes);
            result.pool = unsafe { device.create_descriptor_pool(&info, None) }
                .map_err(vk_err("vkCreateDescriptorPool"))?;
            let set_layouts = [result.set_layout];
            let info = vk::DescriptorSetAllocateInfo::default()
                .descriptor_pool(result.pool)
                .set_layouts(&set_layouts);
            let sets = unsafe { device.allocate_descriptor_sets(&info) }
                .map_err(vk_err("vkAllocateDescriptorSets"))?;
            result.set = sets.first().copied().unwrap_or_default();
        }

        let set_layouts = [result.set_layout];
        let ranges = [vk::PushConstantRange::default()
            .stage_flags(vk::ShaderStageFlags::COMPUTE)
            .size(push_constant_size)];
        let ranges = if push_constant_size > 0 {
            &ranges[..]
        } else {
            &[]
        };
        let info = vk::PipelineLayoutCreateInfo::default()
            .set_layouts(&set_layouts)
            .push_constant_ranges(ranges);
        result.layout = unsafe { device.create_pipeline_layout(&info, None) }
            .map_err(vk_err("vkCreatePipelineLayout"))?;

        let info = vk::ShaderModuleCreateInfo::default().code(spirv);
        let module = unsafe { device.create_shader_module(&info, None) }
            .map_err(vk_err("vkCreateShaderModule"))?;
        let stage = vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::COMPUTE)
            .module(module)
            .name(&entry);
        let info = [vk::ComputePipelineCreateInfo::default()
            .stage(stage)
            .layout(result.layout)];
        let created =
            unsafe { device.create_compute_pipelines(self.shared.pipeline_cache, &info, None) };
        // The module is only needed while the pipeline is being created.
        unsafe { device.destroy_shader_module(module, None) };
        let pipelines =
            created.map_err(|(_, result)| VulkanError::vk("vkCreateComputePipelines", result))?;
        result.pipeline = pipelines.first().copied().unwrap_or_default();
        Ok(result)
    }
}
