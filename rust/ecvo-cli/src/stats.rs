//! Small statistics helpers.

use serde::Serialize;

/// Median and mean of a set of values.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct MedianMean {
    /// Median (mean of the two middle values for an even count; 0 when empty).
    pub median: f64,
    /// Arithmetic mean (0 when empty).
    pub mean: f64,
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
                mean: 2.0
            }
        );
        assert_eq!(MedianMean::of([4.0, 1.0, 2.0, 3.0]).median, 2.5);
        assert_eq!(MedianMean::of([]), MedianMean::default());
    }
}
