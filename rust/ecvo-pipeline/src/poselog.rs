//! The kept poses: every tracked frame's pose and every reference frame's pose, or
//! only the latest ones when a window bounds them
//! ([`PipelineOptions::trajectory_window`](crate::PipelineOptions::trajectory_window)),
//! so that a session of any length holds a constant amount of memory.

use std::collections::VecDeque;

use crate::PoseRecord;

/// The kept trajectory and reference list. Records arrive in tracking order with
/// consecutive `index`es (every tracked frame has one), so the first kept record's
/// index says where the window starts.
pub(crate) struct PoseLog {
    window: Option<usize>,
    poses: VecDeque<PoseRecord>,
    references: VecDeque<PoseRecord>,
    /// Index of the first kept pose (the number of poses discarded before it).
    start: u64,
}

impl PoseLog {
    /// Keeps everything (`None`) or the latest `window` poses, and the references
    /// among them. `window` is at least 1.
    pub(crate) fn new(window: Option<usize>) -> PoseLog {
        PoseLog {
            window,
            poses: VecDeque::new(),
            references: VecDeque::new(),
            start: 0,
        }
    }

    /// Appends a tracked frame's pose (and, if it is one, its reference record),
    /// discarding the oldest beyond the window. Once the window is full, the deques
    /// keep their capacity: no allocation per frame.
    pub(crate) fn push(&mut self, record: PoseRecord, is_reference: bool) {
        if let Some(w) = self.window
            && self.poses.len() >= w
        {
            self.poses.pop_front();
            self.start += 1;
            while self
                .references
                .front()
                .is_some_and(|r| r.index < self.start)
            {
                self.references.pop_front();
            }
        }
        if self.poses.is_empty() {
            self.start = record.index;
        }
        self.poses.push_back(record);
        if is_reference {
            self.references.push_back(record);
        }
    }

    /// Index of the first pose kept: 0 until the window first overflows.
    pub(crate) fn start(&self) -> u64 {
        self.start
    }

    /// The kept poses with `index >= from` (from the window's start if `from` is
    /// before it; check the records' `index`).
    pub(crate) fn poses_since(&self, from: u64) -> Vec<PoseRecord> {
        let mut out = Vec::new();
        self.chunk(from, usize::MAX, &mut out);
        out
    }

    /// Clears `out` and copies into it at most `max` kept poses with `index >= from`;
    /// returns the index of the first kept pose and the index after the last.
    pub(crate) fn chunk(&self, from: u64, max: usize, out: &mut Vec<PoseRecord>) -> (u64, u64) {
        out.clear();
        let end = self.start + self.poses.len() as u64;
        let skip = usize::try_from(from.saturating_sub(self.start)).unwrap_or(usize::MAX);
        if skip < self.poses.len() {
            let stop = skip.saturating_add(max).min(self.poses.len());
            out.extend(self.poses.range(skip..stop).copied());
        }
        (self.start, end)
    }

    /// The kept reference records, in order.
    pub(crate) fn references(&self) -> Vec<PoseRecord> {
        self.references.iter().copied().collect()
    }

    /// Moves the kept records out (at the end of a run).
    pub(crate) fn take(&mut self) -> (Vec<PoseRecord>, Vec<PoseRecord>) {
        (
            std::mem::take(&mut self.poses).into(),
            std::mem::take(&mut self.references).into(),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ecvo_core::{Pose, TrackingState};

    fn record(index: u64) -> PoseRecord {
        PoseRecord {
            sequence: index + 100,
            index,
            timestamp: index as f64,
            pose: Pose::identity(),
            state: TrackingState::Tracking,
            reference_levels: u8::from(index.is_multiple_of(3)),
        }
    }

    fn indices(r: &[PoseRecord]) -> Vec<u64> {
        r.iter().map(|r| r.index).collect()
    }

    #[test]
    fn an_unbounded_log_keeps_everything() {
        let mut log = PoseLog::new(None);
        for i in 0..50 {
            log.push(record(i), i % 3 == 0);
        }
        assert_eq!(log.start(), 0);
        assert_eq!(indices(&log.poses_since(0)), (0..50).collect::<Vec<_>>());
        assert_eq!(indices(&log.poses_since(47)), vec![47, 48, 49]);
        assert!(log.poses_since(50).is_empty());
        assert!(log.poses_since(u64::MAX).is_empty());
        assert_eq!(log.references().len(), 17);
    }

    #[test]
    fn a_window_keeps_the_latest_poses_and_their_references() {
        let mut log = PoseLog::new(Some(8));
        for i in 0..30 {
            log.push(record(i), i % 3 == 0);
            let kept = log.poses_since(0);
            assert_eq!(kept.len(), (i as usize + 1).min(8), "after {i}");
            assert_eq!(kept.last().map(|r| r.index), Some(i));
            assert_eq!(log.start(), kept[0].index);
            // The references kept are exactly those among the kept poses.
            let refs = indices(&log.references());
            let want: Vec<u64> = indices(&kept).into_iter().filter(|i| i % 3 == 0).collect();
            assert_eq!(refs, want, "after {i}");
        }
        assert_eq!(log.start(), 22);
        // Asking from before the window gives the window; from inside it, the tail.
        assert_eq!(indices(&log.poses_since(3)), (22..30).collect::<Vec<_>>());
        assert_eq!(indices(&log.poses_since(27)), vec![27, 28, 29]);
        assert!(log.poses_since(30).is_empty());
        // Chunks: the same records, a few at a time, and the window's bounds.
        let mut out = Vec::new();
        assert_eq!(log.chunk(0, 3, &mut out), (22, 30));
        assert_eq!(indices(&out), vec![22, 23, 24]);
        assert_eq!(log.chunk(28, 3, &mut out), (22, 30));
        assert_eq!(indices(&out), vec![28, 29]);
        assert_eq!(log.chunk(30, 3, &mut out), (22, 30));
        assert!(out.is_empty());
    }

    #[test]
    fn a_full_window_does_not_grow() {
        let mut log = PoseLog::new(Some(64));
        for i in 0..64 {
            log.push(record(i), true);
        }
        let (p, r) = (log.poses.capacity(), log.references.capacity());
        for i in 64..10_000 {
            log.push(record(i), true);
        }
        assert_eq!((log.poses.capacity(), log.references.capacity()), (p, r));
        let (poses, refs) = log.take();
        assert_eq!(indices(&poses), (9_936..10_000).collect::<Vec<_>>());
        assert_eq!(refs.len(), 64);
    }
}
