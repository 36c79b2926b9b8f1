//! The calibration's memory: the measured times per machine, in
//! `$XDG_CACHE_HOME/penumbra/calibration.json` (else
//! `~/.cache/penumbra/calibration.json`), one entry per CPU, kernel and
//! driver, so that a home directory shared by several machines keeps each
//! one's. A file that cannot be read as this version's is ignored with a
//! note (and rewritten by the next calibration), never an error.

use std::ffi::OsString;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::Measured;

/// The file's `format` field.
pub const FORMAT: &str = "penumbra calibration";

/// The file's `version`: a file of another version is ignored.
pub const VERSION: u32 = 1;

/// The file's name in the cache directory.
pub const FILE_NAME: &str = "calibration.json";

/// What a calibration holds for: the CPU, the kernel and the driver.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Key {
    /// The CPU: vendor, family, model, model name and a hash of its flags.
    pub cpu: String,
    /// The kernel's release (`uname -r`).
    pub kernel: String,
    /// The Vulkan driver: its driverName and driverInfo
    /// (VkPhysicalDeviceDriverProperties), as the probe's device reported them.
    pub driver: String,
}

/// One machine's calibration.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Entry {
    /// What it holds for.
    #[serde(flatten)]
    pub key: Key,
    /// Each candidate's frame times.
    pub measured: Vec<Measured>,
}

/// The whole file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Wisdom {
    /// [`FORMAT`].
    pub format: String,
    /// [`VERSION`].
    pub version: u32,
    /// Every machine's.
    pub entries: Vec<Entry>,
}

impl Default for Wisdom {
    fn default() -> Wisdom {
        Wisdom {
            format: FORMAT.into(),
            version: VERSION,
            entries: Vec::new(),
        }
    }
}

impl Wisdom {
    /// Reads `path`: `Ok(None)` when there is no file, `Err(why)` when it is
    /// not a calibration file of this version (the caller notes it and
    /// carries on without it).
    pub fn read(path: &Path) -> Result<Option<Wisdom>, String> {
        let text = match std::fs::read(path) {
            Ok(t) => t,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
            Err(e) => return Err(e.to_string()),
        };
        // A calibration file is a few hundred bytes a machine.
        if text.len() > 1 << 20 {
            return Err("larger than 1 MiB".into());
        }
        Wisdom::parse(&text).map(Some)
    }

    /// Parses a file's bytes.
    pub fn parse(text: &[u8]) -> Result<Wisdom, String> {
        #[derive(Deserialize)]
        struct Header {
            format: String,
            version: u32,
        }
        let h: Header = serde_json::from_slice(text).map_err(|e| e.to_string())?;
        if h.format != FORMAT || h.version != VERSION {
            return Err(format!(
                "format `{}` version {}, not `{FORMAT}` version {VERSION}",
                h.format, h.version
            ));
        }
        serde_json::from_slice(text).map_err(|e| e.to_string())
    }

    /// The entry for this CPU and kernel. The driver is not known before
    /// the driver loads, and the settings must be in the environment by then:
    /// the caller checks the entry's driver against the device's afterwards.
    pub fn find(&self, cpu: &str, kernel: &str) -> Option<&Entry> {
        self.entries
            .iter()
            .find(|e| e.key.cpu == cpu && e.key.kernel == kernel)
    }

    /// Puts `entry` in, replacing any of the same CPU and kernel.
    pub fn insert(&mut self, entry: Entry) {
        self.remove(&entry.key.cpu, &entry.key.kernel);
        self.entries.push(entry);
    }

    /// Removes the entry of this CPU and kernel.
    pub fn remove(&mut self, cpu: &str, kernel: &str) {
        self.entries
            .retain(|e| !(e.key.cpu == cpu && e.key.kernel == kernel));
    }

    /// Writes the file atomically (a temporary file in the same directory,
    /// renamed over it), making the directory if needed.
    pub fn write(&self, path: &Path) -> std::io::Result<()> {
        let dir = path.parent().unwrap_or(Path::new("."));
        std::fs::create_dir_all(dir)?;
        let mut tmp = tempfile::NamedTempFile::new_in(dir)?;
        serde_json::to_writer_pretty(&mut tmp, self)?;
        std::io::Write::write_all(&mut tmp, b"\n")?;
        tmp.persist(path).map_err(|e| e.error)?;
        Ok(())
    }
}

pub use crate::user_cache::user_cache_dir;

/// The calibration file: `penumbra/calibration.json` in [`user_cache_dir`].
pub fn path(var: impl Fn(&str) -> Option<OsString>) -> Option<PathBuf> {
    crate::user_cache::penumbra_dir(var).map(|d| d.join(FILE_NAME))
}

/// This machine's CPU, from the text of `/proc/cpuinfo`: vendor, family,
/// model and model name of the first processor, and a hash of its flags
/// (the instruction sets; the hash keeps the key short).
pub fn cpu_key(cpuinfo: &str) -> String {
    use sha2::Digest as _;
    let field = |name: &str| {
        cpuinfo
            .lines()
            .take_while(|l| !l.trim().is_empty())
            .find_map(|l| {
                let (k, v) = l.split_once(':')?;
                (k.trim() == name).then(|| v.trim().to_owned())
            })
            .unwrap_or_default()
    };
    let flags = sha2::Sha256::digest(field("flags").as_bytes());
    let hex: String = flags[..6].iter().map(|b| format!("{b:02x}")).collect();
    format!(
        "{} family {} model {} ({}), flags {hex}",
        field("vendor_id"),
        field("cpu family"),
        field("model"),
        field("model name")
    )
}

/// This machine's CPU ([`cpu_key`] of `/proc/cpuinfo`; the architecture
/// alone where there is none).
pub fn this_cpu() -> String {
    match std::fs::read_to_string("/proc/cpuinfo") {
        Ok(text) => cpu_key(&text),
        Err(_) => std::env::consts::ARCH.to_owned(),
    }
}

/// This machine's kernel release (`uname -r`).
pub fn this_kernel() -> String {
    std::fs::read_to_string("/proc/sys/kernel/osrelease")
        .map(|s| s.trim().to_owned())
        .unwrap_or_else(|_| std::env::consts::OS.to_owned())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calibration::Candidate;

    fn entry(cpu: &str, driver: &str, ms: f64) -> Entry {
        Entry {
            key: Key {
                cpu: cpu.into(),
                kernel: "6.1".into(),
                driver: driver.into(),
            },
            measured: vec![Measured::of(Candidate::Wide256, &[ms, ms + 1.0]).unwrap()],
        }
    }

    #[test]
    fn a_written_file_reads_back() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("sub/calibration.json");
        assert_eq!(Wisdom::read(&path), Ok(None));
        let mut w = Wisdom::default();
        w.insert(entry("A", "Mesa 1", 10.0));
        w.insert(entry("B", "Mesa 1", 20.0));
        w.insert(entry("A", "Mesa 2", 30.0));
        w.write(&path).unwrap();
        let back = Wisdom::read(&path).unwrap().unwrap();
        assert_eq!(back, w);
        assert_eq!(
            back.entries.len(),
            2,
            "A's new driver replaced its old entry"
        );
        assert_eq!(back.find("A", "6.1").unwrap().key.driver, "Mesa 2");
        assert!(back.find("A", "6.2").is_none());
        assert!(back.find("C", "6.1").is_none());
    }

    #[test]
    fn corrupt_or_foreign_files_are_refused_with_a_reason() {
        assert!(Wisdom::parse(b"{not json").is_err());
        assert!(Wisdom::parse(b"").is_err());
        let other = format!(
            r#"{{"format":"{FORMAT}","version":{},"entries":[]}}"#,
            VERSION + 1
        );
        assert!(Wisdom::parse(other.as_bytes())
            .unwrap_err()
            .contains("version 2"));
        let foreign = format!(r#"{{"format":"fftw","version":{VERSION},"entries":[]}}"#);
        assert!(Wisdom::parse(foreign.as_bytes())
            .unwrap_err()
            .contains("fftw"));
        let bad_entry =
            format!(r#"{{"format":"{FORMAT}","version":{VERSION},"entries":[{{"cpu":1}}]}}"#);
        assert!(Wisdom::parse(bad_entry.as_bytes()).is_err());
    }

    #[test]
    fn the_cache_directory_follows_xdg() {
        let env = |pairs: &'static [(&'static str, &'static str)]| {
            move |k: &str| {
                pairs
                    .iter()
                    .find(|(n, _)| *n == k)
                    .map(|(_, v)| OsString::from(v))
            }
        };
        assert_eq!(
            path(env(&[("HOME", "/h"), ("XDG_CACHE_HOME", "/x")])),
            Some(PathBuf::from("/x/penumbra/calibration.json"))
        );
        assert_eq!(
            path(env(&[("HOME", "/h"), ("XDG_CACHE_HOME", "")])),
            Some(PathBuf::from("/h/.cache/penumbra/calibration.json"))
        );
        assert_eq!(path(env(&[])), None);
    }

    #[test]
    fn the_cpu_key_names_the_model_and_its_flags() {
        let info = |flags: &str| {
            format!(
                "processor\t: 0\nvendor_id\t: AuthenticAMD\ncpu family\t: 26\nmodel\t\t: 2\nmodel name\t: AMD EPYC\nflags\t\t: {flags}\n\nprocessor\t: 1\nmodel\t\t: 99\n"
            )
        };
        let k = cpu_key(&info("sse avx avx512f"));
        assert!(
            k.starts_with("AuthenticAMD family 26 model 2 (AMD EPYC), flags "),
            "{k}"
        );
        assert_ne!(
            k,
            cpu_key(&info("sse avx")),
            "the flags are part of the key"
        );
        assert_eq!(k, cpu_key(&info("sse avx avx512f")));
    }
}
