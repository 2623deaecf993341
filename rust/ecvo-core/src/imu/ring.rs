//! [`GyroRing`]: a fixed ring of gyro samples, oldest first.

use super::GyroSample;

/// A fixed-capacity ring of samples in the order pushed, the oldest overwritten when
/// full. Its buffer is allocated at the first push, never again.
#[derive(Clone, Debug)]
pub struct GyroRing {
    buf: Vec<GyroSample>,
    capacity: usize,
    /// Index in `buf` of the oldest sample.
    head: usize,
    len: usize,
    /// Samples ever pushed: the global index of the next one.
    pushed: u64,
}

impl GyroRing {
    /// An empty ring of `capacity` samples (at least 2); allocates nothing yet.
    pub fn new(capacity: usize) -> Self {
        GyroRing {
            buf: Vec::new(),
            capacity: capacity.max(2),
            head: 0,
            len: 0,
            pushed: 0,
        }
    }

    /// Appends `s`, overwriting the oldest sample when full.
    pub fn push(&mut self, s: GyroSample) {
        if self.buf.capacity() == 0 {
            self.buf.reserve_exact(self.capacity);
        }
        if self.len < self.capacity {
            let i = (self.head + self.len) % self.capacity;
            if i == self.buf.len() {
                self.buf.push(s);
            } else {
                self.buf[i] = s;
            }
            self.len += 1;
        } else {
            self.buf[self.head] = s;
            self.head = (self.head + 1) % self.capacity;
        }
        self.pushed += 1;
    }

    /// Samples kept.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether no sample is kept.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Samples ever pushed (the global index of the next one).
    pub fn pushed(&self) -> u64 {
        self.pushed
    }

    /// The `i`-th oldest sample kept (`i < len`).
    pub fn get(&self, i: usize) -> &GyroSample {
        debug_assert!(i < self.len);
        &self.buf[(self.head + i) % self.capacity]
    }

    /// The newest sample.
    pub fn last(&self) -> Option<&GyroSample> {
        (self.len > 0).then(|| self.get(self.len - 1))
    }

    /// How many kept samples have `t <= x` (the samples are in time order).
    pub fn count_at_or_before(&self, x: f64) -> usize {
        let (mut lo, mut hi) = (0, self.len);
        while lo < hi {
            let mid = (lo + hi) / 2;
            if self.get(mid).t <= x {
                lo = mid + 1;
            } else {
                hi = mid;
            }
        }
        lo
    }

    /// The kept samples of global indices `from..to` (clamped to what was pushed), as
    /// two slices in order, and how many of them were already overwritten.
    pub fn range(&self, from: u64, to: u64) -> (u64, &[GyroSample], &[GyroSample]) {
        let to = to.min(self.pushed);
        let oldest = self.pushed - self.len as u64;
        let start = from.max(oldest);
        let lost = start.saturating_sub(from).min(to.saturating_sub(from));
        if start >= to {
            return (lost, &[], &[]);
        }
        let (a, n) = ((start - oldest) as usize, (to - start) as usize);
        let first = (self.head + a) % self.capacity;
        let end = first + n;
        if end <= self.capacity {
            (lost, &self.buf[first..end], &[])
        } else {
            (lost, &self.buf[first..], &self.buf[..end - self.capacity])
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn s(t: f64) -> GyroSample {
        GyroSample { t, w: [t; 3] }
    }

    #[test]
    fn ring_keeps_the_newest_in_order() {
        let mut r = GyroRing::new(4);
        assert!(r.is_empty() && r.last().is_none());
        for i in 0..10 {
            r.push(s(i as f64));
        }
        assert_eq!((r.len(), r.pushed()), (4, 10));
        let kept: Vec<f64> = (0..4).map(|i| r.get(i).t).collect();
        assert_eq!(kept, [6.0, 7.0, 8.0, 9.0]);
        assert_eq!(r.count_at_or_before(7.5), 2);
        assert_eq!(r.count_at_or_before(5.0), 0);
        assert_eq!(r.count_at_or_before(9.0), 4);
        // Global indices 4..9: 4 and 5 were overwritten, 6..9 come in two slices.
        let (lost, a, b) = r.range(4, 9);
        let got: Vec<f64> = a.iter().chain(b).map(|x| x.t).collect();
        assert_eq!((lost, got), (2, vec![6.0, 7.0, 8.0]));
        let (lost, a, b) = r.range(0, 3);
        assert_eq!((lost, a.len() + b.len()), (3, 0));
        let (lost, a, b) = r.range(8, 100);
        assert_eq!((lost, a.len() + b.len()), (0, 2));
        assert_eq!(r.buf.capacity(), 4, "allocated once, at its capacity");
    }
}
