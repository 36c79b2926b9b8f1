//! Recording, submitting and waiting for work on the compute queue.

use super::buffer::{Buffer, BufferUsage};
use super::context::Context;
use super::image::TexelImage;
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

/// What a dispatch binds at one binding of set 0.
#[derive(Clone, Copy)]
pub enum Resource<'a> {
    /// A storage or uniform buffer.
    Buffer(&'a Buffer),
    /// A texel image.
    Image(&'a TexelImage),
}

impl<'a> From<&'a Buffer> for Resource<'a> {
    fn from(buffer: &'a Buffer) -> Self {
        Resource::Buffer(buffer)
    }
}

impl<'a> From<&'a TexelImage> for Resource<'a> {
    fn from(image: &'a TexelImage) -> Self {
        Resource::Image(image)
    }
}

impl Resource<'_> {
    fn label(&self) -> &str {
        match self {
            Resource::Buffer(b) => b.label(),
            Resource::Image(i) => i.label(),
        }
    }
}

/// One dispatch of a chain ([`Context::dispatch_chain`]).
#[derive(Clone, Copy)]
pub struct Dispatch<'a> {
    /// The pipeline.
    pub pipeline: &'a ComputePipeline,
    /// `resources[i]` is bound at binding `i` of set 0.
    pub resources: &'a [Resource<'a>],
    /// Push constants (as many bytes as the pipeline takes).
    pub push_constants: &'a [u8],
    /// Workgroups.
    pub groups: [u32; 3],
}

impl Resource<'_> {
    /// The Vulkan handle bound, to tell whether two dispatches bind the same.
    fn handle(&self) -> u64 {
        use ash::vk::Handle;
        match self {
            Resource::Buffer(b) => b.handle.as_raw(),
            Resource::Image(i) => i.view.as_raw(),
        }
    }
}

impl Context {
    /// Binds `resources[i]` at binding `i` of set 0 (must match the pipeline's bindings in number
    /// and type), pushes `push_constants` (len == the pipeline's push_constant_size), dispatches
    /// `groups` workgroups, submits and waits for completion. Returns the wall time from submit
    /// to fence signalled.
    pub fn dispatch(
        &self,
        pipeline: &ComputePipeline,
        resources: &[Resource],
        push_constants: &[u8],
        groups: [u32; 3],
    ) -> Result<Duration, VulkanError> {
        self.dispatch_chain(&[Dispatch {
            pipeline,
            resources,
            push_constants,
            groups,
        }])
    }

    /// Records `chain` into one command buffer, in order, with a memory barrier after each
    /// dispatch (each sees the writes of those before it), submits it and waits. A pipeline that
    /// appears more than once must bind the same resources each time (its one descriptor set is
    /// written once). Returns the wall time from submit to fence signalled.
    pub fn dispatch_chain(&self, chain: &[Dispatch]) -> Result<Duration, VulkanError> {
        self.dispatch_chain_within(chain, self.time_limit())
    }

    /// [`Context::dispatch`] with its own time limit instead of [`Context::time_limit`]: for
    /// the first dispatch of a pipeline, which waits for the driver's compile (lavapipe
    /// compiles at the first dispatch).
    pub fn dispatch_within(
        &self,
        pipeline: &ComputePipeline,
        resources: &[Resource],
        push_constants: &[u8],
        groups: [u32; 3],
        limit: Duration,
    ) -> Result<Duration, VulkanError> {
        let chain = [Dispatch {
            pipeline,
            resources,
            push_constants,
            groups,
        }];
        self.dispatch_chain_within(&chain, limit)
    }

    /// [`Context::dispatch_chain`] waiting at most `limit`.
    fn dispatch_chain_within(
        &self,
        chain: &[Dispatch],
        limit: Duration,
    ) -> Result<Duration, VulkanError> {
        let mut written: Vec<(vk::DescriptorSet, Vec<u64>)> = Vec::new();
        for d in chain {
            self.check_dispatch(d.pipeline, d.resources, d.push_constants, d.groups)?;
            let handles: Vec<u64> = d.resources.iter().map(Resource::handle).collect();
            match written.iter().find(|(set, _)| *set == d.pipeline.set) {
                Some((_, h)) if *h != handles => {
                    return Err(VulkanError::InvalidArgument(
                        "a pipeline appears twice in one dispatch chain with different resources"
                            .into(),
                    ))
                }
                Some(_) => {}
                None => written.push((d.pipeline.set, handles)),
            }
        }
        let mut buffer_infos: Vec<[vk::DescriptorBufferInfo; 1]> = Vec::new();
        let mut image_infos: Vec<[vk::DescriptorImageInfo; 1]> = Vec::new();
        let mut updates: Vec<(vk::DescriptorSet, u32, vk::DescriptorType, bool, usize)> =
            Vec::new();
        let mut seen: Vec<vk::DescriptorSet> = Vec::new();
        for d in chain {
            if seen.contains(&d.pipeline.set) {
                continue;
            }
            seen.push(d.pipeline.set);
            for (i, (binding, resource)) in d.pipeline.bindings.iter().zip(d.resources).enumerate()
            {
                let (is_buffer, at) = match resource {
                    Resource::Buffer(b) => {
                        buffer_infos.push([vk::DescriptorBufferInfo::default()
                            .buffer(b.handle)
                            .range(vk::WHOLE_SIZE)]);
                        (true, buffer_infos.len() - 1)
                    }
                    Resource::Image(img) => {
                        image_infos.push([vk::DescriptorImageInfo::default()
                            .image_view(img.view)
                            .image_layout(vk::ImageLayout::GENERAL)]);
                        (false, image_infos.len() - 1)
                    }
                };
                updates.push((
                    d.pipeline.set,
                    i as u32,
                    binding.descriptor_type(),
                    is_buffer,
                    at,
                ));
            }
        }
        let writes: Vec<_> = updates
            .iter()
            .map(|&(set, binding, ty, is_buffer, at)| {
                let write = vk::WriteDescriptorSet::default()
                    .dst_set(set)
                    .dst_binding(binding)
                    .descriptor_type(ty);
                if is_buffer {
                    write.buffer_info(&buffer_infos[at])
                } else {
                    write.image_info(&image_infos[at])
                }
            })
            .collect();
        // SAFETY: everything was checked above; the sets are updated under the submit lock, while
        // no earlier dispatch can still be using them (each submission is waited for).
        self.submit_within(limit, |device, cmd| unsafe {
            if !writes.is_empty() {
                device.update_descriptor_sets(&writes, &[]);
            }
            let bind = vk::PipelineBindPoint::COMPUTE;
            for d in chain {
                let pipeline = d.pipeline;
                if !pipeline.bindings.is_empty() {
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
                if !d.push_constants.is_empty() {
                    let stage = vk::ShaderStageFlags::COMPUTE;
                    device.cmd_push_constants(cmd, pipeline.layout, stage, 0, d.push_constants);
                }
                device.cmd_dispatch(cmd, d.groups[0], d.groups[1], d.groups[2]);
                memory_barrier(device, cmd, vk::PipelineStageFlags::COMPUTE_SHADER);
            }
        })
    }

    /// Validates a dispatch so that the driver never sees a mismatch.
    fn check_dispatch(
        &self,
        pipeline: &ComputePipeline,
        resources: &[Resource],
        push_constants: &[u8],
        groups: [u32; 3],
    ) -> Result<(), VulkanError> {
        let invalid = |msg: String| Err(VulkanError::InvalidArgument(msg));
        if !Arc::ptr_eq(&pipeline.shared, &self.shared) {
            return invalid("the pipeline belongs to another Vulkan context".into());
        }
        if resources.len() != pipeline.bindings.len() {
            return invalid(format!(
                "the pipeline has {} bindings but {} resources were given",
                pipeline.bindings.len(),
                resources.len()
            ));
        }
        for (i, (resource, binding)) in resources.iter().zip(&pipeline.bindings).enumerate() {
            let given = match resource {
                Resource::Buffer(buffer) => {
                    self.check_owned(buffer)?;
                    match buffer.usage() {
                        Some(BufferUsage::Storage) => "storage buffer",
                        Some(BufferUsage::Uniform) => "uniform buffer",
                        None => "staging buffer",
                    }
                }
                Resource::Image(image) => {
                    self.check_owned_image(image)?;
                    "texel image"
                }
            };
            let matches = match (binding, resource) {
                (BindingType::Uniform, Resource::Buffer(b)) => {
                    b.usage() == Some(BufferUsage::Uniform)
                }
                (
                    BindingType::StorageReadOnly | BindingType::StorageReadWrite,
                    Resource::Buffer(b),
                ) => b.usage() == Some(BufferUsage::Storage),
                (BindingType::TexelImage | BindingType::StageImage, Resource::Image(_)) => true,
                _ => false,
            };
            if !matches {
                return invalid(format!(
                    "binding {i} is {binding:?} but '{}' is a {given}",
                    resource.label()
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
        self.submit_within(self.time_limit(), record)
    }

    /// [`Context::submit`], waiting at most `limit`: past it, the work keeps running (it
    /// cannot be cancelled), the device is marked hung and [`VulkanError::TimedOut`] returned.
    fn submit_within(
        &self,
        limit: Duration,
        record: impl FnOnce(&ash::Device, vk::CommandBuffer),
    ) -> Result<Duration, VulkanError> {
        let submitter = self.submitter.lock().unwrap_or_else(|e| e.into_inner());
        if self.shared.is_hung() {
            return Err(VulkanError::TimedOut { limit });
        }
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
                    let nanos = u64::try_from(limit.as_nanos()).unwrap_or(u64::MAX);
                    match device.wait_for_fences(&[fence], true, nanos) {
                        // The work cannot be cancelled: it keeps the queue, the command
                        // buffer and the fence; nothing it may use is freed from now on.
                        Err(vk::Result::TIMEOUT) => {
                            self.shared.mark_hung();
                            Err(VulkanError::TimedOut { limit })
                        }
                        r => r.map_err(vk_err("vkWaitForFences")),
                    }
                });
            let elapsed = start.elapsed();
            self.record_wait(elapsed);
            if !self.shared.is_hung() {
                device.destroy_fence(fence, None);
            }
            result.map(|()| elapsed)
        }
    }
}
