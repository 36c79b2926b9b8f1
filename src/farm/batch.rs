//! Batches: many scenes rendered by one process with one device and one
//! kernel cache (`penumbra render --batch LIST -o DIR`).
//!
//! A list file names one scene a line, relative to the list file's folder,
//! optionally followed by the output's file name inside DIR (default: the
//! scene's file stem plus `.png`); blank lines and lines starting with `#`
//! are skipped. A rerun skips every output that is already there and
//! decodes (outputs are written atomically, so a file that exists is
//! normally whole; one that does not decode is rendered again), so a batch
//! that was stopped resumes where it was.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use crate::loaders::{self, LoadOptions};
use crate::render::{RenderRequest, Renderer, Sampling};

use super::split::Tile;

/// One scene of a batch.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Entry {
    /// Line number in the list file (1-based).
    pub line: usize,
    /// The scene file.
    pub scene: PathBuf,
    /// Where its image goes (inside the output folder).
    pub output: PathBuf,
}

/// Reads a list file. Every problem (an unreadable list, a bad output
/// name, two scenes with the same output) is an error naming the list file
/// and the line. Missing scene files are not: they fail when their turn
/// comes, as every other broken scene does, and the rest still render.
pub fn read_list(list: &Path, out_dir: &Path) -> anyhow::Result<Vec<Entry>> {
    let text = std::fs::read_to_string(list)
        .map_err(|e| anyhow::anyhow!("{}: cannot read the batch list: {e}", list.display()))?;
    let base = list.parent().unwrap_or(Path::new(""));
    let mut entries = Vec::new();
    let mut seen: HashMap<PathBuf, usize> = HashMap::new();
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let at = |msg: String| anyhow::anyhow!("{}:{line}: {msg}", list.display());
        let l = raw.trim();
        if l.is_empty() || l.starts_with('#') {
            continue;
        }
        let mut words = l.split_whitespace();
        let scene = words.next().unwrap_or_default();
        let name = match words.next() {
            Some(n) => n.to_string(),
            None => {
                let stem = Path::new(scene)
                    .file_stem()
                    .ok_or_else(|| at(format!("`{scene}`: no file name")))?;
                format!("{}.png", stem.to_string_lossy())
            }
        };
        if words.next().is_some() {
            return Err(at("expected `SCENE [OUTPUT]`, got more words".into()));
        }
        let out = Path::new(&name);
        if out.components().count() != 1 || out.file_name().is_none() {
            return Err(at(format!(
                "output `{name}`: must be a file name inside the output folder"
            )));
        }
        crate::output::Format::from_path(out).map_err(|_| {
            at(format!(
                "output `{name}`: expected a .png or .exr file name"
            ))
        })?;
        let output = out_dir.join(out);
        if let Some(first) = seen.insert(output.clone(), line) {
            return Err(at(format!("output `{name}` is already line {first}'s")));
        }
        entries.push(Entry {
            line,
            scene: base.join(scene),
            output,
        });
    }
    if entries.is_empty() {
        anyhow::bail!("{}: the batch list names no scene", list.display());
    }
    Ok(entries)
}

/// The entries of batch task `task` (`I/K`): every K-th entry from the I-th,
/// so that tasks get equal shares however the list is ordered.
pub fn task_share(entries: Vec<Entry>, task: Tile) -> Vec<Entry> {
    entries
        .into_iter()
        .enumerate()
        .filter(|(i, _)| *i as u32 % task.count == task.index)
        .map(|(_, e)| e)
        .collect()
}

/// Whether an output is already done: it exists and decodes as an image.
pub fn is_complete(output: &Path) -> bool {
    output.is_file()
        && image::ImageReader::open(output)
            .ok()
            .and_then(|r| r.with_guessed_format().ok())
            .is_some_and(|r| r.decode().is_ok())
}

/// What happened to one entry.
#[derive(Debug)]
pub enum Outcome {
    /// Rendered and written, in this time.
    Rendered(Duration),
    /// Skipped: the output was already complete.
    Skipped,
    /// Failed, with the message (it names the file and field).
    Failed(String),
}

/// How to render every scene of a batch.
#[derive(Clone, Debug)]
pub struct BatchSettings {
    /// Loader options (size overrides and limits).
    pub load: LoadOptions,
    /// Passes and seed.
    pub sampling: Sampling,
    /// `--area-samples`, when given.
    pub area_samples: Option<u32>,
    /// `--exposure` and `--tonemap` of PNG outputs.
    pub display: crate::tonemap::Display,
}

/// Renders one entry with `renderer` (whose kernel cache the whole batch
/// shares) and writes its output atomically.
pub fn render_entry(
    renderer: &mut Renderer,
    entry: &Entry,
    settings: &BatchSettings,
) -> anyhow::Result<()> {
    let mut load = settings.load.clone();
    load.max_triangles = renderer.max_triangles();
    load.max_texture_bytes = renderer.texture_capacity();
    let loaded = loaders::load_scene(&entry.scene, &load)?;
    let lit_by_default = loaded.lit_by_default;
    let mut scene = loaded.scene;
    if let Some(n) = settings.area_samples {
        for l in &mut scene.lights {
            l.kind.set_samples(n);
        }
    }
    let uploaded = renderer
        .upload(&scene)
        .map_err(|e| scene_error(&entry.scene, e))?;
    let (w, h) = uploaded.size();
    let frame = renderer
        .render(
            &uploaded,
            RenderRequest::progressive(w, h, &settings.sampling, &mut |_| {}),
        )
        .map(|r| r.frame)
        .map_err(|e| scene_error(&entry.scene, e))?;
    let format = crate::output::Format::from_path(&entry.output)?;
    let image = settings
        .display
        .for_format(&frame.image, format, lit_by_default);
    crate::output::write_image(&entry.output, &image)?;
    Ok(())
}

fn scene_error(scene: &Path, e: crate::render::RenderError) -> anyhow::Error {
    anyhow::anyhow!("{}: {e}", scene.display())
}

/// Renders every entry in order, skipping complete outputs; `report` hears
/// of each entry as it is done. A failed scene does not stop the others,
/// except one that hangs the device (a shader past the time limit): nothing
/// more can render on it, so the batch ends there (a rerun resumes after the
/// complete outputs).
pub fn run(
    renderer: &mut Renderer,
    entries: &[Entry],
    settings: &BatchSettings,
    report: &mut dyn FnMut(&Entry, &Outcome),
) -> Vec<(Entry, Outcome)> {
    let mut done = Vec::new();
    for e in entries {
        let outcome = if is_complete(&e.output) {
            Outcome::Skipped
        } else {
            let t0 = Instant::now();
            // A panic in one scene is a bug, but it must not lose the rest.
            let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                render_entry(renderer, e, settings)
            }));
            match r {
                Ok(Ok(())) => Outcome::Rendered(t0.elapsed()),
                Ok(Err(err)) => Outcome::Failed(format!("{err:#}")),
                Err(_) => Outcome::Failed(format!("{}: internal error", e.scene.display())),
            }
        };
        report(e, &outcome);
        done.push((e.clone(), outcome));
        if renderer.is_hung() {
            break;
        }
    }
    done
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn list_lines_and_errors() {
        let dir = tempfile::tempdir().unwrap();
        let list = dir.path().join("list.txt");
        std::fs::write(&list, "# frames\na.json\n\n sub/b.gltf  b_out.exr \n").unwrap();
        let e = read_list(&list, Path::new("out")).unwrap();
        assert_eq!(e.len(), 2);
        assert_eq!(e[0].scene, dir.path().join("a.json"));
        assert_eq!(e[0].output, Path::new("out/a.png"));
        assert_eq!(
            (e[1].line, e[1].output.as_path()),
            (4, Path::new("out/b_out.exr"))
        );
        for (text, needle) in [
            (
                "a.json\nb/a.json\n",
                ":2: output `a.png` is already line 1's",
            ),
            ("a.json x.tiff\n", ":1: output `x.tiff`"),
            ("a.json ../x.png\n", ":1: output `../x.png`"),
            ("a.json x.png y\n", ":1: expected"),
            ("# nothing\n", "names no scene"),
        ] {
            std::fs::write(&list, text).unwrap();
            let err = read_list(&list, Path::new("out")).unwrap_err().to_string();
            assert!(err.contains(needle), "{text:?}: {err}");
            assert!(err.contains("list.txt"), "{err}");
        }
        let shares: Vec<usize> = (0..3)
            .map(|i| task_share(vec![e[0].clone(); 7], Tile { index: i, count: 3 }).len())
            .collect();
        assert_eq!(shares, [3, 2, 2]);
    }
}
