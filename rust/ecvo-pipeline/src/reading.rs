//! What a running pipeline can be asked while it runs: the outputs channel, the
//! latest pose, the kept trajectory and references, the point cloud and the
//! statistics. Every read takes a short lock and copies; none stops a stage.

use crossbeam_channel::Receiver;

use crate::queue::lock;
use crate::*;

impl Pipeline {
    /// A receiver of every tracked frame's output, in order (`None` unless
    /// [`PipelineOptions::output_queue`] is set). It disconnects after the last
    /// frame once the input is closed.
    pub fn outputs(&self) -> Option<Receiver<TrackedFrame>> {
        self.outputs.clone()
    }

    /// The latest tracked pose, its timestamp and the tracking state. Copies a small
    /// struct under a mutex that the tracker holds only to overwrite it once per
    /// frame, so it never blocks the tracker for more than that copy.
    pub fn latest(&self) -> LatestPose {
        *lock(&self.shared.latest)
    }

    /// Every tracked frame's pose so far (empty unless `keep_trajectory`; with a
    /// [`PipelineOptions::trajectory_window`], the latest ones).
    pub fn trajectory(&self) -> Vec<PoseRecord> {
        lock(&self.shared.poses).poses_since(0)
    }

    /// The poses of the tracked frames from index `from` on (empty when `from` is at or
    /// past the end, or without `keep_trajectory`). Copies only those, under the same
    /// short lock: a reader polling for new poses pays for what is new, not for the
    /// whole session. With a window, poses before [`Pipeline::trajectory_start`] are
    /// gone and the result starts there: each record carries its `index`.
    pub fn trajectory_since(&self, from: u64) -> Vec<PoseRecord> {
        lock(&self.shared.poses).poses_since(from)
    }

    /// Copies at most `max` of the kept poses with `index >= from` into `out` (cleared
    /// first) and returns the index of the first kept pose and the index after the
    /// last: a caller can copy a long trajectory a chunk at a time, never holding the
    /// lock long and never allocating the whole window.
    pub fn trajectory_chunk(&self, from: u64, max: usize, out: &mut Vec<PoseRecord>) -> (u64, u64) {
        lock(&self.shared.poses).chunk(from, max, out)
    }

    /// The index of the first pose still kept: 0 unless a
    /// [`PipelineOptions::trajectory_window`] has overflowed.
    pub fn trajectory_start(&self) -> u64 {
        lock(&self.shared.poses).start()
    }

    /// Every reference frame's pose so far, in order, the first frame included
    /// (empty unless `keep_trajectory`; with a window, those among the kept poses).
    pub fn references(&self) -> Vec<PoseRecord> {
        lock(&self.shared.poses).references()
    }

    /// A consistent copy of the cloud (empty without geometry). The geometry thread
    /// owns the cloud and adds a reference frame's points under a short lock; the
    /// copy is taken under the same lock, so it never stops the tracker.
    pub fn cloud_snapshot(&self) -> Vec<CloudPoint> {
        let mut v = Vec::new();
        self.cloud_snapshot_into(0, &mut v);
        v
    }

    /// At most `max_points` of the cloud's points, taken evenly (point `i * n / k` of
    /// `n` for `k` taken), copied under the cloud's lock: a viewer asking for a few
    /// thousand points copies those, not the whole cloud.
    pub fn cloud_sample(&self, max_points: usize) -> Vec<CloudPoint> {
        let n = self.cloud_len();
        let take = n.min(max_points);
        let mut out = Vec::with_capacity(take);
        self.cloud_sample_part(n, take, 0..take, &mut out);
        out
    }

    /// Points in the cloud now (0 without geometry).
    pub fn cloud_len(&self) -> usize {
        self.shared
            .cloud
            .as_ref()
            .map_or(0, |c| lock(c).points.len())
    }

    /// Part `range` of the sample of `take` points of the first `n` (point `i * n /
    /// take`, as [`Pipeline::cloud_sample`]) appended to `out`, so that a large sample
    /// can be copied a part at a time; `n` is a size the cloud had (it only grows).
    pub fn cloud_sample_part(
        &self,
        n: usize,
        take: usize,
        range: std::ops::Range<usize>,
        out: &mut Vec<CloudPoint>,
    ) {
        if let Some(c) = &self.shared.cloud {
            let c = lock(c);
            let n = n.min(c.points.len());
            let take = take.min(n);
            for i in range.start..range.end.min(take) {
                out.push(c.points[if take == n { i } else { i * n / take }]);
            }
        }
    }

    /// Appends the cloud's points from position `from` on to `out` and returns the
    /// cloud's size. The cloud only grows at its end, so a renderer can pass the size
    /// it got last time and copy only the new points.
    pub fn cloud_snapshot_into(&self, from: usize, out: &mut Vec<CloudPoint>) -> usize {
        match &self.shared.cloud {
            Some(c) => {
                let c = lock(c);
                if from < c.points.len() {
                    out.extend_from_slice(&c.points[from..]);
                }
                c.points.len()
            }
            None => 0,
        }
    }

    /// A snapshot of the statistics, callable at any time.
    pub fn stats(&self) -> PipelineStats {
        let s = &*self.shared;
        // A copy, so that the lock is not held while the other locks are taken.
        let p = *lock(&s.progress);
        let wall = match (p.first_push, p.last_tracked) {
            (Some(a), Some(b)) if p.tracked > 0 => {
                b.saturating_duration_since(a).as_secs_f64() * 1e3 / p.tracked as f64
            }
            _ => 0.0,
        };
        PipelineStats {
            filter: lock(&s.timers.filter).summary(),
            tracker: lock(&s.timers.tracker).summary(),
            work: lock(&s.timers.work).summary(),
            work_cpu: lock(&s.timers.work_cpu).summary(),
            geometry: lock(&s.timers.geometry).summary(),
            latency: lock(&s.timers.latency).summary(),
            wall_ms_per_frame: wall,
            pushed: p.pushed,
            tracked: p.tracked,
            dropped: p.dropped_at_input + p.dropped_at_tracker,
            dropped_at_input: p.dropped_at_input,
            dropped_at_tracker: p.dropped_at_tracker,
            failed_preparations: p.failed_preparations,
            geometry_skipped: p.geometry_skipped,
            outputs_discarded: p.outputs_discarded,
            ahead_computed: p.ahead_computed,
            ahead_used: p.ahead_used,
            timestamps_rejected: p.timestamps_rejected,
            repeated_frames: p.repeated_frames,
            intrinsics_changes: p.intrinsics_changes,
            poses_discarded: lock(&s.poses).start(),
            input_queue: s.input.stats(),
            tracker_queue: s.prepared.stats(),
            geometry_queue: s.to_geometry.stats(),
            frame_pool: s.frames.stats(),
            counters: lock(&s.counters).clone(),
            cloud_points: self.cloud_len(),
            depth_noise: *lock(&s.depth_noise),
        }
    }
}
