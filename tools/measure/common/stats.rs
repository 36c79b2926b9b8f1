//! Statistics of repeated measurements: median, minimum, maximum and
//! percentiles. The tools report a median with its range rather than a mean,
//! because on a shared machine the slow outliers come from other processes,
//! not from the code measured.

use serde::{Deserialize, Serialize};

/// Samples (times in milliseconds, or ratios) with their median, minimum and
/// maximum, as the benchmark's JSON stores them.
#[derive(Serialize, Deserialize, Clone, Debug, Default)]
pub struct Stat {
    pub median: f64,
    pub min: f64,
    pub max: f64,
    pub samples: Vec<f64>,
}

impl Stat {
    /// The statistics of `samples` (kept in their measured order); NaN
    /// median, minimum and maximum when there are none.
    pub fn of(samples: &[f64]) -> Stat {
        let s = sorted(samples);
        Stat {
            median: median_of_sorted(&s),
            min: s.first().copied().unwrap_or(f64::NAN),
            max: s.last().copied().unwrap_or(f64::NAN),
            samples: samples.to_vec(),
        }
    }
}

/// A sorted copy of `v` (NaNs last, by `f64::total_cmp`).
pub fn sorted(v: &[f64]) -> Vec<f64> {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    s
}

/// The median of sorted samples: the middle one, or the mean of the middle
/// two for an even count; NaN when there are none.
fn median_of_sorted(s: &[f64]) -> f64 {
    let n = s.len();
    if n == 0 {
        f64::NAN
    } else if n % 2 == 1 {
        s[n / 2]
    } else {
        (s[n / 2 - 1] + s[n / 2]) / 2.0
    }
}

/// The median of `v` (the mean of the middle two for an even count; NaN
/// when empty).
pub fn median(v: &[f64]) -> f64 {
    median_of_sorted(&sorted(v))
}

/// `(median, min, max)` of `v`; NaNs when empty.
pub fn median_min_max(v: &[f64]) -> (f64, f64, f64) {
    let s = Stat::of(v);
    (s.median, s.min, s.max)
}

/// The sample at index `len / 2` of the sorted samples: the median for an
/// odd count, the upper of the middle two for an even one. Works for any
/// ordered type (durations too); `None` when empty.
pub fn upper_median<T: Ord + Copy>(v: &[T]) -> Option<T> {
    let mut s = v.to_vec();
    s.sort();
    s.get(s.len() / 2).copied()
}

/// The `p`-th percentile (0 to 100) of `v` by the nearest-rank method: the
/// smallest sample with at least `p`% of the samples at or below it; NaN
/// when empty.
pub fn percentile(v: &[f64], p: f64) -> f64 {
    let s = sorted(v);
    if s.is_empty() {
        return f64::NAN;
    }
    let rank = (p / 100.0 * s.len() as f64).ceil() as usize;
    s[rank.clamp(1, s.len()) - 1]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_of_odd_and_even_counts() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&[4.0, 1.0, 3.0, 2.0]), 2.5);
        assert!(median(&[]).is_nan());
    }

    #[test]
    fn stat_keeps_the_samples_in_order() {
        let s = Stat::of(&[5.0, 1.0, 3.0]);
        assert_eq!((s.median, s.min, s.max), (3.0, 1.0, 5.0));
        assert_eq!(s.samples, vec![5.0, 1.0, 3.0]);
    }

    #[test]
    fn upper_median_and_percentiles() {
        assert_eq!(upper_median(&[4, 1, 3, 2]), Some(3));
        assert_eq!(upper_median::<u32>(&[]), None);
        let v: Vec<f64> = (1..=10).map(f64::from).collect();
        assert_eq!(percentile(&v, 50.0), 5.0);
        assert_eq!(percentile(&v, 90.0), 9.0);
        assert_eq!(percentile(&v, 100.0), 10.0);
        assert_eq!(percentile(&v, 0.0), 1.0);
    }
}
