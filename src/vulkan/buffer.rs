//! Device buffers, their memory, and host upload/readback (mapped directly or via staging).

use super::context::{Context, DeviceShared};
use super::dispatch::memory_barrier;
use super::{vk_err, VulkanError};
use ash::vk;
use std::ptr::NonNull;
use std::sync::Arc;

/// How shaders bind a buffer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BufferUsage {
    /// Storage buffer (`var<storage>`), read-only or read-write.
    Storage,
    /// Uniform buffer (`var<uniform>`).
    Uniform,
}

/// What a buffer is for, which decides its usage flags and memory type.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Role {
    Device(BufferUsage),
    Upload,
    Readback,
}

/// A Vulkan buffer with its own dedicated memory allocation.
pub struct Buffer {
    pub(crate) shared: Arc<DeviceShared>,
    pub(crate) handle: vk::Buffer,
    memory: vk::DeviceMemory,
    /// Size requested by the caller (at least 16); the Vulkan buffer is rounded up to 4 bytes.
    size: u64,
    vk_size: u64,
    label: String,
    role: Role,
    /// Persistent mapping when the host accesses the memory directly.
    mapped: Option<NonNull<u8>>,
    coherent: bool,
}

// SAFETY: the mapping pointer is only written during creation (before the Buffer is shared) and
// otherwise only read from; every Vulkan handle in here may be used from any thread.
unsafe impl Send for Buffer {}
unsafe impl Sync for Buffer {}

impl Buffer {
    /// Size in bytes (at least 16, as Vulkan forbids empty buffers).
    pub fn size(&self) -> u64 {
        self.size
    }

    /// The label given at creation, used in error messages.
    pub fn label(&self) -> &str {
        &self.label
    }

    /// True when the host maps the buffer's memory directly; false when uploads and readbacks go
    /// through a temporary staging buffer (device-only memory, or `PENUMBRA_FORCE_STAGING=1`).
    pub fn is_host_visible(&self) -> bool {
        self.mapped.is_some()
    }

    /// The usage shaders bind this buffer with (None for internal staging buffers).
    pub(crate) fn usage(&self) -> Option<BufferUsage> {
        match self.role {
            Role::Device(usage) => Some(usage),
            Role::Upload | Role::Readback => None,
        }
    }

    /// The persistent mapping; an error for buffers that go through staging.
    fn mapping(&self) -> Result<NonNull<u8>, VulkanError> {
        self.mapped
            .ok_or_else(|| VulkanError::vk("vkMapMemory", vk::Result::ERROR_MEMORY_MAP_FAILED))
    }

    /// Writes `data` followed by zeros into the mapped memory.
    fn write_mapped(&self, data: &[u8]) -> Result<(), VulkanError> {
        self.write_mapped_prefix(data, self.vk_size)
    }

    /// Writes `data` followed by zeros up to byte `end` (at most the buffer's size) into the
    /// mapped memory: a kept staging buffer larger than the transfer is written only as far
    /// as the copy reads.
    fn write_mapped_prefix(&self, data: &[u8], end: u64) -> Result<(), VulkanError> {
        let ptr = self.mapping()?;
        let end = end.min(self.vk_size) as usize;
        let len = data.len().min(end);
        // SAFETY: the mapping covers vk_size >= end bytes and nothing else accesses it now.
        unsafe {
            std::ptr::copy_nonoverlapping(data.as_ptr(), ptr.as_ptr(), len);
            std::ptr::write_bytes(ptr.as_ptr().add(len), 0, end - len);
        }
        if !self.coherent {
            // Offset 0 + WHOLE_SIZE covers the whole mapping, so nonCoherentAtomSize is respected.
            let range = [vk::MappedMemoryRange::default()
                .memory(self.memory)
                .size(vk::WHOLE_SIZE)];
            unsafe { self.shared.device.flush_mapped_memory_ranges(&range) }
                .map_err(vk_err("vkFlushMappedMemoryRanges"))?;
        }
        Ok(())
    }

    /// Copies the first `out.len()` bytes (at most the buffer's size) of the mapped memory
    /// into `out`.
    fn read_mapped_into(&self, out: &mut [u8]) -> Result<(), VulkanError> {
        let ptr = self.mapping()?;
        if !self.coherent {
            let range = [vk::MappedMemoryRange::default()
                .memory(self.memory)
                .size(vk::WHOLE_SIZE)];
            unsafe { self.shared.device.invalidate_mapped_memory_ranges(&range) }
                .map_err(vk_err("vkInvalidateMappedMemoryRanges"))?;
        }
        let len = out.len().min(self.vk_size as usize);
        // SAFETY: len <= vk_size, which the mapping covers; the device finished writing.
        unsafe { std::ptr::copy_nonoverlapping(ptr.as_ptr(), out.as_mut_ptr(), len) };
        Ok(())
    }
}

impl Drop for Buffer {
    fn drop(&mut self) {
        if self.shared.is_hung() {
            // Work that may use it still runs on the device: leak it.
            return;
        }
        // SAFETY: every submit waits for its fence, so the buffer is not in use; freeing the
        // memory also unmaps it. Null handles (failed creation) are ignored by Vulkan.
        unsafe {
            self.shared.device.destroy_buffer(self.handle, None);
            self.shared.device.free_memory(self.memory, None);
        }
    }
}

/// The smallest staging buffer allocated.
const MIN_STAGING: u64 = 64 * 1024;

/// The largest staging buffer kept between transfers (one for uploads, one for readbacks):
/// larger transfers allocate their own, whose cost is small beside their size.
pub const MAX_KEPT_STAGING: u64 = 64 * 1024 * 1024;

fn mib(bytes: u64) -> String {
    format!("{:.1} MiB", bytes as f64 / (1024.0 * 1024.0))
}

impl Context {
    /// Device buffer initialised with `data`. Empty data allocates a 16-byte zeroed buffer
    /// (Vulkan forbids size 0; shaders bind dummy buffers for absent primitive kinds).
    pub fn create_buffer_with_data(
        &self,
        label: &str,
        usage: BufferUsage,
        data: &[u8],
    ) -> Result<Buffer, VulkanError> {
        let buffer = self.allocate(label, Role::Device(usage), data.len() as u64)?;
        self.upload(&buffer, data)?;
        Ok(buffer)
    }

    /// Zero-initialised device buffer of `size` bytes (min 16) that can be read back.
    pub fn create_buffer(
        &self,
        label: &str,
        usage: BufferUsage,
        size: u64,
    ) -> Result<Buffer, VulkanError> {
        let buffer = self.allocate(label, Role::Device(usage), size)?;
        if buffer.is_host_visible() {
            buffer.write_mapped(&[])?;
        } else {
            // Zeroing on the device avoids a staging buffer full of zeros.
            self.submit(|device, cmd| unsafe {
                device.cmd_fill_buffer(cmd, buffer.handle, 0, vk::WHOLE_SIZE, 0);
                memory_barrier(device, cmd, vk::PipelineStageFlags::TRANSFER);
            })?;
        }
        Ok(buffer)
    }

    /// Copies the whole buffer back to the host.
    pub fn read_buffer(&self, buffer: &Buffer) -> Result<Vec<u8>, VulkanError> {
        let mut out = vec![0; buffer.size as usize];
        self.read_buffer_into(buffer, &mut out)?;
        Ok(out)
    }

    /// Copies the first `out.len()` bytes of the buffer into `out`, with no copy in between
    /// where the host maps the buffer (a frame's image goes straight into its pixels).
    pub fn read_buffer_into(&self, buffer: &Buffer, out: &mut [u8]) -> Result<(), VulkanError> {
        self.check_owned(buffer)?;
        if out.len() as u64 > buffer.size {
            return Err(VulkanError::InvalidArgument(format!(
                "buffer '{}': reading {} bytes of its {}",
                buffer.label,
                out.len(),
                buffer.size
            )));
        }
        if buffer.is_host_visible() {
            return buffer.read_mapped_into(out);
        }
        let staging = self.staging(buffer.label(), Role::Readback, buffer.vk_size)?;
        self.copy(buffer, &staging)?;
        let read = staging.read_mapped_into(out);
        self.keep_staging(staging);
        read
    }

    /// Rejects buffers created by another context (their handles are invalid on this device).
    pub(crate) fn check_owned(&self, buffer: &Buffer) -> Result<(), VulkanError> {
        if Arc::ptr_eq(&buffer.shared, &self.shared) {
            return Ok(());
        }
        let label = &buffer.label;
        let msg = format!("buffer '{label}' belongs to another Vulkan context");
        Err(VulkanError::InvalidArgument(msg))
    }

    /// Writes `data` (zero-padded) into a freshly created device buffer.
    fn upload(&self, buffer: &Buffer, data: &[u8]) -> Result<(), VulkanError> {
        if buffer.is_host_visible() {
            return buffer.write_mapped(data);
        }
        let staging = self.upload_buffer(buffer.label(), buffer.vk_size, data)?;
        self.copy(&staging, buffer)?;
        self.keep_staging(staging);
        Ok(())
    }

    /// Copies `src` into `dst` on the queue and waits: as many bytes as the smaller holds
    /// (a kept staging buffer may be larger than the device buffer).
    fn copy(&self, src: &Buffer, dst: &Buffer) -> Result<(), VulkanError> {
        let region = [vk::BufferCopy::default().size(src.vk_size.min(dst.vk_size))];
        self.submit(|device, cmd| unsafe {
            device.cmd_copy_buffer(cmd, src.handle, dst.handle, &region);
            memory_barrier(device, cmd, vk::PipelineStageFlags::TRANSFER);
        })?;
        Ok(())
    }

    /// A host-visible transfer-source buffer of at least `size` bytes whose first `size` hold
    /// `data` and then zeros, for uploads to device memory that cannot be mapped (images in
    /// optimal tiling). Hand it back with [`Context::keep_staging`] after the copy.
    pub(super) fn upload_buffer(
        &self,
        label: &str,
        size: u64,
        data: &[u8],
    ) -> Result<Buffer, VulkanError> {
        let staging = self.staging(label, Role::Upload, size)?;
        staging.write_mapped_prefix(data, size)?;
        Ok(staging)
    }

    /// A staging buffer of `role` (upload or readback) of at least `size` bytes: the one kept
    /// from an earlier transfer when it is large enough, else a new one (rounded up to a power
    /// of two, so that a run of growing transfers allocates a few times, not each time).
    ///
    /// Why kept: allocating host memory that a GPU can reach pins its pages, which made a
    /// fresh staging buffer per transfer cost more than the transfer on a GPU (docs/gpu.md).
    fn staging(&self, label: &str, role: Role, size: u64) -> Result<Buffer, VulkanError> {
        let slot = usize::from(role == Role::Readback);
        let kept = self.staging.lock().unwrap_or_else(|e| e.into_inner())[slot].take();
        match kept {
            Some(b) if b.vk_size >= size => Ok(b),
            other => {
                // A smaller kept buffer is freed; the new one replaces it when handed back.
                drop(other);
                let rounded = size.next_power_of_two().max(MIN_STAGING);
                let size = if rounded <= MAX_KEPT_STAGING {
                    rounded
                } else {
                    size
                };
                self.allocate(&format!("staging for {label}"), role, size)
            }
        }
    }

    /// Hands a staging buffer back after its transfer finished: it is kept for the next
    /// transfer of its role unless it is larger than [`MAX_KEPT_STAGING`] or a larger one is
    /// kept already.
    pub(super) fn keep_staging(&self, buffer: Buffer) {
        if buffer.vk_size > MAX_KEPT_STAGING {
            return;
        }
        let slot = match buffer.role {
            Role::Upload => 0,
            Role::Readback => 1,
            Role::Device(_) => return,
        };
        let mut kept = self.staging.lock().unwrap_or_else(|e| e.into_inner());
        if kept[slot]
            .as_ref()
            .is_none_or(|k| k.vk_size < buffer.vk_size)
        {
            kept[slot] = Some(buffer);
        }
    }

    /// Index of the first memory type allowed by `type_bits` that has all flags of the earliest
    /// satisfiable preference.
    pub(super) fn memory_type(
        &self,
        type_bits: u32,
        preferences: &[vk::MemoryPropertyFlags],
    ) -> Option<(u32, vk::MemoryPropertyFlags)> {
        let props = &self.memory_properties;
        let types = props
            .memory_types
            .get(..props.memory_type_count as usize)
            .unwrap_or(&props.memory_types);
        preferences.iter().find_map(|&wanted| {
            types
                .iter()
                .enumerate()
                .find(|(i, t)| type_bits & (1 << i) != 0 && t.property_flags.contains(wanted))
                .map(|(i, t)| (i as u32, t.property_flags))
        })
    }

    /// Dedicated memory for `what` (named in errors, e.g. `buffer 'x'`) of the first memory
    /// type meeting `preferences` (see [`Context::memory_type`]), with that type's flags. Running
    /// out of memory is a [`VulkanError::Limit`] naming `what` and the size.
    pub(super) fn allocate_memory(
        &self,
        what: &str,
        requirements: vk::MemoryRequirements,
        preferences: &[vk::MemoryPropertyFlags],
    ) -> Result<(vk::DeviceMemory, vk::MemoryPropertyFlags), VulkanError> {
        let (type_index, flags) = self
            .memory_type(requirements.memory_type_bits, preferences)
            .ok_or_else(|| VulkanError::Limit(format!("no suitable memory type for {what}")))?;
        let alloc = vk::MemoryAllocateInfo::default()
            .allocation_size(requirements.size)
            .memory_type_index(type_index);
        // SAFETY: valid allocate info; the caller owns (and frees) the memory.
        let memory =
            unsafe { self.shared.device.allocate_memory(&alloc, None) }.map_err(|result| {
                match result {
                    vk::Result::ERROR_OUT_OF_DEVICE_MEMORY
                    | vk::Result::ERROR_OUT_OF_HOST_MEMORY => VulkanError::Limit(format!(
                        "allocating {} for {what} failed: {result}",
                        mib(requirements.size)
                    )),
                    result => VulkanError::vk("vkAllocateMemory", result),
                }
            })?;
        Ok((memory, flags))
    }

    /// A storage buffer of `size` bytes (min 16) without memory of its own: the caller binds
    /// it to the memory of the texel image it aliases ([`Context::create_stage_image_with_words`]),
    /// which frees that memory.
    pub(super) fn storage_alias(&self, label: &str, size: u64) -> Result<Buffer, VulkanError> {
        let size = size.max(16);
        let limit = self.limits().max_storage_buffer_range;
        if size > limit {
            return Err(VulkanError::Limit(format!(
                "buffer '{label}' needs {} but this device's maxStorageBufferRange is {}",
                mib(size),
                mib(limit)
            )));
        }
        let info = vk::BufferCreateInfo::default()
            .size(size)
            .usage(vk::BufferUsageFlags::STORAGE_BUFFER)
            .sharing_mode(vk::SharingMode::EXCLUSIVE);
        // SAFETY: valid create info; the Buffer value owns the handle (its memory stays null:
        // freeing a null memory handle is a no-op).
        let handle = unsafe { self.shared.device.create_buffer(&info, None) }
            .map_err(vk_err("vkCreateBuffer"))?;
        Ok(Buffer {
            shared: self.shared.clone(),
            handle,
            memory: vk::DeviceMemory::null(),
            size,
            vk_size: size,
            label: label.to_string(),
            role: Role::Device(BufferUsage::Storage),
            mapped: None,
            coherent: true,
        })
    }

    /// Checks limits, then creates a buffer of `size` bytes (min 16) with dedicated memory.
    fn allocate(&self, label: &str, role: Role, size: u64) -> Result<Buffer, VulkanError> {
        let size = size.max(16);
        // vkCmdFillBuffer works in 4-byte words; an overflow fails the limit checks below.
        let vk_size = size.checked_next_multiple_of(4).unwrap_or(u64::MAX);
        let limits = self.limits();
        let mut checks = vec![("maxMemoryAllocationSize", limits.max_memory_allocation_size)];
        match role {
            Role::Device(BufferUsage::Storage) => {
                checks.push(("maxStorageBufferRange", limits.max_storage_buffer_range))
            }
            Role::Device(BufferUsage::Uniform) => {
                checks.push(("maxUniformBufferRange", limits.max_uniform_buffer_range))
            }
            Role::Upload | Role::Readback => {}
        }
        for (name, limit) in checks.into_iter().rev() {
            if vk_size > limit {
                let exact = if mib(vk_size) == mib(limit) {
                    format!(" ({vk_size} > {limit} bytes)")
                } else {
                    String::new()
                };
                return Err(VulkanError::Limit(format!(
                    "buffer '{label}' needs {} but this device's {name} is {}{exact}",
                    mib(vk_size),
                    mib(limit)
                )));
            }
        }

        use vk::BufferUsageFlags as U;
        use vk::MemoryPropertyFlags as M;
        let transfer = U::TRANSFER_SRC | U::TRANSFER_DST;
        let (usage, preferences): (_, &[M]) = match role {
            Role::Device(BufferUsage::Storage) => {
                (U::STORAGE_BUFFER | transfer, &[M::DEVICE_LOCAL, M::empty()])
            }
            Role::Device(BufferUsage::Uniform) => {
                (U::UNIFORM_BUFFER | transfer, &[M::DEVICE_LOCAL, M::empty()])
            }
            Role::Upload => (
                transfer,
                &[M::HOST_VISIBLE | M::HOST_COHERENT, M::HOST_VISIBLE],
            ),
            Role::Readback => (
                transfer,
                &[M::HOST_VISIBLE | M::HOST_CACHED, M::HOST_VISIBLE],
            ),
        };
        let device = &self.shared.device;
        let info = vk::BufferCreateInfo::default()
            .size(vk_size)
            .usage(usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE);
        // SAFETY: valid create info; the Buffer value below owns (and on error destroys) the handle.
        let handle =
            unsafe { device.create_buffer(&info, None) }.map_err(vk_err("vkCreateBuffer"))?;
        let mut buffer = Buffer {
            shared: self.shared.clone(),
            handle,
            memory: vk::DeviceMemory::null(),
            size,
            vk_size,
            label: label.to_string(),
            role,
            mapped: None,
            coherent: true,
        };
        let requirements = unsafe { device.get_buffer_memory_requirements(handle) };
        let flags;
        (buffer.memory, flags) =
            self.allocate_memory(&format!("buffer '{label}'"), requirements, preferences)?;
        unsafe { device.bind_buffer_memory(handle, buffer.memory, 0) }
            .map_err(vk_err("vkBindBufferMemory"))?;
        let map_device_memory = flags.contains(M::HOST_VISIBLE) && !self.force_staging;
        if matches!(role, Role::Upload | Role::Readback) || map_device_memory {
            let ptr = unsafe {
                device.map_memory(
                    buffer.memory,
                    0,
                    vk::WHOLE_SIZE,
                    vk::MemoryMapFlags::empty(),
                )
            }
            .map_err(vk_err("vkMapMemory"))?;
            buffer.mapped = NonNull::new(ptr.cast::<u8>());
            buffer.coherent = flags.contains(M::HOST_COHERENT);
        }
        Ok(buffer)
    }
}
