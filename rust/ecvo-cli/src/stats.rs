//! Small statistics helpers.

use serde::Serialize;

/// Median, mean and 95th percentile of a set of values.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct MedianMean {
    /// Median (mean of the two middle values for an even count; 0 when empty).
    pub median: f64,
    /// Arithmetic mean (0 when empty).
    pub mean: f64,
    /// 95th percentile, nearest rank: the smallest value at least 95 % of the values
    /// do not exceed (0 when empty).
    pub p95: f64,
}

impl MedianMean {
    /// Median and mean of `values`.
    pub fn of(values: impl IntoIterator<Item = f64>) -> Self {
        let mut v: Vec<f64> = values.into_iter().filter(|x| x.is_finite()).collect();
        if v.is_empty() {
            return MedianMean::default();
        }
        v.sort_by(f64::total_cmp);
        let n = v.len();
        let median = if n % 2 == 1 {
            v[n / 2]
        } else {
            0.5 * (v[n / 2 - 1] + v[n / 2])
        };
        MedianMean {
            median,
            mean: v.iter().sum::<f64>() / n as f64,
            p95: v[(n * 95).div_ceil(100).max(1) - 1],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_and_mean() {
        assert_eq!(
            MedianMean::of([3.0, 1.0, 2.0]),
            MedianMean {
                median: 2.0,
                mean: 2.0,
                p95: 3.0,
            }
        );
        assert_eq!(MedianMean::of([4.0, 1.0, 2.0, 3.0]).median, 2.5);
        // Nearest rank: of 1..=100 the 95th value, of 1..=20 the 19th.
        assert_eq!(MedianMean::of((1..=100).map(f64::from)).p95, 95.0);
        assert_eq!(MedianMean::of((1..=20).map(f64::from)).p95, 19.0);
        assert_eq!(MedianMean::of([7.0]).p95, 7.0);
        assert_eq!(MedianMean::of([]), MedianMean::default());
    }
}
