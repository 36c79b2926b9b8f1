//! The driver matrix: the bunny and the showcase on every lavapipe at hand —
//! the installed one, and each tree that `tools/mesa_tree.sh` unpacked into
//! `target/mesa-*/` (`tools/setup.sh --tests` makes Debian's main-suite one,
//! Mesa 22.3 on Debian 12) — each driver in child processes pointed at it by
//! `VK_DRIVER_FILES` and `VK_ICD_FILENAMES`, the drivers interleaved round
//! by round so that a busy second core hits them alike.

use std::path::PathBuf;

use common::Stat;

use crate::child::child;
use crate::schema::{DriverRun, DriverScene, DriversPart, PartInfo, ThroughputPart};
use crate::Args;

/// The ICD files of the unpacked driver trees, in name order.
fn trees() -> Vec<PathBuf> {
    let root = common::repo_root();
    let mut found: Vec<PathBuf> = std::fs::read_dir(root.join("target"))
        .into_iter()
        .flatten()
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().starts_with("mesa-"))
        .map(|e| e.path().join("lvp_icd.json"))
        .filter(|p| p.is_file())
        .collect();
    found.sort();
    found
}

/// The part: `rounds` rounds, each running every driver's child once.
pub fn run(args: &Args, parts: &mut Vec<PartInfo>, rounds: usize) -> DriversPart {
    let root = common::repo_root();
    let icds: Vec<Option<PathBuf>> = std::iter::once(None)
        .chain(trees().into_iter().map(Some))
        .collect();
    let mut out = DriversPart {
        rounds,
        note: (icds.len() == 1).then(|| {
            "no second driver tree in target/ (`tools/setup.sh --tests` unpacks one): only the installed driver ran".into()
        }),
        ..Default::default()
    };
    // runs[driver][round]: None where that round's child failed, so that the
    // speed-ups below pair each driver's round with the installed one's.
    let mut runs: Vec<Vec<Option<ThroughputPart>>> = vec![Vec::new(); icds.len()];
    let mut errors: Vec<Option<String>> = vec![None; icds.len()];
    for _ in 0..rounds {
        for (i, icd) in icds.iter().enumerate() {
            let path = icd.as_ref().map(|p| p.display().to_string());
            let env: Vec<(&str, &str)> = match &path {
                Some(p) => vec![("VK_DRIVER_FILES", p), ("VK_ICD_FILENAMES", p)],
                None => Vec::new(),
            };
            match child::<ThroughputPart>(args, parts, "driver", &env) {
                Ok(p) => runs[i].push(Some(p)),
                Err(e) => {
                    errors[i] = Some(format!("{e:#}"));
                    runs[i].push(None);
                }
            }
        }
    }
    // The installed driver's median per scene and round, for the speed-ups.
    let median = |p: &ThroughputPart, s: usize| Stat::of(&p.scenes[s].render_ms.samples).median;
    for (i, icd) in icds.iter().enumerate() {
        let r = &runs[i];
        let mut run = DriverRun {
            icd: icd.as_ref().map_or("installed".into(), |p| {
                p.strip_prefix(&root).unwrap_or(p).display().to_string()
            }),
            error: errors[i].clone(),
            ..Default::default()
        };
        let ok: Vec<&ThroughputPart> = r.iter().flatten().collect();
        if let Some(first) = ok.first() {
            run.device = first.device.clone();
            for (s, t) in first.scenes.iter().enumerate() {
                let frames: Vec<f64> = ok
                    .iter()
                    .flat_map(|p| p.scenes[s].render_ms.samples.clone())
                    .collect();
                let speedups: Vec<f64> = runs[0]
                    .iter()
                    .zip(r)
                    .filter_map(|(base, p)| {
                        Some(median(base.as_ref()?, s) / median(p.as_ref()?, s))
                    })
                    .collect();
                run.scenes.push(DriverScene {
                    scene: t.scene.clone(),
                    width: t.width,
                    height: t.height,
                    rays: t.primary_rays + t.shadow_rays,
                    driver_compile_ms: ok.iter().map(|p| p.scenes[s].driver_compile_ms).collect(),
                    render_ms: Stat::of(&frames),
                    speed_vs_installed: Stat::of(&speedups),
                });
            }
        }
        out.drivers.push(run);
    }
    out
}
