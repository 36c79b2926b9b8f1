//! Read-only texel images: arrays of 16-byte records that shaders read with `textureLoad` from
//! a `texture_storage_2d<rgba32uint, read>`.
//!
//! Why images and not storage buffers: lavapipe (Mesa 25.0) loads a storage buffer at a
//! per-lane address as a loop over the SIMD lanes, with a branch for the lane's mask and one
//! for the bounds check of every 32-bit component. Its storage-image load is straight-line
//! SIMD code instead (bounds handled by selects, one 16-byte load per lane), so records that
//! every traversal step or triangle test reads (BVH nodes, triangles) cost far less as texels
//! (docs/bench.md §6). A storage image rather than a sampled one: lavapipe's sampled fetch
//! (`texture_2d`) computes a mip level for each lane, which took most of the gain away.
//! GPUs read such images through their texture path, long-standing practice for BVH data.

use super::buffer::{Buffer, MAX_KEPT_STAGING};
use super::context::{Context, DeviceShared};
use super::{vk_err, VulkanError};
use ash::vk;
use std::sync::Arc;

/// Texels per image row. Record `i` sits at `(i % TEXEL_ROW, i / TEXEL_ROW)`; shaders compute
/// that with a mask and a shift. 4096 is the smallest `maxImageDimension2D` Vulkan allows.
pub const TEXEL_ROW: u32 = 4096;

/// Bytes per texel (format `R32G32B32A32_UINT`: four 32-bit words).
pub const TEXEL_BYTES: usize = 16;

/// A 2D `R32G32B32A32_UINT` storage image holding an array of texels, row by row, in `GENERAL`
/// layout, which shaders only read (WGSL `texture_storage_2d<rgba32uint, read>`).
pub struct TexelImage {
    pub(crate) shared: Arc<DeviceShared>,
    image: vk::Image,
    pub(crate) view: vk::ImageView,
    memory: vk::DeviceMemory,
    texels: u64,
    label: String,
    /// A storage buffer over the same memory ([`Context::create_stage_image_with_words`]).
    words: Option<Buffer>,
}

impl TexelImage {
    /// Number of texels the caller stored (the last row is padded with zeros).
    pub fn texels(&self) -> u64 {
        self.texels
    }

    /// The label given at creation, used in error messages.
    pub fn label(&self) -> &str {
        &self.label
    }

    /// Bytes of the texels, including the zero padding of the last row.
    pub fn size(&self) -> u64 {
        rows(self.texels) as u64 * TEXEL_ROW as u64 * TEXEL_BYTES as u64
    }

    /// The storage buffer over the image's memory, where texel `i` is the
    /// `i`-th 16 bytes (a stage image made by
    /// [`Context::create_stage_image_with_words`]), for shaders that write
    /// the texels as `array<vec4<u32>>`.
    pub fn words(&self) -> Option<&Buffer> {
        self.words.as_ref()
    }
}

impl Drop for TexelImage {
    fn drop(&mut self) {
        if self.shared.is_hung() {
            // Work that may use it still runs on the device: leak it.
            return;
        }
        // SAFETY: every submit waits for its fence, so the image is not in use. Null handles
        // (failed creation) are ignored by Vulkan.
        // The aliasing buffer goes before the memory it is bound to.
        drop(self.words.take());
        unsafe {
            let device = &self.shared.device;
            device.destroy_image_view(self.view, None);
            device.destroy_image(self.image, None);
            device.free_memory(self.memory, None);
        }
    }
}

/// Image rows for `texels` texels (at least one: Vulkan forbids empty images).
fn rows(texels: u64) -> u32 {
    texels.div_ceil(TEXEL_ROW as u64).clamp(1, u32::MAX as u64) as u32
}

/// The rows of image `label` holding `texels` texels, or the error naming
/// `maxImageDimension2D` (`max`) when the device allows fewer.
fn checked_rows(label: &str, texels: u64, max: u32) -> Result<u32, VulkanError> {
    let height = rows(texels);
    if height > max {
        return Err(VulkanError::Limit(format!(
            "texel image '{label}' needs {height} rows of {TEXEL_ROW} texels ({texels} texels of {TEXEL_BYTES} bytes) but this device's maxImageDimension2D is {max}"
        )));
    }
    Ok(height)
}

impl Context {
    /// A texel image holding `data` (a whole number of 16-byte texels; empty data gives one
    /// row of zeros, so that shaders can always bind something). Fails with
    /// [`VulkanError::Limit`] naming `maxImageDimension2D` when there are more rows than the
    /// device allows.
    pub fn create_texel_image(&self, label: &str, data: &[u8]) -> Result<TexelImage, VulkanError> {
        if !data.len().is_multiple_of(TEXEL_BYTES) {
            return Err(VulkanError::InvalidArgument(format!(
                "texel image '{label}': {} bytes is not a whole number of {TEXEL_BYTES}-byte texels",
                data.len()
            )));
        }
        self.texel_image((data.len() / TEXEL_BYTES) as u64, label, Some(data), false)
    }

    /// A texel image of at least `texels` texels whose contents are undefined until a pipeline
    /// writes them (the stages' hit records and queues): no upload, so large ones are cheap.
    pub fn create_stage_image(&self, label: &str, texels: u64) -> Result<TexelImage, VulkanError> {
        self.texel_image(texels, label, None, false)
    }

    /// Whether [`Context::create_stage_image_with_words`] works on this device: a CPU device
    /// (lavapipe) whose linear `R32G32B32A32_UINT` images can be storage images with rows of
    /// exactly [`TEXEL_ROW`] texels, so that a storage buffer over the same memory holds texel
    /// `i` at bytes `16 i ..`.
    ///
    /// Why: lavapipe writes a storage-image texel through a call into the image's store
    /// function, which costs several per-lane buffer stores, while its image loads are
    /// straight-line SIMD code (the module docs). A stage then writes its records as words and
    /// the next stage reads them as texels. Vulkan defines such aliasing for buffers and
    /// linear images in `GENERAL` layout (host-accessible subresources: "Memory Aliasing").
    pub fn stage_words(&self) -> bool {
        self.stage_words
    }

    /// A stage image as [`Context::create_stage_image`] makes it, plus a storage buffer over
    /// its memory ([`TexelImage::words`]); fails where [`Context::stage_words`] is false.
    pub fn create_stage_image_with_words(
        &self,
        label: &str,
        texels: u64,
    ) -> Result<TexelImage, VulkanError> {
        if !self.stage_words {
            return Err(VulkanError::InvalidArgument(format!(
                "stage image '{label}': this device's stage images cannot be aliased by buffers"
            )));
        }
        let image = self.texel_image(texels, label, None, true)?;
        if image.words.is_none() {
            // Shaders compiled for words would write into a placeholder.
            return Err(VulkanError::Limit(format!(
                "stage image '{label}': its linear layout is not whole rows of {TEXEL_ROW} texels from offset 0"
            )));
        }
        Ok(image)
    }

    /// Creates a linear one-row texel image and checks its layout for
    /// [`Context::stage_words`]: offset 0 and a row pitch of exactly one row of texels.
    pub(crate) fn probe_stage_words(&self) -> Result<bool, VulkanError> {
        let image = self.texel_image(1, "stage words probe", None, true);
        match image {
            Ok(image) => Ok(image.words.is_some()),
            Err(VulkanError::Limit(_)) => Ok(false),
            Err(e) => Err(e),
        }
    }

    /// With `words` (no `data`): a linear image with a storage buffer over its memory when its
    /// layout is one of whole rows from offset 0, else the linear image alone.
    fn texel_image(
        &self,
        texels: u64,
        label: &str,
        data: Option<&[u8]>,
        words: bool,
    ) -> Result<TexelImage, VulkanError> {
        let height = checked_rows(label, texels, self.limits().max_image_dimension_2d)?;
        let needed = vk::FormatFeatureFlags::STORAGE_IMAGE | vk::FormatFeatureFlags::TRANSFER_DST;
        if !self.texel_format_features.contains(needed) {
            return Err(VulkanError::Limit(format!(
                "texel image '{label}': this device cannot use R32G32B32A32_UINT storage images (format features {:?})",
                self.texel_format_features
            )));
        }
        let device = &self.shared.device;
        let format = vk::Format::R32G32B32A32_UINT;
        // On a CPU device whose linear texel images are whole rows from offset 0 (the probe
        // of `stage_words`), contents are written straight into the image's memory: no
        // staging buffer, and no copy by the driver (docs/textures.md, FlightHelmet's load).
        let host_written = data.is_some() && self.stage_words;
        let info = vk::ImageCreateInfo::default()
            .image_type(vk::ImageType::TYPE_2D)
            .format(format)
            .extent(vk::Extent3D {
                width: TEXEL_ROW,
                height,
                depth: 1,
            })
            .mip_levels(1)
            .array_layers(1)
            .samples(vk::SampleCountFlags::TYPE_1)
            .tiling(match words || host_written {
                true => vk::ImageTiling::LINEAR,
                false => vk::ImageTiling::OPTIMAL,
            })
            .usage(vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_DST)
            .sharing_mode(vk::SharingMode::EXCLUSIVE)
            // Host writes to a linear image survive only a transition from PREINITIALIZED
            // (Vulkan 1.3, "Image Layouts").
            .initial_layout(match host_written {
                true => vk::ImageLayout::PREINITIALIZED,
                false => vk::ImageLayout::UNDEFINED,
            });
        // SAFETY: valid create info; the TexelImage below owns (and on error destroys) it.
        let image = unsafe { device.create_image(&info, None) }.map_err(vk_err("vkCreateImage"))?;
        let mut result = TexelImage {
            shared: self.shared.clone(),
            image,
            view: vk::ImageView::null(),
            memory: vk::DeviceMemory::null(),
            texels,
            label: label.to_string(),
            words: None,
        };
        let mut requirements = unsafe { device.get_image_memory_requirements(image) };
        if words {
            let layout = unsafe {
                device.get_image_subresource_layout(
                    image,
                    vk::ImageSubresource::default().aspect_mask(vk::ImageAspectFlags::COLOR),
                )
            };
            let row = TEXEL_ROW as u64 * TEXEL_BYTES as u64;
            if layout.offset == 0 && layout.row_pitch == row {
                let buffer =
                    self.storage_alias(&format!("{label} (words)"), texels * TEXEL_BYTES as u64)?;
                let for_buffer = unsafe { device.get_buffer_memory_requirements(buffer.handle) };
                requirements.size = requirements.size.max(for_buffer.size);
                requirements.alignment = requirements.alignment.max(for_buffer.alignment);
                requirements.memory_type_bits &= for_buffer.memory_type_bits;
                result.words = Some(buffer);
            }
        }
        let max_alloc = self.limits().max_memory_allocation_size;
        if requirements.size > max_alloc {
            return Err(VulkanError::Limit(format!(
                "texel image '{label}' needs {} bytes but this device's maxMemoryAllocationSize is {max_alloc}",
                requirements.size
            )));
        }
        let host = vk::MemoryPropertyFlags::HOST_VISIBLE | vk::MemoryPropertyFlags::HOST_COHERENT;
        let preferences: &[vk::MemoryPropertyFlags] = match host_written {
            true => &[vk::MemoryPropertyFlags::DEVICE_LOCAL | host, host],
            false => &[
                vk::MemoryPropertyFlags::DEVICE_LOCAL,
                vk::MemoryPropertyFlags::empty(),
            ],
        };
        (result.memory, _) =
            self.allocate_memory(&format!("texel image '{label}'"), requirements, preferences)?;
        unsafe { device.bind_image_memory(image, result.memory, 0) }
            .map_err(vk_err("vkBindImageMemory"))?;
        if let Some(buffer) = &result.words {
            // SAFETY: the memory type and size satisfy the buffer's requirements too.
            unsafe { device.bind_buffer_memory(buffer.handle, result.memory, 0) }
                .map_err(vk_err("vkBindBufferMemory"))?;
        }
        let range = vk::ImageSubresourceRange::default()
            .aspect_mask(vk::ImageAspectFlags::COLOR)
            .level_count(1)
            .layer_count(1);
        let view_info = vk::ImageViewCreateInfo::default()
            .image(image)
            .view_type(vk::ImageViewType::TYPE_2D)
            .format(format)
            .subresource_range(range);
        result.view = unsafe { device.create_image_view(&view_info, None) }
            .map_err(vk_err("vkCreateImageView"))?;

        let range_all = range;
        let Some(data) = data else {
            // No contents: only the layout the shaders use.
            self.to_general(
                image,
                range_all,
                (
                    vk::ImageLayout::UNDEFINED,
                    vk::PipelineStageFlags::TOP_OF_PIPE,
                ),
                vk::AccessFlags::empty(),
                vk::AccessFlags::SHADER_READ | vk::AccessFlags::SHADER_WRITE,
            )?;
            return Ok(result);
        };
        if host_written {
            self.write_rows(&result, range, height, data)?;
        } else {
            // Images in optimal tiling cannot be mapped: upload through a staging buffer.
            self.upload_rows(image, range, label, height, data)?;
        }
        Ok(result)
    }

    /// Fills `image` (a linear texel image in host-visible, coherent memory, still in the
    /// `PREINITIALIZED` layout) with `data` (the rest zero) through a mapping, on all cores,
    /// and leaves it in `GENERAL` for the shaders.
    fn write_rows(
        &self,
        image: &TexelImage,
        range: vk::ImageSubresourceRange,
        height: u32,
        data: &[u8],
    ) -> Result<(), VulkanError> {
        use rayon::prelude::*;
        let device = &self.shared.device;
        // SAFETY: a valid image; its layout is asked of its only subresource.
        let layout = unsafe {
            device.get_image_subresource_layout(
                image.image,
                vk::ImageSubresource::default().aspect_mask(vk::ImageAspectFlags::COLOR),
            )
        };
        let row = TEXEL_ROW as u64 * TEXEL_BYTES as u64;
        let rows = u64::from(height);
        if layout.offset != 0 || layout.row_pitch != row || layout.size < rows * row {
            return Err(VulkanError::Limit(format!(
                "texel image '{}': its linear layout is not whole rows of {TEXEL_ROW} texels from offset 0",
                image.label
            )));
        }
        let len = (rows * row) as usize;
        // SAFETY: the memory is host-visible, bound to this image alone, and idle.
        let ptr =
            unsafe { device.map_memory(image.memory, 0, len as u64, vk::MemoryMapFlags::empty()) }
                .map_err(vk_err("vkMapMemory"))?;
        // SAFETY: the mapping covers `len` bytes and nothing else accesses them until unmapped.
        let mapped = unsafe { std::slice::from_raw_parts_mut(ptr.cast::<u8>(), len) };
        // Chunks of 1 MiB: both cores fault in and fill the pages, the copy's cost on a CPU.
        const CHUNK: usize = 1 << 20;
        mapped
            .par_chunks_mut(CHUNK)
            .enumerate()
            .for_each(|(i, out)| {
                let start = (i * CHUNK).min(data.len());
                let end = (start + out.len()).min(data.len());
                let (copied, zeroed) = out.split_at_mut(end - start);
                copied.copy_from_slice(&data[start..end]);
                zeroed.fill(0);
            });
        // SAFETY: mapped above; coherent memory needs no flush.
        unsafe { device.unmap_memory(image.memory) };
        self.to_general(
            image.image,
            range,
            (
                vk::ImageLayout::PREINITIALIZED,
                vk::PipelineStageFlags::HOST,
            ),
            vk::AccessFlags::HOST_WRITE,
            vk::AccessFlags::SHADER_READ,
        )
    }

    /// Moves an idle `image` from layout `from.0` (last written by stage `from.1` with
    /// `src_access`) to `GENERAL` for the compute shaders' `dst_access`, and waits.
    fn to_general(
        &self,
        image: vk::Image,
        range: vk::ImageSubresourceRange,
        from: (vk::ImageLayout, vk::PipelineStageFlags),
        src_access: vk::AccessFlags,
        dst_access: vk::AccessFlags,
    ) -> Result<(), VulkanError> {
        let barrier = vk::ImageMemoryBarrier::default()
            .old_layout(from.0)
            .new_layout(vk::ImageLayout::GENERAL)
            .src_access_mask(src_access)
            .dst_access_mask(dst_access)
            .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .image(image)
            .subresource_range(range);
        // SAFETY: the image is valid and idle.
        self.submit(|device, cmd| unsafe {
            device.cmd_pipeline_barrier(
                cmd,
                from.1,
                vk::PipelineStageFlags::COMPUTE_SHADER,
                vk::DependencyFlags::empty(),
                &[],
                &[],
                &[barrier],
            );
        })?;
        Ok(())
    }

    /// Fills `image` (`height` rows of [`TEXEL_ROW`] texels, still in the
    /// `UNDEFINED` layout) with `data` (the rest zero) and leaves it in
    /// `GENERAL` for the shaders. The rows go through a staging buffer of
    /// at most [`MAX_KEPT_STAGING`] bytes, one band at a time, so that a
    /// large image (a scene's textures, up to a gigabyte) is not held a
    /// second time in host memory while it is uploaded.
    fn upload_rows(
        &self,
        image: vk::Image,
        range: vk::ImageSubresourceRange,
        label: &str,
        height: u32,
        data: &[u8],
    ) -> Result<(), VulkanError> {
        use vk::PipelineStageFlags as S;
        let flags = vk::DependencyFlags::empty();
        let to_transfer = vk::ImageMemoryBarrier::default()
            .old_layout(vk::ImageLayout::UNDEFINED)
            .new_layout(vk::ImageLayout::TRANSFER_DST_OPTIMAL)
            .dst_access_mask(vk::AccessFlags::TRANSFER_WRITE)
            .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .image(image)
            .subresource_range(range);
        let between = to_transfer
            .old_layout(vk::ImageLayout::TRANSFER_DST_OPTIMAL)
            .src_access_mask(vk::AccessFlags::TRANSFER_WRITE);
        let to_shader = between
            .new_layout(vk::ImageLayout::GENERAL)
            .dst_access_mask(vk::AccessFlags::SHADER_READ);
        let row_bytes = TEXEL_ROW as u64 * TEXEL_BYTES as u64;
        let band = (MAX_KEPT_STAGING / row_bytes).clamp(1, u64::from(height)) as u32;
        let mut y = 0;
        while y < height {
            let rows = band.min(height - y);
            let start = (u64::from(y) * row_bytes).min(data.len() as u64) as usize;
            let end = (u64::from(y + rows) * row_bytes).min(data.len() as u64) as usize;
            let bytes = u64::from(rows) * row_bytes;
            let staging = self.upload_buffer(label, bytes, &data[start..end])?;
            let region = vk::BufferImageCopy::default()
                .image_subresource(
                    vk::ImageSubresourceLayers::default()
                        .aspect_mask(vk::ImageAspectFlags::COLOR)
                        .layer_count(1),
                )
                .image_offset(vk::Offset3D {
                    x: 0,
                    y: y as i32,
                    z: 0,
                })
                .image_extent(vk::Extent3D {
                    width: TEXEL_ROW,
                    height: rows,
                    depth: 1,
                });
            let (first, last) = (y == 0, y + rows == height);
            // SAFETY: the image, its memory and the staging buffer are valid and idle.
            self.submit(|device, cmd| unsafe {
                if first {
                    device.cmd_pipeline_barrier(
                        cmd,
                        S::TOP_OF_PIPE,
                        S::TRANSFER,
                        flags,
                        &[],
                        &[],
                        &[to_transfer],
                    );
                }
                device.cmd_copy_buffer_to_image(
                    cmd,
                    staging.handle,
                    image,
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    &[region],
                );
                let (next, barrier) = match last {
                    true => (S::COMPUTE_SHADER, to_shader),
                    false => (S::TRANSFER, between),
                };
                device.cmd_pipeline_barrier(cmd, S::TRANSFER, next, flags, &[], &[], &[barrier]);
            })?;
            self.keep_staging(staging);
            y += rows;
        }
        Ok(())
    }

    /// Overwrites texels `first..first + data.len() / TEXEL_BYTES` of `image` with `data`
    /// (a texture edit re-uploads that texture's texels only). The range may start and end
    /// mid-row: it is copied as up to three rectangles (the first partial row, the whole rows,
    /// the last partial row).
    pub fn write_texel_image(
        &self,
        image: &TexelImage,
        first: u64,
        data: &[u8],
    ) -> Result<(), VulkanError> {
        self.check_owned_image(image)?;
        if !data.len().is_multiple_of(TEXEL_BYTES) {
            return Err(VulkanError::InvalidArgument(format!(
                "texel image '{}': {} bytes is not a whole number of texels",
                image.label,
                data.len()
            )));
        }
        let count = (data.len() / TEXEL_BYTES) as u64;
        if count == 0 {
            return Ok(());
        }
        if first + count > image.texels {
            return Err(VulkanError::InvalidArgument(format!(
                "texel image '{}': texels {first}..{} lie beyond its {}",
                image.label,
                first + count,
                image.texels
            )));
        }
        let staging = self.upload_buffer(&image.label, data.len() as u64, data)?;
        let row = TEXEL_ROW as u64;
        let mut regions = Vec::new();
        let (mut at, end) = (first, first + count);
        while at < end {
            let x = at % row;
            let width = if x == 0 && end - at >= row {
                // Whole rows from here.
                ((end - at) / row) * row
            } else {
                (row - x).min(end - at)
            };
            let (w, h) = if width >= row {
                (row, width / row)
            } else {
                (width, 1)
            };
            regions.push(
                vk::BufferImageCopy::default()
                    .buffer_offset((at - first) * TEXEL_BYTES as u64)
                    .buffer_row_length(TEXEL_ROW)
                    .image_subresource(
                        vk::ImageSubresourceLayers::default()
                            .aspect_mask(vk::ImageAspectFlags::COLOR)
                            .layer_count(1),
                    )
                    .image_offset(vk::Offset3D {
                        x: x as i32,
                        y: (at / row) as i32,
                        z: 0,
                    })
                    .image_extent(vk::Extent3D {
                        width: w as u32,
                        height: h as u32,
                        depth: 1,
                    }),
            );
            at += w * h;
        }
        let range = vk::ImageSubresourceRange::default()
            .aspect_mask(vk::ImageAspectFlags::COLOR)
            .level_count(1)
            .layer_count(1);
        let to_transfer = vk::ImageMemoryBarrier::default()
            .old_layout(vk::ImageLayout::GENERAL)
            .new_layout(vk::ImageLayout::GENERAL)
            .src_access_mask(vk::AccessFlags::SHADER_READ)
            .dst_access_mask(vk::AccessFlags::TRANSFER_WRITE)
            .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .image(image.image)
            .subresource_range(range);
        let to_shader = to_transfer
            .src_access_mask(vk::AccessFlags::TRANSFER_WRITE)
            .dst_access_mask(vk::AccessFlags::SHADER_READ);
        use vk::PipelineStageFlags as S;
        let flags = vk::DependencyFlags::empty();
        // SAFETY: the image and the staging buffer are valid; every submit waits for its
        // fence, so no dispatch reads the image meanwhile.
        self.submit(|device, cmd| unsafe {
            device.cmd_pipeline_barrier(
                cmd,
                S::COMPUTE_SHADER,
                S::TRANSFER,
                flags,
                &[],
                &[],
                &[to_transfer],
            );
            device.cmd_copy_buffer_to_image(
                cmd,
                staging.handle,
                image.image,
                vk::ImageLayout::GENERAL,
                &regions,
            );
            device.cmd_pipeline_barrier(
                cmd,
                S::TRANSFER,
                S::COMPUTE_SHADER,
                flags,
                &[],
                &[],
                &[to_shader],
            );
        })?;
        self.keep_staging(staging);
        Ok(())
    }

    /// Rejects images created by another context (their handles are invalid on this device).
    pub(crate) fn check_owned_image(&self, image: &TexelImage) -> Result<(), VulkanError> {
        if Arc::ptr_eq(&image.shared, &self.shared) {
            return Ok(());
        }
        Err(VulkanError::InvalidArgument(format!(
            "texel image '{}' belongs to another Vulkan context",
            image.label
        )))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_round_up_and_respect_the_limit() {
        assert_eq!(checked_rows("a", 0, 1).unwrap(), 1);
        assert_eq!(checked_rows("a", 1, 1).unwrap(), 1);
        assert_eq!(checked_rows("a", TEXEL_ROW as u64, 1).unwrap(), 1);
        assert_eq!(checked_rows("a", TEXEL_ROW as u64 + 1, 2).unwrap(), 2);
        // 16384 rows is lavapipe's maxImageDimension2D: 2^26 texels, 1 GiB.
        let full = 16384 * TEXEL_ROW as u64;
        assert_eq!(checked_rows("a", full, 16384).unwrap(), 16384);
        match checked_rows("BVH nodes", full + 1, 16384) {
            Err(VulkanError::Limit(msg)) => {
                assert!(msg.contains("'BVH nodes'"), "{msg}");
                assert!(msg.contains("maxImageDimension2D is 16384"), "{msg}");
                assert!(msg.contains("16385 rows"), "{msg}");
            }
            other => panic!("expected a Limit error, got {other:?}"),
        }
    }
}
