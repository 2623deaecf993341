//! The watch on frame-to-frame residual spreads: a registration whose intensity
//! *and* depth residuals both spread several times wider than those of the frames
//! just before it did not find a rigid motion that explains the two frames.
//!
//! One residual's spread alone jumps on real data (motion blur widens the
//! intensity residuals, a near surface the depth ones: on tracked frames of fr1/desk
//! up to 10.7x and 12.4x), but not both at once (at most 3.9x and 3.0x together over
//! the robustness suite). A frame that no rigid motion explains, such as a zoom of 30 % nobody
//! announced, widens both (15x and 9x). Kept for the last [`HISTORY`] believed
//! frame-to-frame registrations: constant memory, no allocation.

use crate::scale::Scale;

/// Registrations remembered.
pub const HISTORY: usize = 15;
/// The watch says nothing until it has seen this many.
pub const MIN_HISTORY: usize = 5;

/// The spreads `(√Σ_II, √Σ_ZZ)` of the last believed frame-to-frame registrations.
#[derive(Clone, Debug, Default)]
pub struct SpreadWatch {
    ring: [(f64, f64); HISTORY],
    len: usize,
    next: usize,
}

impl SpreadWatch {
    /// Forgets every registration (a new start).
    pub fn clear(&mut self) {
        self.len = 0;
        self.next = 0;
    }

    /// Remembers the spreads of a believed registration (ignored unless finite and
    /// positive).
    pub fn record(&mut self, s: &Scale) {
        let (i, z) = (s.ii.sqrt(), s.zz.sqrt());
        if !(i > 0.0 && z > 0.0 && i.is_finite() && z.is_finite()) {
            return;
        }
        self.ring[self.next] = (i, z);
        self.next = (self.next + 1) % HISTORY;
        self.len = (self.len + 1).min(HISTORY);
    }

    /// True when both spreads of `s` exceed `factor` times the median of the
    /// remembered ones (false while fewer than [`MIN_HISTORY`] are remembered).
    pub fn is_jump(&self, s: &Scale, factor: f64) -> bool {
        if self.len < MIN_HISTORY || !factor.is_finite() {
            return false;
        }
        let (mi, mz) = self.medians();
        s.ii.sqrt() > factor * mi && s.zz.sqrt() > factor * mz
    }

    /// True when either spread of `s` exceeds `factor` times the median of the
    /// remembered ones (false with nothing remembered): a registration against a
    /// keyframe that explains the frame worse than the recent ones did.
    pub fn is_wider(&self, s: &Scale, factor: f64) -> bool {
        if self.len == 0 || !factor.is_finite() {
            return false;
        }
        let (mi, mz) = self.medians();
        s.ii.sqrt() > factor * mi || s.zz.sqrt() > factor * mz
    }

    /// The medians of the remembered intensity and depth spreads.
    fn medians(&self) -> (f64, f64) {
        let mut i = [0.0f64; HISTORY];
        let mut z = [0.0f64; HISTORY];
        for (k, &(a, b)) in self.ring[..self.len].iter().enumerate() {
            i[k] = a;
            z[k] = b;
        }
        let median = |v: &mut [f64]| {
            v.sort_unstable_by(f64::total_cmp);
            let n = v.len();
            if n % 2 == 1 {
                v[n / 2]
            } else {
                0.5 * (v[n / 2 - 1] + v[n / 2])
            }
        };
        (median(&mut i[..self.len]), median(&mut z[..self.len]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn s(i: f64, z: f64) -> Scale {
        Scale {
            ii: i * i,
            iz: 0.0,
            zz: z * z,
        }
    }

    #[test]
    fn silent_until_enough_history() {
        let mut w = SpreadWatch::default();
        for _ in 0..MIN_HISTORY - 1 {
            w.record(&s(0.01, 0.002));
        }
        assert!(!w.is_jump(&s(1.0, 1.0), 5.0));
        w.record(&s(0.01, 0.002));
        assert!(w.is_jump(&s(1.0, 1.0), 5.0));
    }

    #[test]
    fn both_spreads_must_jump() {
        let mut w = SpreadWatch::default();
        for k in 0..HISTORY {
            w.record(&s(0.01 + 0.001 * k as f64, 0.002));
        }
        // Median intensity spread 0.017, depth 0.002.
        assert!(w.is_jump(&s(0.09, 0.011), 5.0));
        assert!(!w.is_jump(&s(0.09, 0.009), 5.0), "depth only 4.5x");
        assert!(!w.is_jump(&s(0.08, 0.05), 5.0), "intensity only 4.7x");
        assert!(!w.is_jump(&s(0.5, 0.5), f64::INFINITY), "switched off");
    }

    #[test]
    fn keeps_only_the_last_registrations() {
        let mut w = SpreadWatch::default();
        for _ in 0..HISTORY {
            w.record(&s(1.0, 1.0));
        }
        for _ in 0..HISTORY {
            w.record(&s(0.01, 0.01));
        }
        assert!(w.is_jump(&s(0.06, 0.06), 5.0));
        w.record(&s(f64::NAN, 1.0));
        w.record(&s(0.0, 1.0));
        assert!(w.is_jump(&s(0.06, 0.06), 5.0), "bad spreads are not kept");
        w.clear();
        assert!(!w.is_jump(&s(0.06, 0.06), 5.0));
    }
}
