//! `penumbra farm slurm`: an sbatch script for a split render or a batch,
//! and, with `--submit`/`--resume`, its submission, the wait and a report.
//! Slurm does all the scheduling; penumbra only writes the job and checks
//! the parts.
//!
//! The script (`OUT.farm/job.sh`) is plain bash with `set -euo pipefail`
//! that a user can read, edit and run by hand: `bash OUT.farm/job.sh submit
//! [TASKS]` submits a job array with one task per part, each writing its
//! part atomically into `OUT.farm/parts/`, and a merge job that depends on
//! the array with `afterok` and `--kill-on-invalid-dep=yes`, so it runs
//! only when every task succeeded and is cancelled otherwise. The jobs run
//! the same script (`job.sh task`, `job.sh merge`). It holds the paths the
//! user gave and no other path of this machine; the binary is `$PENUMBRA`
//! or `penumbra` on the nodes' PATH.

use std::path::{Path, PathBuf};
use std::process::Command;

use super::split::{Passes, Tile};

/// What the job array renders.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Work {
    /// One scene in `tiles` row bands × `splits` pass ranges, then a merge.
    Split {
        /// The scene file, as the user gave it.
        scene: String,
        /// Row bands.
        tiles: u32,
        /// Pass ranges per band.
        splits: u32,
    },
    /// The scenes of a list file shared among `tasks` tasks (no merge).
    Batch {
        /// The list file, as the user gave it.
        list: String,
        /// Array tasks.
        tasks: u32,
    },
}

/// A farm job: what to render, where, and with which options.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Job {
    /// Tiles and sample splits of one scene, or a batch.
    pub work: Work,
    /// The merged image (split) or the output folder (batch), as given.
    pub out: String,
    /// Passes of the render.
    pub spp: u32,
    /// Seed of the sample pattern.
    pub seed: u32,
    /// `--width`, when given.
    pub width: Option<u32>,
    /// `--height`, when given.
    pub height: Option<u32>,
    /// `--partition`, when given.
    pub partition: Option<String>,
    /// `--time`, when given (Slurm's time format).
    pub time: Option<String>,
    /// More flags for every render, one argument each (`--environment=2`):
    /// what changes the image beyond size, passes and seed.
    pub render_flags: Vec<String>,
    /// Flags for the merge (`--tonemap=pbr-neutral`), one argument each.
    pub merge_flags: Vec<String>,
}

/// Quotes a string for bash (single quotes).
fn quote(s: &str) -> String {
    format!("'{}'", s.replace('\'', r"'\''"))
}

impl Job {
    /// The work folder next to the output: `OUT.farm`.
    pub fn work_dir(&self) -> PathBuf {
        PathBuf::from(format!("{}.farm", self.out.trim_end_matches('/')))
    }

    /// The script's path, `OUT.farm/job.sh`.
    pub fn script_path(&self) -> PathBuf {
        self.work_dir().join("job.sh")
    }

    /// Number of array tasks.
    pub fn tasks(&self) -> u32 {
        match &self.work {
            Work::Split { tiles, splits, .. } => tiles * splits,
            Work::Batch { tasks, .. } => *tasks,
        }
    }

    /// The part file task `i` writes (split jobs).
    pub fn part_path(&self, i: u32) -> PathBuf {
        self.work_dir().join("parts").join(format!("part-{i}.exr"))
    }

    /// The tile and passes task `i` renders, as the script computes them.
    pub fn task_part(&self, i: u32) -> Option<(Tile, Passes)> {
        match &self.work {
            Work::Split { tiles, splits, .. } => Some((
                Tile {
                    index: i / splits,
                    count: *tiles,
                },
                Passes::split(i % splits, *splits, self.spp),
            )),
            Work::Batch { .. } => None,
        }
    }

    /// The sbatch script.
    pub fn script(&self) -> String {
        let mut render_args = vec![
            format!("--spp {}", self.spp),
            format!("--seed {}", self.seed),
        ];
        if let Some(w) = self.width {
            render_args.push(format!("--width {w}"));
        }
        if let Some(h) = self.height {
            render_args.push(format!("--height {h}"));
        }
        render_args.extend(self.render_flags.iter().map(|f| quote(f)));
        let merge_args: Vec<String> = self.merge_flags.iter().map(|f| quote(f)).collect();
        let mut sbatch_args = Vec::new();
        if let Some(p) = &self.partition {
            sbatch_args.push(quote(&format!("--partition={p}")));
        }
        if let Some(t) = &self.time {
            sbatch_args.push(quote(&format!("--time={t}")));
        }
        let work = self.work_dir().display().to_string();
        let tasks = self.tasks();
        let (what, vars, task_body, merge_body, submit_merge) = match &self.work {
            Work::Split { scene, tiles, splits } => (
                format!(
                    "{scene} -> {}: {tiles} tiles x {splits} sample splits = {tasks} tasks, then a merge",
                    self.out
                ),
                format!("scene={}\ntiles={tiles}\nsplits={splits}\n", quote(scene)),
                r#"  # Task i renders tile i / splits of $tiles and pass split i % splits.
  local tile=$((i / splits)) split=$((i % splits))
  local a=$((split * spp / splits)) b=$(((split + 1) * spp / splits))
  "$penumbra" render "$scene" "${render_args[@]}" --tile "$tile/$tiles" --passes "$a..$b" -o "$(part "$i")""#
                    .to_string(),
                r#"merge() {
  local parts=() i start rc=0
  start=$(date +%s.%N)
  for ((i = 0; i < tasks; i++)); do parts+=("$(part "$i")"); done
  "$penumbra" merge "${parts[@]}" "${merge_args[@]}" -o "$out" || rc=$?
  echo "$start $(date +%s.%N) $rc" > "$work/logs/merge.time"
  return "$rc"
}
"#
                .to_string(),
                r#"  local dep=()
  if [[ -n $array ]]; then dep=(--dependency="afterok:$array" --kill-on-invalid-dep=yes); fi
  merge=$(sbatch --parsable "${sbatch_args[@]}" --job-name=penumbra-merge "${dep[@]}" \
    --output="$work/logs/merge.log" "$0" merge)
  echo "array=$array merge=${merge%%;*}""#
                    .to_string(),
            ),
            Work::Batch { list, tasks } => (
                format!("batch {list} -> {}/: {tasks} tasks", self.out),
                format!("list={}\n", quote(list)),
                r#"  # Task i renders every $tasks-th scene of the list from the i-th.
  mkdir -p "$out"
  "$penumbra" render --batch "$list" -o "$out" --batch-task "$i/$tasks" "${render_args[@]}""#
                    .to_string(),
                String::new(),
                r#"  echo "array=$array""#.to_string(),
            ),
        };
        let merge_case = if merge_body.is_empty() {
            ""
        } else {
            "  merge) merge ;;\n"
        };
        format!(
            r#"#!/bin/bash
# Generated by `penumbra farm slurm`: {what}.
#
#   bash {work}/job.sh submit [TASKS]   submit the array (all tasks, or a list
#                                       such as 2,5) and the merge job
#   penumbra farm slurm ... --submit    the same, then wait and report times
#   penumbra farm slurm ... --resume    resubmit only missing or invalid parts
#
# Every task writes its output atomically (a temporary file renamed into
# place) under {work}/; logs go to {work}/logs/. The merge job runs only when
# every task succeeded (afterok) and is cancelled when one failed
# (--kill-on-invalid-dep=yes). Paths are relative to the folder sbatch is run
# from, where the jobs start; that folder must be on a file system every node
# sees. PENUMBRA names the binary when `penumbra` is not on the nodes' PATH.
set -euo pipefail

penumbra=${{PENUMBRA:-penumbra}}
out={out}
work={work_q}
{vars}tasks={tasks}
spp={spp}
render_args=({render_args})
merge_args=({merge_args})
sbatch_args=({sbatch_args})

part() {{ echo "$work/parts/part-$1.exr"; }}

task() {{
  local i=$SLURM_ARRAY_TASK_ID start rc=0
  start=$(date +%s.%N)
  run_task "$i" || rc=$?
  echo "$start $(date +%s.%N) $rc" > "$work/logs/task-$i.time"
  return "$rc"
}}

run_task() {{
  local i=$1
{task_body}
}}

{merge_body}
# TASKS: array indices (default all); `none` submits the merge alone.
submit() {{
  local which=${{1:-0-$((tasks - 1))}} array= merge
  mkdir -p "$work/parts" "$work/logs"
  if [[ $which != none ]]; then
    array=$(sbatch --parsable "${{sbatch_args[@]}}" --job-name=penumbra-parts \
      --array="$which" --output="$work/logs/task-%a.log" "$0" task)
    array=${{array%%;*}}
  fi
{submit_merge}
}}

case ${{1:-}} in
  task) task ;;
{merge_case}  submit) submit "${{2:-}}" ;;
  *) echo "usage: bash $0 submit [TASKS]" >&2; exit 2 ;;
esac
"#,
            out = quote(&self.out),
            work_q = quote(&work),
            spp = self.spp,
            render_args = render_args.join(" "),
            merge_args = merge_args.join(" "),
            sbatch_args = sbatch_args.join(" "),
        )
    }

    /// Writes the script into the work folder (creating it and its `parts`
    /// and `logs` folders) and returns its path.
    pub fn write_script(&self) -> anyhow::Result<PathBuf> {
        let work = self.work_dir();
        for d in [work.join("parts"), work.join("logs")] {
            std::fs::create_dir_all(&d)
                .map_err(|e| anyhow::anyhow!("{}: cannot create: {e}", d.display()))?;
        }
        let path = self.script_path();
        crate::output::persist_with(&path, |f| {
            use std::io::Write;
            f.write_all(self.script().as_bytes())?;
            Ok(())
        })?;
        Ok(path)
    }
}

/// Job ids of one submission.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Submitted {
    /// The array job (none when only the merge was submitted).
    pub array: Option<String>,
    /// The merge job (split jobs).
    pub merge: Option<String>,
}

/// Runs `bash job.sh submit TASKS` (with `PENUMBRA` set to this binary
/// unless the environment names one) and reads the job ids it prints.
pub fn submit(job: &Job, tasks: &[u32]) -> anyhow::Result<Submitted> {
    let spec: Vec<String> = tasks.iter().map(u32::to_string).collect();
    let mut cmd = Command::new("bash");
    let spec = if spec.is_empty() {
        "none".to_string()
    } else {
        spec.join(",")
    };
    cmd.arg(job.script_path()).arg("submit").arg(spec);
    if std::env::var_os("PENUMBRA").is_none() {
        if let Ok(exe) = std::env::current_exe() {
            cmd.env("PENUMBRA", exe);
        }
    }
    let out = cmd
        .output()
        .map_err(|e| anyhow::anyhow!("bash {}: cannot run: {e}", job.script_path().display()))?;
    let stdout = String::from_utf8_lossy(&out.stdout);
    if !out.status.success() {
        anyhow::bail!(
            "{}: submit failed: {}",
            job.script_path().display(),
            String::from_utf8_lossy(&out.stderr)
                .trim()
                .replace('\n', "; ")
        );
    }
    let field = |k: &str| {
        stdout
            .split_whitespace()
            .find_map(|w| w.strip_prefix(k).map(str::to_string))
            .filter(|id| !id.is_empty())
    };
    let s = Submitted {
        array: field("array="),
        merge: field("merge="),
    };
    if s.array.is_none() && s.merge.is_none() {
        anyhow::bail!(
            "{}: submit printed no job id: {stdout}",
            job.script_path().display()
        );
    }
    Ok(s)
}

/// Blocks until the last job of a submission has ended, whatever its end:
/// `srun --dependency=afterany:JOB true`, a one-second job that Slurm starts
/// when JOB is over (not `sbatch --wait`, which polls every 32 s).
pub fn wait(job: &Job, s: &Submitted) -> anyhow::Result<()> {
    let Some(last) = s.merge.as_ref().or(s.array.as_ref()) else {
        return Ok(());
    };
    let mut cmd = Command::new("srun");
    cmd.arg(format!("--dependency=afterany:{last}"))
        .arg("--job-name=penumbra-wait")
        .arg("--quiet");
    if let Some(p) = &job.partition {
        cmd.arg(format!("--partition={p}"));
    }
    cmd.arg("true");
    let st = cmd
        .status()
        .map_err(|e| anyhow::anyhow!("srun: cannot run: {e}"))?;
    anyhow::ensure!(st.success(), "srun --dependency=afterany:{last} true: {st}");
    Ok(())
}

/// A job's state from `scontrol show job -o` (`COMPLETED`, `CANCELLED`, …).
pub fn job_state(id: &str) -> String {
    Command::new("scontrol")
        .args(["show", "job", "-o", id])
        .output()
        .ok()
        .and_then(|o| {
            String::from_utf8_lossy(&o.stdout)
                .split_whitespace()
                .find_map(|w| w.strip_prefix("JobState=").map(str::to_string))
        })
        .unwrap_or_else(|| "UNKNOWN".into())
}

/// Start, end (seconds since the epoch) and exit code a task or the merge
/// recorded in `logs/NAME.time`.
pub fn recorded_time(job: &Job, name: &str) -> Option<(f64, f64, i32)> {
    let text =
        std::fs::read_to_string(job.work_dir().join("logs").join(format!("{name}.time"))).ok()?;
    let mut w = text.split_whitespace();
    Some((
        w.next()?.parse().ok()?,
        w.next()?.parse().ok()?,
        w.next()?.parse().ok()?,
    ))
}

/// The split tasks whose part is missing or invalid: unreadable, not of the
/// render `render_id`, not the part the task should have written, or with
/// pixels that do not read back.
pub fn invalid_parts(job: &Job, render_id: &str) -> Vec<u32> {
    (0..job.tasks())
        .filter(|&i| {
            let path = job.part_path(i);
            let Some((tile, passes)) = job.task_part(i) else {
                return true;
            };
            match super::part::read_info(&path) {
                Ok(info) => {
                    info.render != render_id
                        || info.tile != tile
                        || info.passes != passes
                        || super::part::read_pixels(&path, &info).is_err()
                }
                Err(_) => true,
            }
        })
        .collect()
}

/// The merged image is there and complete.
pub fn output_complete(job: &Job) -> bool {
    super::batch::is_complete(Path::new(&job.out))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn job(work: Work) -> Job {
        Job {
            work,
            out: "renders/it's here.png".into(),
            spp: 64,
            seed: 3,
            width: Some(640),
            height: None,
            partition: Some("gpu".into()),
            time: Some("00:10:00".into()),
            render_flags: vec!["--environment=2".into()],
            merge_flags: vec!["--tonemap=pbr-neutral".into()],
        }
    }

    fn bash_n(script: &str) {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("job.sh");
        std::fs::write(&p, script).unwrap();
        let out = Command::new("bash").arg("-n").arg(&p).output().unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }

    #[test]
    fn scripts_parse_and_hold_only_the_given_paths() {
        let split = job(Work::Split {
            scene: "scenes/showcase.json".into(),
            tiles: 6,
            splits: 4,
        });
        let batch = job(Work::Batch {
            list: "assets/list.txt".into(),
            tasks: 8,
        });
        for j in [&split, &batch] {
            let s = j.script();
            bash_n(&s);
            assert!(s.starts_with("#!/bin/bash\n"));
            assert!(s.contains("set -euo pipefail"));
            assert!(s.contains("'--partition=gpu' '--time=00:10:00'"));
            assert!(s.contains(r"out='renders/it'\''s here.png'"), "{s}");
            // No path of this machine: the only absolute path is the shebang.
            let cwd = std::env::current_dir().unwrap();
            assert!(!s.contains(cwd.to_str().unwrap()));
            for (n, line) in s.lines().enumerate().skip(1) {
                for w in line.split(|c: char| c.is_whitespace() || "'\"=(".contains(c)) {
                    // (`/` alone is bash arithmetic.)
                    let abs = w.starts_with('/') && w.len() > 1;
                    assert!(!abs, "line {}: absolute path `{w}`", n + 1);
                }
            }
        }
        let s = split.script();
        assert!(
            s.contains("--dependency=\"afterok:$array\" --kill-on-invalid-dep=yes"),
            "{s}"
        );
        assert!(s.contains("tasks=24"));
        // Every render and the merge get the flags that change the image.
        assert!(s.contains("render_args=(--spp 64 --seed 3 --width 640 '--environment=2')"));
        assert!(s.contains("merge_args=('--tonemap=pbr-neutral')"));
        assert!(
            s.contains(r#"merge "${parts[@]}" "${merge_args[@]}" -o"#),
            "{s}"
        );
        assert!(!batch.script().contains("merge) merge"));
        assert_eq!(
            split.task_part(5),
            Some((Tile { index: 1, count: 6 }, Passes { start: 16, end: 32 }))
        );
        assert_eq!(
            split.part_path(5),
            Path::new("renders/it's here.png.farm/parts/part-5.exr")
        );
    }
}
