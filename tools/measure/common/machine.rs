//! The machine a measurement ran on and when: the CPU from `/proc/cpuinfo`
//! (vendor, family, model and the instruction sets that decide how lavapipe's
//! and the peers' SIMD code runs, AVX2 or AVX-512 above all), the date and
//! the commit, for the header of a report.

use std::path::Path;
use std::process::Command;

use serde::{Deserialize, Serialize};

/// The instruction-set flags worth naming in a report, in this order.
const FLAGS: &[&str] = &[
    "sse4_2",
    "avx",
    "avx2",
    "fma",
    "bmi2",
    "avx512f",
    "avx512dq",
    "avx512cd",
    "avx512bw",
    "avx512vl",
    "avx512ifma",
    "avx512vbmi",
    "avx512_vbmi2",
    "avx512_vnni",
    "avx512_bf16",
    "avx512_bitalg",
    "avx512_vpopcntdq",
];

/// One CPU as `/proc/cpuinfo` describes its first processor.
#[derive(Serialize, Deserialize, Clone, Debug, Default)]
pub struct CpuInfo {
    pub vendor: String,
    pub family: u32,
    pub model: u32,
    pub model_name: String,
    /// The flags of [`FLAGS`] this CPU has.
    pub isa: Vec<String>,
    /// `GALLIUM_OVERRIDE_CPU_CAPS` as the measuring process found it: Mesa's
    /// cap on the instruction sets lavapipe targets, when one was set.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gallium_caps: Option<String>,
}

impl CpuInfo {
    /// Reads `/proc/cpuinfo`; fields it lacks stay empty or zero.
    pub fn read() -> CpuInfo {
        let text = std::fs::read_to_string("/proc/cpuinfo").unwrap_or_default();
        let first = text.split("\n\n").next().unwrap_or("");
        let field = |name: &str| {
            first
                .lines()
                .find(|l| l.split(':').next().is_some_and(|k| k.trim() == name))
                .and_then(|l| l.split_once(':'))
                .map(|(_, v)| v.trim().to_string())
                .unwrap_or_default()
        };
        let flags = field("flags");
        let have: Vec<&str> = flags.split_whitespace().collect();
        CpuInfo {
            vendor: field("vendor_id"),
            family: field("cpu family").parse().unwrap_or(0),
            model: field("model").parse().unwrap_or(0),
            model_name: field("model name"),
            isa: FLAGS
                .iter()
                .filter(|f| have.contains(f))
                .map(|f| f.to_string())
                .collect(),
            gallium_caps: std::env::var("GALLIUM_OVERRIDE_CPU_CAPS").ok(),
        }
    }

    /// Whether lavapipe generates AVX-512 code here: the CPU has it and no
    /// `GALLIUM_OVERRIDE_CPU_CAPS` caps it away (a cap that names no
    /// `avx512` does).
    pub fn avx512_in_use(&self) -> bool {
        self.avx512()
            && self
                .gallium_caps
                .as_deref()
                .is_none_or(|c| c.contains("avx512"))
    }

    /// Whether the CPU has AVX-512 Foundation.
    pub fn avx512(&self) -> bool {
        self.isa.iter().any(|f| f == "avx512f")
    }

    /// AMD's core generation for the families and models AMD documents
    /// (none for other vendors or unknown models).
    pub fn microarchitecture(&self) -> Option<&'static str> {
        if self.vendor != "AuthenticAMD" {
            return None;
        }
        match (self.family, self.model) {
            (23, 0x00..=0x2f) => Some("Zen / Zen+"),
            (23, 0x30..=0xff) => Some("Zen 2"),
            (25, 0x00..=0x0f | 0x20..=0x5f) => Some("Zen 3"),
            (25, 0x10..=0x1f | 0x60..=0x7f | 0xa0..=0xaf) => Some("Zen 4"),
            (26, _) => Some("Zen 5"),
            _ => None,
        }
    }

    /// One line for the report: `AMD EPYC: vendor AuthenticAMD, family 25,
    /// model 1 (Zen 3); sse4_2 avx avx2 fma bmi2; no AVX-512`.
    pub fn describe(&self) -> String {
        if self.vendor.is_empty() {
            return "unknown (no /proc/cpuinfo)".into();
        }
        format!(
            "{}: vendor {}, family {}, model {}{}; instruction sets: {}; {}",
            self.model_name,
            self.vendor,
            self.family,
            self.model,
            self.microarchitecture()
                .map_or(String::new(), |m| format!(" ({m})")),
            self.isa.join(" "),
            match (self.avx512(), &self.gallium_caps) {
                (true, Some(c)) if !self.avx512_in_use() =>
                    format!("with AVX-512, which lavapipe does not use here (`GALLIUM_OVERRIDE_CPU_CAPS={c}`)"),
                (true, _) => "with AVX-512".into(),
                (false, _) => "no AVX-512".into(),
            }
        )
    }
}

/// The CPU model from /proc/cpuinfo.
pub fn cpu_model() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into())
}

/// Now, UTC, as `YYYY-MM-DD HH:MM`.
pub fn utc_now() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs()) as i64;
    let (days, rem) = (secs.div_euclid(86400), secs.rem_euclid(86400));
    // Howard Hinnant's civil_from_days.
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + (m <= 2) as i64;
    format!(
        "{y:04}-{m:02}-{d:02} {:02}:{:02} UTC",
        rem / 3600,
        rem % 3600 / 60
    )
}

/// The machine table that heads a report: the CPU, the Vulkan device and
/// its driver, the commit, the date and the load average when it is written
/// (other processes share the cores). A Markdown table, ending in a newline.
pub fn report_table(device: &penumbra::vulkan::DeviceInfo) -> String {
    let root = crate::repo_root();
    let load = std::fs::read_to_string("/proc/loadavg")
        .unwrap_or_default()
        .split_whitespace()
        .take(3)
        .collect::<Vec<_>>()
        .join(", ");
    format!(
        "| | |\n|---|---|\n| CPU | {} |\n| Device | {} |\n| Driver | {} — {} |\n| Commit | {} |\n| Date | {} |\n| Load average at the end (1, 5, 15 min; other processes share the cores) | {load} |\n",
        CpuInfo::read().describe(),
        device.name,
        device.driver_name,
        device.driver_info,
        git_commit(&root),
        utc_now(),
    )
}

/// `git rev-parse --short HEAD`, marked when the tree has changes.
pub fn git_commit(root: &Path) -> String {
    let git = |args: &[&str]| {
        Command::new("git")
            .args(args)
            .current_dir(root)
            .output()
            .ok()
            .filter(|o| o.status.success())
            .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
    };
    match git(&["rev-parse", "--short", "HEAD"]) {
        Some(c) => {
            let dirty = git(&["status", "--porcelain", "--untracked-files=no"])
                .is_some_and(|s| !s.is_empty());
            if dirty {
                format!("{c} (with uncommitted changes)")
            } else {
                c
            }
        }
        None => "unknown (not a git checkout)".into(),
    }
}

#[cfg(test)]
mod tests {
    use super::CpuInfo;

    #[test]
    fn a_gallium_cap_below_avx512_turns_it_off_and_the_header_says_so() {
        let mut c = CpuInfo {
            vendor: "AuthenticAMD".into(),
            family: 25,
            model: 17,
            model_name: "AMD EPYC".into(),
            isa: vec!["avx2".into(), "avx512f".into()],
            gallium_caps: None,
        };
        assert!(c.avx512() && c.avx512_in_use());
        assert!(c.describe().ends_with("; with AVX-512"), "{}", c.describe());
        c.gallium_caps = Some("avx".into());
        assert!(c.avx512() && !c.avx512_in_use());
        assert!(
            c.describe()
                .ends_with("which lavapipe does not use here (`GALLIUM_OVERRIDE_CPU_CAPS=avx`)"),
            "{}",
            c.describe()
        );
        c.isa.pop();
        c.gallium_caps = None;
        assert!(!c.avx512_in_use());
        assert!(c.describe().ends_with("; no AVX-512"));
    }
}
