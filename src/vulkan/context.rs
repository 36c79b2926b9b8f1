//! Instance creation, device listing and selection, the logical device and its compute queue.

use super::{vk_err, VulkanError};
use ash::vk;
use std::ffi::{c_void, CStr};
use std::str::FromStr;
use std::sync::{Arc, Mutex};
use std::time::Duration;

const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// Which device [`Context::new`] should use.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum DeviceSelector {
    /// Position in the list returned by [`Context::list_devices`].
    Index(usize),
    /// Case-insensitive substring of the device name; the first match wins.
    Name(String),
}

impl FromStr for DeviceSelector {
    type Err = std::convert::Infallible;

    /// All digits parse as [`DeviceSelector::Index`], anything else as [`DeviceSelector::Name`].
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let digits = !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
        Ok(match s.parse() {
            Ok(i) if digits => DeviceSelector::Index(i),
            _ => DeviceSelector::Name(s.to_string()),
        })
    }
}

/// Options for [`Context::new`].
#[derive(Default, Clone, Debug)]
pub struct ContextOptions {
    /// Device to use; `None` picks a discrete GPU, else an integrated GPU, else anything.
    pub device: Option<DeviceSelector>,
    /// Enable the Khronos validation layer (also enabled by `PENUMBRA_VALIDATION=1`).
    pub validation: bool,
}

/// Description of a usable physical device.
#[derive(Clone, Debug)]
pub struct DeviceInfo {
    /// Position in [`Context::list_devices`] (the driver's enumeration order).
    pub index: usize,
    /// Device name, e.g. `llvmpipe (LLVM 19.1.4, 256 bits)`.
    pub name: String,
    /// `discrete GPU`, `integrated GPU`, `virtual GPU`, `CPU` or `other`.
    pub device_type: String,
    /// Supported Vulkan version, e.g. `1.3.289`.
    pub api_version: String,
    /// Driver name (Vulkan 1.2 driver properties), or empty when unavailable.
    pub driver_name: String,
    /// Driver details such as `Mesa 25.0.7 (LLVM 19.1.4)`, or empty when unavailable.
    pub driver_info: String,
    /// PCI vendor id.
    pub vendor_id: u32,
    /// Vendor-specific device id.
    pub device_id: u32,
    /// `driverVersion`, in the vendor's encoding.
    pub driver_version: u32,
    /// `pipelineCacheUUID`: pipeline cache data is valid for devices of this UUID only.
    pub pipeline_cache_uuid: [u8; 16],
}

/// The device limits the renderer has to respect.
#[derive(Clone, Copy, Debug)]
pub struct DeviceLimits {
    /// `maxStorageBufferRange`: largest storage buffer a shader can bind, in bytes.
    pub max_storage_buffer_range: u64,
    /// `maxUniformBufferRange`: largest uniform buffer a shader can bind, in bytes.
    pub max_uniform_buffer_range: u64,
    /// `maxComputeWorkGroupCount`: largest dispatch per dimension.
    pub max_compute_work_group_count: [u32; 3],
    /// `maxComputeWorkGroupInvocations`: largest workgroup (x*y*z).
    pub max_compute_work_group_invocations: u32,
    /// `maxPushConstantsSize`, in bytes.
    pub max_push_constants_size: u32,
    /// `maxMemoryAllocationSize` (Vulkan 1.1 maintenance3): largest single allocation.
    pub max_memory_allocation_size: u64,
    /// `maxImageDimension2D`: largest width or height of a 2D image, in texels.
    pub max_image_dimension_2d: u32,
    /// `subgroupSize` (Vulkan 1.1): invocations of a subgroup.
    pub subgroup_size: u32,
}

/// Loader, instance and optional validation messenger; destroyed after the device.
struct InstanceHolder {
    entry: ash::Entry,
    instance: ash::Instance,
    messenger: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    /// Error messages from the validation layer. The messenger holds a raw pointer to this
    /// mutex, so this clone keeps it alive until the instance is gone.
    errors: Arc<Mutex<Vec<String>>>,
}

impl InstanceHolder {
    fn new(validation: bool) -> Result<Self, VulkanError> {
        // SAFETY: loading the system loader runs its initialisers; nothing else to uphold.
        let entry =
            unsafe { ash::Entry::load() }.map_err(|e| VulkanError::NoLoader(e.to_string()))?;
        let errors = Arc::new(Mutex::new(Vec::new()));
        if validation {
            // SAFETY: plain enumeration call on a loaded entry.
            let layers = unsafe { entry.enumerate_instance_layer_properties() }
                .map_err(vk_err("vkEnumerateInstanceLayerProperties"))?;
            if !layers
                .iter()
                .any(|l| l.layer_name_as_c_str() == Ok(VALIDATION_LAYER))
            {
                return Err(VulkanError::ValidationLayerMissing);
            }
        }
        let app = vk::ApplicationInfo::default()
            .application_name(c"penumbra")
            .engine_name(c"penumbra")
            .api_version(vk::API_VERSION_1_1);
        let layers = [VALIDATION_LAYER.as_ptr()];
        let extensions = [ash::ext::debug_utils::NAME.as_ptr()];
        let mut messenger_info = vk::DebugUtilsMessengerCreateInfoEXT::default()
            .message_severity(
                vk::DebugUtilsMessageSeverityFlagsEXT::WARNING
                    | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR,
            )
            .message_type(
                vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                    | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                    | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
            )
            .pfn_user_callback(Some(debug_callback))
            .user_data(Arc::as_ptr(&errors) as *mut c_void);
        let mut create_info = vk::InstanceCreateInfo::default().application_info(&app);
        if validation {
            // Chaining the messenger info also reports problems in vkCreate/DestroyInstance.
            create_info = create_info
                .enabled_layer_names(&layers)
                .enabled_extension_names(&extensions)
                .push_next(&mut messenger_info);
        }
        // SAFETY: create_info and everything it points to outlive the call.
        let instance =
            unsafe { entry.create_instance(&create_info, None) }.map_err(
                |result| match result {
                    vk::Result::ERROR_INCOMPATIBLE_DRIVER => VulkanError::NoDevice,
                    result => VulkanError::vk("vkCreateInstance", result),
                },
            )?;
        let mut holder = InstanceHolder {
            entry,
            instance,
            messenger: None,
            errors,
        };
        if validation {
            let loader = ash::ext::debug_utils::Instance::new(&holder.entry, &holder.instance);
            // SAFETY: the callback's user data (the errors mutex) lives as long as `holder`.
            let messenger = unsafe { loader.create_debug_utils_messenger(&messenger_info, None) }
                .map_err(vk_err("vkCreateDebugUtilsMessengerEXT"))?;
            holder.messenger = Some((loader, messenger));
        }
        Ok(holder)
    }

    /// Usable devices (Vulkan >= 1.1 with a compute queue and subgroup
    /// arithmetic in compute shaders) in enumeration order.
    fn devices(&self) -> Result<Vec<PhysicalDevice>, VulkanError> {
        // SAFETY: valid instance.
        let all = unsafe { self.instance.enumerate_physical_devices() }
            .map_err(vk_err("vkEnumeratePhysicalDevices"))?;
        let mut usable = Vec::new();
        for handle in all {
            if let Some(device) = self.describe(handle, usable.len())? {
                usable.push(device);
            }
        }
        Ok(usable)
    }

    fn describe(
        &self,
        handle: vk::PhysicalDevice,
        index: usize,
    ) -> Result<Option<PhysicalDevice>, VulkanError> {
        let instance = &self.instance;
        // SAFETY: `handle` comes from this instance; the pNext chains below point to locals.
        let props = unsafe { instance.get_physical_device_properties(handle) };
        if props.api_version < vk::API_VERSION_1_1 {
            return Ok(None);
        }
        let families = unsafe { instance.get_physical_device_queue_family_properties(handle) };
        let Some(queue_family) = families
            .iter()
            .position(|f| f.queue_flags.contains(vk::QueueFlags::COMPUTE) && f.queue_count > 0)
        else {
            return Ok(None);
        };
        // Driver properties are core in 1.2; older devices may expose VK_KHR_driver_properties.
        let has_driver_props = props.api_version >= vk::API_VERSION_1_2 || {
            let exts = unsafe { instance.enumerate_device_extension_properties(handle) }
                .map_err(vk_err("vkEnumerateDeviceExtensionProperties"))?;
            exts.iter()
                .any(|e| e.extension_name_as_c_str() == Ok(ash::khr::driver_properties::NAME))
        };
        let mut maintenance3 = vk::PhysicalDeviceMaintenance3Properties::default();
        let mut driver = vk::PhysicalDeviceDriverProperties::default();
        let mut subgroup = vk::PhysicalDeviceSubgroupProperties::default();
        let mut props2 = vk::PhysicalDeviceProperties2::default()
            .push_next(&mut maintenance3)
            .push_next(&mut subgroup);
        if has_driver_props {
            props2 = props2.push_next(&mut driver);
        }
        unsafe { instance.get_physical_device_properties2(handle, &mut props2) };
        // The kernel sums its ray counters per subgroup (subgroupAdd), and
        // the packet traversal votes and broadcasts (subgroupAny,
        // subgroupBroadcastFirst): lavapipe and every desktop GPU have
        // these; a device without them is not usable.
        let ops = vk::SubgroupFeatureFlags::BASIC
            | vk::SubgroupFeatureFlags::ARITHMETIC
            | vk::SubgroupFeatureFlags::VOTE
            | vk::SubgroupFeatureFlags::BALLOT;
        if !subgroup
            .supported_stages
            .contains(vk::ShaderStageFlags::COMPUTE)
            || !subgroup.supported_operations.contains(ops)
        {
            return Ok(None);
        }
        let c_str = |r: Result<&CStr, _>| {
            r.map(|s: &CStr| s.to_string_lossy().into_owned())
                .unwrap_or_default()
        };
        let device_type = match props.device_type {
            vk::PhysicalDeviceType::DISCRETE_GPU => "discrete GPU",
            vk::PhysicalDeviceType::INTEGRATED_GPU => "integrated GPU",
            vk::PhysicalDeviceType::VIRTUAL_GPU => "virtual GPU",
            vk::PhysicalDeviceType::CPU => "CPU",
            _ => "other",
        };
        let v = props.api_version;
        let info = DeviceInfo {
            index,
            name: c_str(props.device_name_as_c_str()),
            device_type: device_type.to_string(),
            api_version: format!(
                "{}.{}.{}",
                vk::api_version_major(v),
                vk::api_version_minor(v),
                vk::api_version_patch(v)
            ),
            // Left zeroed (empty strings) when the device lacks driver properties.
            driver_name: c_str(driver.driver_name_as_c_str()),
            driver_info: c_str(driver.driver_info_as_c_str()),
            vendor_id: props.vendor_id,
            device_id: props.device_id,
            driver_version: props.driver_version,
            pipeline_cache_uuid: props.pipeline_cache_uuid,
        };
        let l = &props.limits;
        let limits = DeviceLimits {
            max_storage_buffer_range: l.max_storage_buffer_range.into(),
            max_uniform_buffer_range: l.max_uniform_buffer_range.into(),
            max_compute_work_group_count: l.max_compute_work_group_count,
            max_compute_work_group_invocations: l.max_compute_work_group_invocations,
            max_push_constants_size: l.max_push_constants_size,
            max_memory_allocation_size: maintenance3.max_memory_allocation_size,
            max_image_dimension_2d: l.max_image_dimension2_d,
            subgroup_size: subgroup.subgroup_size,
        };
        let queue_family = queue_family as u32;
        Ok(Some(PhysicalDevice {
            handle,
            info,
            limits,
            queue_family,
        }))
    }
}

impl Drop for InstanceHolder {
    fn drop(&mut self) {
        // SAFETY: the device (if any) was destroyed by DeviceShared before we get here.
        unsafe {
            if let Some((loader, messenger)) = self.messenger.take() {
                loader.destroy_debug_utils_messenger(messenger, None);
            }
            self.instance.destroy_instance(None);
        }
    }
}

/// Validation callback: print warnings and errors, record errors for `check_validation`.
unsafe extern "system" fn debug_callback(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _types: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user_data: *mut c_void,
) -> vk::Bool32 {
    // SAFETY: the layer passes valid (or null) pointers; user_data is the errors mutex.
    let message = unsafe { data.as_ref().and_then(|d| d.message_as_c_str()) }
        .map(|m| m.to_string_lossy().into_owned())
        .unwrap_or_default();
    eprintln!("vulkan validation: {message}");
    if severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR) {
        if let Some(errors) = unsafe { (user_data as *const Mutex<Vec<String>>).as_ref() } {
            errors
                .lock()
                .unwrap_or_else(|e| e.into_inner())
                .push(message);
        }
    }
    vk::FALSE
}

/// A usable physical device with what we learned about it.
struct PhysicalDevice {
    handle: vk::PhysicalDevice,
    info: DeviceInfo,
    limits: DeviceLimits,
    queue_family: u32,
}

/// The logical device, shared by the context, buffers and pipelines; destroyed last.
pub(crate) struct DeviceShared {
    pub(crate) device: ash::Device,
    /// Dropped by hand after the device, unless the device hung.
    instance: std::mem::ManuallyDrop<InstanceHolder>,
    /// Set when a wait ran past the time limit ([`Context::time_limit`]): the
    /// queue is still running work that cannot be cancelled, so nothing it
    /// may use is destroyed any more (every `Drop` leaks instead), and every
    /// later submit fails at once. Only ending the process frees the device.
    hung: std::sync::atomic::AtomicBool,
    /// The device's pipeline cache (src/vulkan/pipeline_cache.rs), and the
    /// file it is written back to when the device closes.
    pub(crate) pipeline_cache: vk::PipelineCache,
    pipeline_cache_file: Option<std::path::PathBuf>,
}

impl DeviceShared {
    /// Whether a wait on this device ran past its time limit.
    pub(crate) fn is_hung(&self) -> bool {
        self.hung.load(std::sync::atomic::Ordering::Acquire)
    }

    /// Marks the device as running work that will not be waited for.
    pub(crate) fn mark_hung(&self) {
        self.hung.store(true, std::sync::atomic::Ordering::Release)
    }
}

impl Drop for DeviceShared {
    fn drop(&mut self) {
        if self.is_hung() {
            // The queue still runs: destroying the device, the instance or unloading the
            // driver under it is undefined, and waiting for it would never end. Leak them.
            return;
        }
        // SAFETY: every object created from the device holds an Arc to us, so all are gone;
        // the instance goes after its device, and is not used after this.
        unsafe {
            let _ = self.device.device_wait_idle();
            if let Some(path) = &self.pipeline_cache_file {
                super::pipeline_cache::save(&self.device, self.pipeline_cache, path);
            }
            self.device
                .destroy_pipeline_cache(self.pipeline_cache, None);
            self.device.destroy_device(None);
            std::mem::ManuallyDrop::drop(&mut self.instance);
        }
    }
}

/// Queue submission state; Vulkan requires external synchronisation of both handles.
pub(crate) struct Submitter {
    pub(crate) queue: vk::Queue,
    pub(crate) command_pool: vk::CommandPool,
    pub(crate) command_buffer: vk::CommandBuffer,
}

/// An open Vulkan device with one compute queue; creates buffers and pipelines and runs dispatches.
pub struct Context {
    pub(crate) shared: Arc<DeviceShared>,
    pub(crate) submitter: Mutex<Submitter>,
    pub(crate) memory_properties: vk::PhysicalDeviceMemoryProperties,
    /// `PENUMBRA_FORCE_STAGING=1`: never map device memory, always go through staging buffers.
    pub(crate) force_staging: bool,
    /// What the device can do with texel images' format in optimal tiling (Vulkan makes
    /// storage-image use of `R32G32B32A32_UINT` mandatory; checked all the same).
    pub(crate) texel_format_features: vk::FormatFeatureFlags,
    /// Whether stage images can be linear images aliased by storage buffers
    /// ([`Context::stage_words`]), probed at creation.
    pub(crate) stage_words: bool,
    /// Whether a stage invocation may find its pixel by its subgroup and
    /// lane ([`Context::lane_pixels`]).
    lane_pixels: bool,
    info: DeviceInfo,
    limits: DeviceLimits,
    /// The staging buffers kept between transfers: upload, readback (`Context::staging`).
    pub(crate) staging: Mutex<[Option<super::Buffer>; 2]>,
    /// The longest one wait on the device may take, in nanoseconds ([`Context::set_time_limit`]).
    time_limit: std::sync::atomic::AtomicU64,
    /// The longest wait so far, in nanoseconds ([`Context::longest_wait`]).
    longest_wait: std::sync::atomic::AtomicU64,
}

fn physical_is_cpu(info: &DeviceInfo) -> bool {
    info.device_type == "CPU"
}

fn env_flag(name: &str) -> bool {
    std::env::var(name).is_ok_and(|v| v == "1")
}

impl Context {
    /// Lists the usable devices (Vulkan >= 1.1 with a compute queue) in enumeration order.
    pub fn list_devices() -> Result<Vec<DeviceInfo>, VulkanError> {
        let holder = InstanceHolder::new(false)?;
        Ok(holder.devices()?.into_iter().map(|d| d.info).collect())
    }

    /// Opens the selected device (see [`ContextOptions`]).
    pub fn new(opts: &ContextOptions) -> Result<Context, VulkanError> {
        let instance = InstanceHolder::new(opts.validation || env_flag("PENUMBRA_VALIDATION"))?;
        let physical = select(instance.devices()?, opts.device.as_ref())?;
        let priorities = [1.0];
        let queue_info = [vk::DeviceQueueCreateInfo::default()
            .queue_family_index(physical.queue_family)
            .queue_priorities(&priorities)];
        // No extensions, and one optional feature: 64-bit integers, with which
        // the stages store their records on a CPU device (`stage_words`).
        // SAFETY: physical device from this instance.
        let supported = unsafe {
            instance
                .instance
                .get_physical_device_features(physical.handle)
        };
        let shader_int64 = supported.shader_int64 == vk::TRUE;
        let features = vk::PhysicalDeviceFeatures::default().shader_int64(shader_int64);
        let device_info = vk::DeviceCreateInfo::default()
            .queue_create_infos(&queue_info)
            .enabled_features(&features);
        // SAFETY: physical device from this instance; create info outlives the call.
        let device = unsafe {
            instance
                .instance
                .create_device(physical.handle, &device_info, None)
        }
        .map_err(vk_err("vkCreateDevice"))?;
        let identity = super::pipeline_cache::CacheIdentity {
            vendor_id: physical.info.vendor_id,
            device_id: physical.info.device_id,
            driver_version: physical.info.driver_version,
            uuid: physical.info.pipeline_cache_uuid,
        };
        let pipeline_cache_file = super::pipeline_cache::file(&identity);
        let initial = pipeline_cache_file
            .as_deref()
            .map(|p| super::pipeline_cache::read(p, &identity))
            .unwrap_or_default();
        let pipeline_cache = super::pipeline_cache::create(&device, &initial);
        let shared = Arc::new(DeviceShared {
            device,
            instance: std::mem::ManuallyDrop::new(instance),
            hung: std::sync::atomic::AtomicBool::new(false),
            pipeline_cache,
            pipeline_cache_file,
        });
        let device = &shared.device;
        // SAFETY: family/index were requested at device creation.
        let queue = unsafe { device.get_device_queue(physical.queue_family, 0) };
        let pool_info = vk::CommandPoolCreateInfo::default()
            .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER)
            .queue_family_index(physical.queue_family);
        let command_pool = unsafe { device.create_command_pool(&pool_info, None) }
            .map_err(vk_err("vkCreateCommandPool"))?;
        let alloc_info = vk::CommandBufferAllocateInfo::default()
            .command_pool(command_pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        let command_buffer = match unsafe { device.allocate_command_buffers(&alloc_info) } {
            Ok(buffers) if !buffers.is_empty() => buffers[0],
            other => {
                unsafe { device.destroy_command_pool(command_pool, None) };
                let result = other.err().unwrap_or(vk::Result::ERROR_UNKNOWN);
                return Err(VulkanError::vk("vkAllocateCommandBuffers", result));
            }
        };
        let instance = &shared.instance.instance;
        let memory_properties =
            unsafe { instance.get_physical_device_memory_properties(physical.handle) };
        let texel_formats = unsafe {
            instance.get_physical_device_format_properties(
                physical.handle,
                vk::Format::R32G32B32A32_UINT,
            )
        };
        let texel_format_features = texel_formats.optimal_tiling_features;
        let linear_storage = texel_formats
            .linear_tiling_features
            .contains(vk::FormatFeatureFlags::STORAGE_IMAGE);
        let mut context = Context {
            submitter: Mutex::new(Submitter {
                queue,
                command_pool,
                command_buffer,
            }),
            memory_properties,
            force_staging: env_flag("PENUMBRA_FORCE_STAGING"),
            texel_format_features,
            stage_words: false,
            lane_pixels: false,
            info: physical.info,
            limits: physical.limits,
            staging: Mutex::new([None, None]),
            time_limit: std::sync::atomic::AtomicU64::new(DEFAULT_TIME_LIMIT.as_nanos() as u64),
            longest_wait: std::sync::atomic::AtomicU64::new(0),
            shared,
        };
        // Only on CPU devices (lavapipe), where a texel store costs several
        // buffer stores; a GPU reads linear images more slowly than optimal
        // ones and writes either fast. The words are stored as 64-bit
        // integers (shaders/render.wgsl's `stage_words`), which every CPU
        // device we know of supports.
        context.stage_words = linear_storage
            && shader_int64
            && physical_is_cpu(&context.info)
            && context.probe_stage_words()?;
        let subgroup = context.limits.subgroup_size;
        context.lane_pixels = physical_is_cpu(&context.info) && subgroup > 0 && 64 % subgroup == 0;
        Ok(context)
    }

    /// Whether the stages' workgroups of 64 invocations are whole subgroups
    /// in order, so that `subgroup_id · subgroup_size +
    /// subgroup_invocation_id` numbers a workgroup's invocations from 0 to
    /// 63 (`shaders/render.wgsl`'s `LANE_PIXELS`).
    ///
    /// Why: lavapipe computes every lane's `local_invocation_index` (and
    /// `global_invocation_id`) with integer divisions by the workgroup's
    /// size at the start of each SIMD group (docs/stages.md measures what
    /// they cost), while its subgroup ids are a loop counter and a constant
    /// vector. A CPU device (lavapipe) runs a workgroup as its
    /// SIMD groups one after another, each a whole subgroup of the vector
    /// width (8 or 16 lanes, dividing 64). Vulkan 1.1 promises neither on a
    /// GPU, where the index costs nothing, so a GPU keeps the index.
    pub fn lane_pixels(&self) -> bool {
        self.lane_pixels
    }

    /// The device this context runs on.
    pub fn info(&self) -> &DeviceInfo {
        &self.info
    }

    /// The device's limits.
    pub fn limits(&self) -> &DeviceLimits {
        &self.limits
    }

    /// Err(Validation{..}) if the validation messenger recorded any error-severity message since
    /// the context was created (or since the last call). Always Ok without validation.
    pub fn check_validation(&self) -> Result<(), VulkanError> {
        let mut errors = self
            .shared
            .instance
            .errors
            .lock()
            .unwrap_or_else(|e| e.into_inner());
        let drained: Vec<String> = errors.drain(..).collect();
        match drained.first() {
            None => Ok(()),
            Some(first) => Err(VulkanError::Validation {
                count: drained.len(),
                first: first.clone(),
            }),
        }
    }
}

/// The longest that one submission may run on the device unless set otherwise
/// ([`Context::set_time_limit`]): a watchdog for shader code that never ends. Far above what
/// any honest submission takes (one pass over a band of the image, at most 128 MiB of pixels;
/// docs/watchdog.md lists the longest measured on the scenes in scenes/).
pub const DEFAULT_TIME_LIMIT: Duration = Duration::from_secs(60);

/// The longest the driver's compile of one pipeline may take (lavapipe compiles at the first
/// dispatch; penumbra's stages take 0.5–2.8 s cold): the first dispatch of a pipeline waits
/// this long, or the time limit if that is longer.
pub const DRIVER_COMPILE_LIMIT: Duration = Duration::from_secs(60);

impl Context {
    /// Bounds every later wait on the device: a submission that has not finished after
    /// `limit` fails with [`VulkanError::TimedOut`] and leaves the device hung (see there).
    pub fn set_time_limit(&self, limit: Duration) {
        let nanos = u64::try_from(limit.as_nanos()).unwrap_or(u64::MAX);
        self.time_limit
            .store(nanos, std::sync::atomic::Ordering::Relaxed);
    }

    /// The bound on one wait ([`Context::set_time_limit`]; [`DEFAULT_TIME_LIMIT`] unless set).
    pub fn time_limit(&self) -> Duration {
        Duration::from_nanos(self.time_limit.load(std::sync::atomic::Ordering::Relaxed))
    }

    /// Whether a wait ran past the time limit: the device still runs that work, and every
    /// later submit fails.
    pub fn is_hung(&self) -> bool {
        self.shared.is_hung()
    }

    /// The longest that one submission has run since the last call, from submit to its fence
    /// (the driver's compile at a pipeline's first dispatch included): how far the work stays
    /// from [`Context::time_limit`] (tools/measure/watchdog_margin.rs).
    pub fn take_longest_wait(&self) -> Duration {
        Duration::from_nanos(
            self.longest_wait
                .swap(0, std::sync::atomic::Ordering::Relaxed),
        )
    }

    /// Records one wait for [`Context::take_longest_wait`].
    pub(crate) fn record_wait(&self, wait: Duration) {
        let nanos = u64::try_from(wait.as_nanos()).unwrap_or(u64::MAX);
        self.longest_wait
            .fetch_max(nanos, std::sync::atomic::Ordering::Relaxed);
    }
}

impl Drop for Context {
    fn drop(&mut self) {
        if self.shared.is_hung() {
            return;
        }
        let submitter = self.submitter.get_mut().unwrap_or_else(|e| e.into_inner());
        // SAFETY: waiting for idle guarantees the command buffer is no longer pending.
        unsafe {
            let _ = self.shared.device.device_wait_idle();
            self.shared
                .device
                .destroy_command_pool(submitter.command_pool, None);
        }
    }
}

/// Applies the selection rules of [`ContextOptions::device`].
fn select(
    devices: Vec<PhysicalDevice>,
    selector: Option<&DeviceSelector>,
) -> Result<PhysicalDevice, VulkanError> {
    if devices.is_empty() {
        return Err(VulkanError::NoDevice);
    }
    let position = match selector {
        None => ["discrete GPU", "integrated GPU"]
            .iter()
            .find_map(|t| devices.iter().position(|d| d.info.device_type == *t))
            .or(Some(0)),
        Some(DeviceSelector::Index(i)) => (*i < devices.len()).then_some(*i),
        Some(DeviceSelector::Name(name)) => {
            let name = name.to_lowercase();
            devices
                .iter()
                .position(|d| !name.is_empty() && d.info.name.to_lowercase().contains(&name))
        }
    };
    match position {
        Some(i) => devices.into_iter().nth(i).ok_or(VulkanError::NoDevice),
        None => Err(VulkanError::NoMatchingDevice {
            wanted: match selector {
                Some(DeviceSelector::Index(i)) => i.to_string(),
                Some(DeviceSelector::Name(n)) => n.clone(),
                None => String::new(),
            },
            available: devices
                .iter()
                .map(|d| format!("{}: {}", d.info.index, d.info.name))
                .collect::<Vec<_>>()
                .join(", "),
        }),
    }
}
