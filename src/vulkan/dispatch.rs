//! Recording, submitting and waiting for work on the compute queue.

use super::buffer::{Buffer, BufferUsage};
use super::context::Context;
use super::pipeline::{BindingType, ComputePipeline};
use super::{vk_err, VulkanError};
use ash::vk;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Makes the writes of `src_stage` (shader writes after a dispatch, otherwise transfer writes)
/// visible to every later use of a buffer: shader access in the next dispatch, staging copies
/// and host reads.
///
/// # Safety
/// `cmd` must be a command buffer of `device` in the recording state.
pub(crate) unsafe fn memory_barrier(
    device: &ash::Device,
    cmd: vk::CommandBuffer,
    src_stage: vk::PipelineStageFlags,
) {
    use vk::{AccessFlags as A, PipelineStageFlags as S};
    let src_access = if src_stage == S::COMPUTE_SHADER {
        A::SHADER_WRITE
    } else {
        A::TRANSFER_WRITE
    };
    let dst_access = A::SHADER_READ
        | A::SHADER_WRITE
        | A::UNIFORM_READ
        | A::TRANSFER_READ
        | A::TRANSFER_WRITE
        | A::HOST_READ;
    let barrier = [vk::MemoryBarrier::default()
        .src_access_mask(src_access)
        .dst_access_mask(dst_access)];
    let dst_stage = S::COMPUTE_SHADER | S::TRANSFER | S::HOST;
    let flags = vk::DependencyFlags::empty();
    unsafe { device.cmd_pipeline_barrier(cmd, src_stage, dst_stage, flags, &barrier, &[], &[]) };
}

impl Context {
    /// Binds `buffers[i]` at binding `i` of set 0 (must match the pipeline's bindings in number and
    /// usage), pushes `push_constants` (len == the pipeline's push_constant_size), dispatches
    /// `groups` workgroups, submits and waits for completion. Returns the wall time from submit
    /// to fence signalled.
    pub fn dispatch(
        &self,
        pipeline: &ComputePipeline,
        buffers: &[&Buffer],
        push_constants: &[u8],
        groups: [u32; 3],
    ) -> Result<Duration, VulkanError> {
        self.check_dispatch(pipeline, buffers, push_constants, groups)?;
        let infos: Vec<[vk::DescriptorBufferInfo; 1]> = buffers
            .iter()
            .map(|b| {
                [vk::DescriptorBufferInfo::default()
                    .buffer(b.handle)
                    .range(vk::WHOLE_SIZE)]
            })
            .collect();
        let writes: Vec<_> = pipeline
            .bindings
            .iter()
            .zip(&infos)
            .enumerate()
            .map(|(i, (binding, info))| {
                vk::WriteDescriptorSet::default()
                    .dst_set(pipeline.set)
                    .dst_binding(i as u32)
                    .descriptor_type(binding.descriptor_type())
                    .buffer_info(info)
            })
            .collect();
        // SAFETY: everything was checked above; the set is updated under the submit lock, while
        // no earlier dispatch can still be using it (each one is waited for).
        self.submit(|device, cmd| unsafe {
            let bind = vk::PipelineBindPoint::COMPUTE;
            if !writes.is_empty() {
                device.update_descriptor_sets(&writes, &[]);
                device.cmd_bind_descriptor_sets(
                    cmd,
                    bind,
                    pipeline.layout,
                    0,
                    &[pipeline.set],
                    &[],
                );
            }
            device.cmd_bind_pipeline(cmd, bind, pipeline.pipeline);
            if !push_constants.is_empty() {
                let stage = vk::ShaderStageFlags::COMPUTE;
                device.cmd_push_constants(cmd, pipeline.layout, stage, 0, push_constants);
            }
            device.cmd_dispatch(cmd, groups[0], groups[1], groups[2]);
            memory_barrier(device, cmd, vk::PipelineStageFlags::COMPUTE_SHADER);
        })
    }

    /// Validates a dispatch so that the driver never sees a mismatch.
    fn check_dispatch(
        &self,
        pipeline: &ComputePipeline,
        buffers: &[&Buffer],
        push_constants: &[u8],
        groups: [u32; 3],
    ) -> Result<(), VulkanError> {
        let invalid = |msg: String| Err(VulkanError::InvalidArgument(msg));
        if !Arc::ptr_eq(&pipeline.shared, &self.shared) {
            return invalid("the pipeline belongs to another Vulkan context".into());
        }
        if buffers.len() != pipeline.bindings.len() {
            return invalid(format!(
                "the pipeline has {} bindings but {} buffers were given",
                pipeline.bindings.len(),
                buffers.len()
            ));
        }
        for (i, (buffer, binding)) in buffers.iter().zip(&pipeline.bindings).enumerate() {
            self.check_owned(buffer)?;
            let wanted = match binding {
                BindingType::Uniform => BufferUsage::Uniform,
                BindingType::StorageReadOnly | BindingType::StorageReadWrite => {
                    BufferUsage::Storage
                }
            };
            if buffer.usage() != Some(wanted) {
                return invalid(format!(
                    "binding {i} is {binding:?} but buffer '{}' was created as {:?}",
                    buffer.label(),
                    buffer.usage()
                ));
            }
        }
        if push_constants.len() != pipeline.push_constant_size as usize {
            return invalid(format!(
                "the pipeline takes {} bytes of push constants but {} were given",
                pipeline.push_constant_size,
                push_constants.len()
            ));
        }
        let max = self.limits().max_compute_work_group_count;
        if groups.iter().zip(&max).any(|(g, m)| g > m) {
            return Err(VulkanError::Limit(format!(
                "dispatch of {groups:?} workgroups exceeds this device's maxComputeWorkGroupCount of {max:?}"
            )));
        }
        Ok(())
    }

    /// Records commands with `record`, submits them and waits for them to finish. Returns the
    /// time from submit to fence signalled. Serialised by the submitter lock, which also guards
    /// the queue and command buffer (Vulkan requires external synchronisation of both).
    pub(crate) fn submit(
        &self,
        record: impl FnOnce(&ash::Device, vk::CommandBuffer),
    ) -> Result<Duration, VulkanError> {
        let submitter = self.submitter.lock().unwrap_or_else(|e| e.into_inner());
        let device = &self.shared.device;
        let cmd = submitter.command_buffer;
        let begin = vk::CommandBufferBeginInfo::default()
            .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
        // SAFETY: the command buffer is not pending (every submit below is waited for) and we
        // hold the lock that serialises its use.
        unsafe {
            device
                .reset_command_buffer(cmd, vk::CommandBufferResetFlags::empty())
                .map_err(vk_err("vkResetCommandBuffer"))?;
            device
                .begin_command_buffer(cmd, &begin)
                .map_err(vk_err("vkBeginCommandBuffer"))?;
            record(device, cmd);
            device
                .end_command_buffer(cmd)
                .map_err(vk_err("vkEndCommandBuffer"))?;
            let fence = device
                .create_fence(&vk::FenceCreateInfo::default(), None)
                .map_err(vk_err("vkCreateFence"))?;
            let cmds = [cmd];
            let submit = [vk::SubmitInfo::default().command_buffers(&cmds)];
            let start = Instant::now();
            let result = device
                .queue_submit(submitter.queue, &submit, fence)
                .map_err(vk_err("vkQueueSubmit"))
                .and_then(|()| {
                    device
                        .wait_for_fences(&[fence], true, u64::MAX)
                        .map_err(vk_err("vkWaitForFences"))
                });
            let elapsed = start.elapsed();
            device.destroy_fence(fence, None);
            result.map(|()| elapsed)
        }
    }
}
