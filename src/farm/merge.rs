//! `penumbra merge`: checks that a set of part files makes up exactly one
//! render, then streams them into one image, written atomically.
//!
//! The checks read only headers: every part has the same render identity,
//! image size, tile count and pass count; every tile is there, and its pass
//! ranges cover `0..spp` exactly once. Any problem is reported, naming the
//! parts concerned, before anything is written.
//!
//! Memory: tiles are merged one at a time, top to bottom, so the merge
//! holds one tile's pass sums and the part being added to them (2 × 12
//! bytes a pixel of one tile), plus one output row (PNG) or one block of 16
//! rows (OpenEXR) — not the whole image.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use super::part::{self, PartInfo};
use super::split::Passes;
use crate::output::Format;
use crate::tonemap::{self, Display};

/// A checked set of parts: for each tile, its parts in pass order.
#[derive(Debug)]
pub struct Plan {
    /// Full image width.
    pub width: u32,
    /// Full image height.
    pub height: u32,
    /// Passes of the render.
    pub spp: u32,
    /// Per tile (index 0..N), its parts ordered by pass range.
    pub tiles: Vec<Vec<(PathBuf, PartInfo)>>,
}

/// Most parts one problem names; the rest are counted.
pub const MAX_NAMED_PARTS: usize = 5;

/// Most problems the error lists; the rest are counted.
pub const MAX_PROBLEMS: usize = 10;

/// The first [`MAX_NAMED_PARTS`] of `paths` by name, then how many more:
/// a problem's line stays short however many parts share it.
fn names(paths: &[&PathBuf]) -> String {
    let mut listed = paths
        .iter()
        .take(MAX_NAMED_PARTS)
        .map(|p| p.display().to_string())
        .collect::<Vec<_>>()
        .join(", ");
    if paths.len() > MAX_NAMED_PARTS {
        listed += &format!(" and {} more", paths.len() - MAX_NAMED_PARTS);
    }
    listed
}

/// Fails with the first [`MAX_PROBLEMS`] of `problems` on one line, then
/// how many more there are; succeeds when there are none.
fn refuse(problems: &[String]) -> anyhow::Result<()> {
    if problems.is_empty() {
        return Ok(());
    }
    let mut line = problems[..problems.len().min(MAX_PROBLEMS)].join("; ");
    if problems.len() > MAX_PROBLEMS {
        line += &format!("; and {} more problems", problems.len() - MAX_PROBLEMS);
    }
    anyhow::bail!("{line}")
}

/// The paths given more than once, each named once with its count.
fn given_twice(paths: &[PathBuf]) -> Vec<String> {
    let mut counts: BTreeMap<&PathBuf, usize> = BTreeMap::new();
    for p in paths {
        *counts.entry(p).or_default() += 1;
    }
    counts
        .into_iter()
        .filter(|&(_, n)| n > 1)
        .map(|(p, n)| format!("{}: given {n} times; give each part once", p.display()))
        .collect()
}

/// Reads the parts' headers and checks that they make up one whole render.
/// The error is one line that lists every problem found, naming the parts
/// (or the missing tiles and passes).
pub fn plan(paths: &[PathBuf]) -> anyhow::Result<Plan> {
    anyhow::ensure!(!paths.is_empty(), "merge: no part files given");
    let mut problems = given_twice(paths);
    refuse(&problems)?;
    let mut infos = Vec::new();
    for p in paths {
        match part::read_info(p) {
            Ok(i) => infos.push((p.clone(), i)),
            Err(e) => problems.push(e.to_string()),
        }
    }
    refuse(&problems)?;
    // Everything is compared with the first part.
    let (first_path, first) = infos[0].clone();
    let mut others: BTreeMap<String, Vec<&PathBuf>> = BTreeMap::new();
    for (p, i) in &infos[1..] {
        let what = if i.render != first.render {
            format!(
                "from another render (scene `{}`, render {}) than {} (scene `{}`, render {})",
                i.scene,
                &i.render[..12],
                first_path.display(),
                first.scene,
                &first.render[..12]
            )
        } else if (i.width, i.height) != (first.width, first.height) {
            format!(
                "size {}x{} differs from {}'s {}x{}",
                i.width,
                i.height,
                first_path.display(),
                first.width,
                first.height
            )
        } else if i.tile.count != first.tile.count || i.spp != first.spp {
            format!(
                "split into {} tiles of {} passes, {} into {} tiles of {} passes",
                i.tile.count,
                i.spp,
                first_path.display(),
                first.tile.count,
                first.spp
            )
        } else {
            continue;
        };
        others.entry(what).or_default().push(p);
    }
    for (what, ps) in &others {
        problems.push(format!("{}: {what}", names(ps)));
    }
    refuse(&problems)?;
    let n = first.tile.count;
    let mut tiles: Vec<Vec<(PathBuf, PartInfo)>> = vec![Vec::new(); n as usize];
    for (p, i) in infos {
        tiles[i.tile.index as usize].push((p, i));
    }
    for (t, parts) in tiles.iter_mut().enumerate() {
        parts.sort_by_key(|(p, i)| (i.passes, p.clone()));
        if parts.is_empty() {
            problems.push(format!("tile {t}/{n}: missing"));
            continue;
        }
        // `next`: the first pass not yet covered, by `cover` (the part
        // that reaches furthest so far). Parts that repeat passes are
        // grouped by what they repeat, so each is named once.
        let mut next = 0;
        let mut cover = 0;
        let mut repeats: BTreeMap<(usize, Passes), Vec<&PathBuf>> = BTreeMap::new();
        for (k, (p, i)) in parts.iter().enumerate() {
            if i.passes.start > next {
                problems.push(format!(
                    "tile {t}/{n}: passes {next}..{} missing",
                    i.passes.start
                ));
            } else if i.passes.start < next {
                repeats.entry((cover, i.passes)).or_default().push(p);
            }
            if i.passes.end > next {
                (next, cover) = (i.passes.end, k);
            }
        }
        for ((cover, passes), ps) in &repeats {
            let verb = if ps.len() == 1 { "repeats" } else { "repeat" };
            problems.push(format!(
                "tile {t}/{n}: {} (passes {passes}) {verb} passes already in {}",
                names(ps),
                parts[*cover].0.display()
            ));
        }
        if next < first.spp {
            problems.push(format!(
                "tile {t}/{n}: passes {next}..{} missing",
                first.spp
            ));
        }
    }
    refuse(&problems)?;
    Ok(Plan {
        width: first.width,
        height: first.height,
        spp: first.spp,
        tiles,
    })
}

/// One tile's merged pixels, loaded on demand, one tile at a time.
struct TileCursor<'a> {
    plan: &'a Plan,
    /// (tile index, first row, mean colours of its rows).
    current: Option<(usize, u32, Vec<[f32; 3]>)>,
}

impl TileCursor<'_> {
    /// The mean of a tile: its parts' pass sums added in pass order, then
    /// multiplied by `1 / spp` as the undivided render does (which is why a
    /// tile over all passes is bit-identical to it).
    fn load(&self, t: usize) -> anyhow::Result<Vec<[f32; 3]>> {
        let mut acc: Option<Vec<[f32; 3]>> = None;
        for (p, info) in &self.plan.tiles[t] {
            let px = part::read_pixels(p, info)?;
            match &mut acc {
                None => acc = Some(px),
                Some(a) => {
                    for (s, v) in a.iter_mut().zip(&px) {
                        *s = [s[0] + v[0], s[1] + v[1], s[2] + v[2]];
                    }
                }
            }
        }
        let mut acc = acc.ok_or_else(|| anyhow::anyhow!("tile {t}: no parts"))?;
        if self.plan.spp > 1 {
            let inv = 1.0 / self.plan.spp as f32;
            for p in &mut acc {
                *p = p.map(|c| c * inv);
            }
        }
        Ok(acc)
    }

    /// Row `y` of the merged image.
    fn row(&mut self, y: u32) -> anyhow::Result<&[[f32; 3]]> {
        let t = self
            .plan
            .tiles
            .iter()
            .position(|parts| parts[0].1.rows.contains(&y))
            .ok_or_else(|| anyhow::anyhow!("row {y}: in no tile"))?;
        if self.current.as_ref().is_none_or(|c| c.0 != t) {
            let start = self.plan.tiles[t][0].1.rows.start;
            self.current = Some((t, start, self.load(t)?));
        }
        let (_, start, px) = self.current.as_ref().expect("loaded above");
        let w = self.plan.width as usize;
        let i = (y - start) as usize * w;
        Ok(&px[i..i + w])
    }
}

/// Merges a checked plan into `out` (.png: sRGB 8 bit with `display`'s
/// exposure and tone mapping; .exr: linear float RGB), streaming tile by tile, written atomically: on any error (a part
/// that turns out truncated) nothing is left at `out`.
pub fn write(plan: &Plan, out: &Path, display: Display) -> anyhow::Result<()> {
    let format = crate::output::check_writable(out)?;
    // A merge knows no scene: the tone mapping asked for, else none.
    let (scale, tonemap) = (display.exposure.exp2(), display.tonemap_for(false));
    let mut cursor = TileCursor {
        plan,
        current: None,
    };
    crate::output::persist_with(out, |file| match format {
        Format::Png => crate::output::encode_png_rows(file, plan.width, plan.height, |y, buf| {
            let row = cursor.row(y)?;
            for (o, p) in buf.chunks_exact_mut(3).zip(row) {
                o.copy_from_slice(&tonemap::map(*p, scale, tonemap).map(crate::output::srgb8));
            }
            Ok(())
        }),
        Format::Exr => write_exr(file, plan, cursor),
    })
}

/// The OpenEXR side of [`write`]: the exr crate asks for pixels through a
/// closure, in increasing line order; the closure cannot fail, so the first
/// error is kept and returned after the write (the file is then discarded).
fn write_exr(
    file: &mut std::io::BufWriter<&std::fs::File>,
    plan: &Plan,
    cursor: TileCursor<'_>,
) -> anyhow::Result<()> {
    use exr::prelude::*;
    let state = Mutex::new((cursor, None::<anyhow::Error>));
    let channels = SpecificChannels::rgb(|p: Vec2<usize>| {
        let mut guard = state.lock().unwrap_or_else(|e| e.into_inner());
        let (cursor, error) = &mut *guard;
        if error.is_some() {
            return (0f32, 0f32, 0f32);
        }
        match cursor.row(p.y() as u32) {
            Ok(row) => {
                let c = row[p.x()];
                (c[0], c[1], c[2])
            }
            Err(e) => {
                *error = Some(e);
                (0.0, 0.0, 0.0)
            }
        }
    });
    let layer = Layer::new(
        (plan.width as usize, plan.height as usize),
        LayerAttributes::named("penumbra"),
        Encoding::FAST_LOSSLESS,
        channels,
    );
    let result = exr::image::Image::from_layer(layer)
        .write()
        .non_parallel()
        .to_buffered(file)
        .map_err(|e| anyhow::anyhow!("cannot encode OpenEXR: {e}"));
    let (_, error) = state.into_inner().unwrap_or_else(|e| e.into_inner());
    match error {
        Some(e) => Err(e),
        None => result,
    }
}
