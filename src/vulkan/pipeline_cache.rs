//! A `VkPipelineCache` kept on disk per device and driver, so that a GPU
//! driver need not compile the kernel's pipelines again in every process
//! (pipeline creation took 490 ms of a 0.7 s one-shot render on an H200,
//! docs/gpu.md). lavapipe ignores it (its data is the header alone) and keeps
//! its own shader cache.
//!
//! The file is `penumbra/pipelines-VENDOR-DEVICE-DRIVERVERSION-UUID.bin` in
//! the user's cache directory (`$XDG_CACHE_HOME`, else `~/.cache`). Its data
//! goes to the driver only when its header is the one this device writes
//! (Vulkan's `VkPipelineCacheHeaderVersionOne`: checked here, since a driver
//! is not required to survive foreign data); anything else is ignored. It is
//! written back when the device closes, atomically (a temporary file renamed
//! over it). `PENUMBRA_PIPELINE_CACHE=0` turns it off.

use std::path::{Path, PathBuf};

use ash::vk;

/// Size of `VkPipelineCacheHeaderVersionOne`: headerSize, headerVersion,
/// vendorID, deviceID (4 bytes each) and pipelineCacheUUID (16).
pub const HEADER_BYTES: usize = 32;

/// A pipeline cache file larger than this is not read.
pub const MAX_FILE_BYTES: u64 = 256 << 20;

/// What a cache's data must have been written for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CacheIdentity {
    /// `VkPhysicalDeviceProperties::vendorID`.
    pub vendor_id: u32,
    /// `deviceID`.
    pub device_id: u32,
    /// `driverVersion` (the file name only: the header does not hold it).
    pub driver_version: u32,
    /// `pipelineCacheUUID`.
    pub uuid: [u8; 16],
}

impl CacheIdentity {
    /// The file's name.
    pub fn file_name(&self) -> String {
        let uuid: String = self.uuid.iter().map(|b| format!("{b:02x}")).collect();
        format!(
            "pipelines-{:04x}-{:04x}-{:08x}-{uuid}.bin",
            self.vendor_id, self.device_id, self.driver_version
        )
    }

    /// Whether `data` starts with the header this device writes. The Vulkan
    /// specification (section "Pipeline Cache Header"): headerSize ≥ 32,
    /// headerVersion `VK_PIPELINE_CACHE_HEADER_VERSION_ONE` (1), then the
    /// vendor and device IDs and the UUID, every field least significant
    /// byte first whatever the host's byte order.
    pub fn accepts(&self, data: &[u8]) -> bool {
        if data.len() < HEADER_BYTES {
            return false;
        }
        let word = |i: usize| u32::from_le_bytes([data[i], data[i + 1], data[i + 2], data[i + 3]]);
        let header_size = word(0) as usize;
        header_size >= HEADER_BYTES
            && header_size <= data.len()
            && word(4) == vk::PipelineCacheHeaderVersion::ONE.as_raw() as u32
            && word(8) == self.vendor_id
            && word(12) == self.device_id
            && data[16..32] == self.uuid
    }
}

/// The file for this device, or `None` where it is turned off or no cache
/// directory is known.
pub fn file(identity: &CacheIdentity) -> Option<PathBuf> {
    if std::env::var("PENUMBRA_PIPELINE_CACHE").is_ok_and(|v| v == "0") {
        return None;
    }
    crate::user_cache::penumbra_dir(|k| std::env::var_os(k)).map(|d| d.join(identity.file_name()))
}

/// The file's data if it is this device's, else nothing.
pub fn read(path: &Path, identity: &CacheIdentity) -> Vec<u8> {
    let fits = std::fs::metadata(path).is_ok_and(|m| m.len() <= MAX_FILE_BYTES);
    match std::fs::read(path) {
        Ok(data) if fits && identity.accepts(&data) => data,
        _ => Vec::new(),
    }
}

/// Writes `data` to `path` atomically, making the directory if needed.
pub fn write(path: &Path, data: &[u8]) -> std::io::Result<()> {
    let dir = path.parent().unwrap_or(Path::new("."));
    std::fs::create_dir_all(dir)?;
    let mut tmp = tempfile::NamedTempFile::new_in(dir)?;
    std::io::Write::write_all(&mut tmp, data)?;
    tmp.persist(path).map_err(|e| e.error)?;
    Ok(())
}

/// Creates the device's pipeline cache from `initial` data, or empty if the
/// driver refuses the data.
pub(crate) fn create(device: &ash::Device, initial: &[u8]) -> vk::PipelineCache {
    let make = |data: &[u8]| {
        let info = vk::PipelineCacheCreateInfo::default().initial_data(data);
        // SAFETY: the create info points to `data`, which outlives the call.
        unsafe { device.create_pipeline_cache(&info, None) }
    };
    make(initial)
        .or_else(|_| make(&[]))
        .unwrap_or(vk::PipelineCache::null())
}

/// Writes the cache's data to `path` (errors are ignored: the cache is an
/// optimisation).
pub(crate) fn save(device: &ash::Device, cache: vk::PipelineCache, path: &Path) {
    if cache == vk::PipelineCache::null() {
        return;
    }
    // SAFETY: `cache` was created from `device` and is not in use by another thread.
    if let Ok(data) = unsafe { device.get_pipeline_cache_data(cache) } {
        let _ = write(path, &data);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const ID: CacheIdentity = CacheIdentity {
        vendor_id: 0x10de,
        device_id: 0x2335,
        driver_version: 0x8a1c_8000,
        uuid: [7; 16],
    };

    /// A header as the specification lays it out, then `extra` bytes.
    fn header(
        size: u32,
        version: u32,
        vendor: u32,
        device: u32,
        uuid: [u8; 16],
        extra: usize,
    ) -> Vec<u8> {
        let mut d = Vec::new();
        for w in [size, version, vendor, device] {
            d.extend_from_slice(&w.to_le_bytes());
        }
        d.extend_from_slice(&uuid);
        d.resize(d.len() + extra, 0xab);
        d
    }

    #[test]
    fn this_devices_header_is_accepted() {
        assert!(ID.accepts(&header(32, 1, 0x10de, 0x2335, [7; 16], 0)));
        assert!(ID.accepts(&header(32, 1, 0x10de, 0x2335, [7; 16], 100)));
        assert!(ID.accepts(&header(48, 1, 0x10de, 0x2335, [7; 16], 16)));
    }

    #[test]
    fn any_other_header_is_refused() {
        let ok = header(32, 1, 0x10de, 0x2335, [7; 16], 8);
        assert!(!ID.accepts(&ok[..31]), "truncated");
        assert!(!ID.accepts(&[]));
        assert!(
            !ID.accepts(&header(16, 1, 0x10de, 0x2335, [7; 16], 8)),
            "headerSize below 32"
        );
        assert!(
            !ID.accepts(&header(64, 1, 0x10de, 0x2335, [7; 16], 8)),
            "headerSize past the data"
        );
        assert!(
            !ID.accepts(&header(32, 2, 0x10de, 0x2335, [7; 16], 8)),
            "version"
        );
        assert!(
            !ID.accepts(&header(32, 1, 0x1002, 0x2335, [7; 16], 8)),
            "vendor"
        );
        assert!(
            !ID.accepts(&header(32, 1, 0x10de, 0x2336, [7; 16], 8)),
            "device"
        );
        assert!(
            !ID.accepts(&header(32, 1, 0x10de, 0x2335, [8; 16], 8)),
            "UUID"
        );
        // Big-endian fields are another header.
        let mut be = ok.clone();
        be[0..4].copy_from_slice(&32u32.to_be_bytes());
        assert!(!ID.accepts(&be));
    }

    #[test]
    fn the_file_name_holds_device_and_driver() {
        assert_eq!(
            ID.file_name(),
            "pipelines-10de-2335-8a1c8000-07070707070707070707070707070707.bin"
        );
        let other = CacheIdentity {
            driver_version: 1,
            ..ID
        };
        assert_ne!(ID.file_name(), other.file_name());
    }

    #[test]
    fn read_refuses_foreign_files_and_write_is_whole() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("sub").join(ID.file_name());
        assert!(read(&path, &ID).is_empty(), "missing");
        let good = header(32, 1, 0x10de, 0x2335, [7; 16], 40);
        write(&path, &good).unwrap();
        assert_eq!(read(&path, &ID), good);
        write(&path, &header(32, 1, 0x10de, 0x2335, [9; 16], 40)).unwrap();
        assert!(read(&path, &ID).is_empty(), "foreign");
        write(&path, b"garbage").unwrap();
        assert!(read(&path, &ID).is_empty(), "corrupt");
    }
}
