//! How a render is split: tiles are bands of whole rows, passes are ranges
//! of pass indices. Both are parsed from the command line here, so that a
//! bad value is one error naming the flag.

use std::ops::Range;

/// Rows per workgroup of the kernel: band boundaries fall on multiples of it,
/// so that no workgroup straddles two tiles.
pub const ROW_ALIGN: u32 = 8;

/// Tile `index` of `count` (`--tile I/N`, `0 <= I < N`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Tile {
    /// Which tile, from 0 (the top band).
    pub index: u32,
    /// How many tiles the image is split into.
    pub count: u32,
}

impl std::str::FromStr for Tile {
    type Err = String;
    fn from_str(s: &str) -> Result<Tile, String> {
        let bad = || format!("expected I/N with 0 <= I < N (e.g. 0/4), got `{s}`");
        let (i, n) = s.split_once('/').ok_or_else(bad)?;
        let index: u32 = i.trim().parse().map_err(|_| bad())?;
        let count: u32 = n.trim().parse().map_err(|_| bad())?;
        if count == 0 || index >= count {
            return Err(bad());
        }
        Ok(Tile { index, count })
    }
}

impl std::fmt::Display for Tile {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl Tile {
    /// The whole image as one tile.
    pub const WHOLE: Tile = Tile { index: 0, count: 1 };

    /// Most tiles an image `height` rows high splits into: every band has
    /// at least [`ROW_ALIGN`] rows (the last may have fewer).
    pub fn max_count(height: u32) -> u32 {
        height.div_ceil(ROW_ALIGN)
    }

    /// The rows of this tile in an image `height` rows high: band `i` starts
    /// at row `8 * floor(i * ceil(height / 8) / N)`, so bands differ by at
    /// most 8 rows and cover the image exactly once. An error when the image
    /// has fewer than N bands of 8 rows.
    pub fn rows(&self, height: u32) -> Result<Range<u32>, String> {
        let groups = Self::max_count(height) as u64;
        if self.count as u64 > groups {
            return Err(format!(
                "{} tiles of an image {height} rows high: at most {groups} (bands of at least {ROW_ALIGN} rows)",
                self.count
            ));
        }
        let start = |i: u64| ((i * groups / self.count as u64) as u32 * ROW_ALIGN).min(height);
        Ok(start(self.index as u64)..start(self.index as u64 + 1))
    }
}

/// Passes `start..end` of a progressive render (`--passes A..B`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Passes {
    /// First pass index.
    pub start: u32,
    /// One past the last pass index.
    pub end: u32,
}

impl std::str::FromStr for Passes {
    type Err = String;
    fn from_str(s: &str) -> Result<Passes, String> {
        let bad = || format!("expected A..B with A < B (e.g. 0..16), got `{s}`");
        let (a, b) = s.split_once("..").ok_or_else(bad)?;
        let start: u32 = a.trim().parse().map_err(|_| bad())?;
        let end: u32 = b.trim().parse().map_err(|_| bad())?;
        if start >= end {
            return Err(bad());
        }
        Ok(Passes { start, end })
    }
}

impl std::fmt::Display for Passes {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}..{}", self.start, self.end)
    }
}

impl Passes {
    /// Split `i` of `m` of `spp` passes: the ranges differ by at most one
    /// pass and cover `0..spp` exactly once (`farm slurm --sample-splits`).
    pub fn split(i: u32, m: u32, spp: u32) -> Passes {
        let at = |k: u32| (k as u64 * spp as u64 / m as u64) as u32;
        Passes {
            start: at(i),
            end: at(i + 1),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiles_cover_every_row_once() {
        for height in [1, 7, 8, 9, 63, 64, 65, 540, 1000] {
            for count in 1..=Tile::max_count(height).min(40) {
                let mut next = 0;
                for index in 0..count {
                    let r = Tile { index, count }.rows(height).unwrap();
                    assert_eq!(r.start, next, "h={height} n={count} i={index}");
                    assert!(r.end > r.start, "empty tile h={height} n={count} i={index}");
                    if r.end < height {
                        assert_eq!(r.start % ROW_ALIGN, 0);
                    }
                    next = r.end;
                }
                assert_eq!(next, height);
            }
            let too_many = Tile {
                index: 0,
                count: Tile::max_count(height) + 1,
            };
            assert!(too_many.rows(height).is_err());
        }
    }

    #[test]
    fn parses_and_rejects() {
        assert_eq!("2/6".parse::<Tile>(), Ok(Tile { index: 2, count: 6 }));
        for bad in ["6/6", "1/0", "x/2", "3", "-1/2", ""] {
            assert!(bad.parse::<Tile>().is_err(), "{bad}");
        }
        assert_eq!("4..8".parse::<Passes>(), Ok(Passes { start: 4, end: 8 }));
        for bad in ["8..8", "9..8", "4", "a..b", "..3"] {
            assert!(bad.parse::<Passes>().is_err(), "{bad}");
        }
    }

    #[test]
    fn pass_splits_cover_every_pass_once() {
        for spp in [1, 2, 7, 64, 100] {
            for m in 1..=spp.min(9) {
                let mut next = 0;
                for i in 0..m {
                    let p = Passes::split(i, m, spp);
                    assert_eq!(p.start, next);
                    assert!(p.end > p.start);
                    next = p.end;
                }
                assert_eq!(next, spp);
            }
        }
    }
}
