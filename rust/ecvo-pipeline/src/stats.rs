//! Statistics as in the paper's Table 2: per-stage times per frame, total time per
//! frame, queue depths, dropped frames and the tracker's counters. Times go into
//! fixed-bin histograms, so the memory stays constant however long the stream.

use std::time::Duration;

use ecvo_core::Counters;

/// Histogram bins per doubling of time (a bin is 2^(1/16), about 4.4 %, wide).
const BINS_PER_OCTAVE: f64 = 16.0;
/// Octaves covered above [`FLOOR_MS`]: 1 µs to about 18 minutes.
const OCTAVES: usize = 30;
const BINS: usize = OCTAVES * BINS_PER_OCTAVE as usize;
/// Lower edge of the first bin, in milliseconds (shorter times land in it).
const FLOOR_MS: f64 = 1e-3;

/// A fixed-size log-binned histogram of durations: exact count, mean and maximum,
/// median and percentiles to within half a bin (about 2.2 %).
#[derive(Clone)]
pub(crate) struct Histogram {
    bins: Box<[u64; BINS]>,
    count: u64,
    sum_ms: f64,
    max_ms: f64,
}

impl Default for Histogram {
    fn default() -> Self {
        Histogram {
            bins: Box::new([0; BINS]),
            count: 0,
            sum_ms: 0.0,
            max_ms: 0.0,
        }
    }
}

impl Histogram {
    /// Adds one duration.
    pub(crate) fn record(&mut self, d: Duration) {
        let ms = d.as_secs_f64() * 1e3;
        let bin = if ms <= FLOOR_MS {
            0
        } else {
            ((ms / FLOOR_MS).log2() * BINS_PER_OCTAVE) as usize
        };
        self.bins[bin.min(BINS - 1)] += 1;
        self.count += 1;
        self.sum_ms += ms;
        self.max_ms = self.max_ms.max(ms);
    }

    /// The `q`-quantile (0..=1) in milliseconds: the geometric centre of its bin,
    /// clamped to the maximum.
    fn quantile_ms(&self, q: f64) -> f64 {
        if self.count == 0 {
            return 0.0;
        }
        let rank = ((q * self.count as f64).ceil() as u64).clamp(1, self.count);
        let mut seen = 0;
        for (i, &n) in self.bins.iter().enumerate() {
            seen += n;
            if seen >= rank {
                let centre = FLOOR_MS * ((i as f64 + 0.5) / BINS_PER_OCTAVE).exp2();
                return centre.min(self.max_ms);
            }
        }
        self.max_ms
    }

    /// Summary of what was recorded.
    pub(crate) fn summary(&self) -> StageStats {
        StageStats {
            frames: self.count,
            mean_ms: if self.count == 0 {
                0.0
            } else {
                self.sum_ms / self.count as f64
            },
            median_ms: self.quantile_ms(0.5),
            p95_ms: self.quantile_ms(0.95),
            max_ms: self.max_ms,
        }
    }
}

/// CPU time the calling thread has used so far (`CLOCK_THREAD_CPUTIME_ID`); zero
/// where the platform has no such clock. Differences of it time a stage's work on its
/// compute thread without the time the thread spent descheduled, as the peers are
/// timed (issue 30).
pub(crate) fn thread_cpu() -> std::time::Duration {
    #[cfg(unix)]
    {
        let mut ts = libc::timespec {
            tv_sec: 0,
            tv_nsec: 0,
        };
        // SAFETY: `ts` is a valid, writable timespec; the call only writes it.
        if unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) } == 0 {
            return std::time::Duration::new(ts.tv_sec as u64, ts.tv_nsec as u32);
        }
    }
    std::time::Duration::ZERO
}

/// Time one stage spent per frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StageStats {
    /// Frames the stage processed.
    pub frames: u64,
    /// Mean time per frame, milliseconds (exact).
    pub mean_ms: f64,
    /// Median time per frame, milliseconds (to within about 2 %).
    pub median_ms: f64,
    /// 95th percentile, milliseconds (to within about 2 %).
    pub p95_ms: f64,
    /// Longest time, milliseconds (exact).
    pub max_ms: f64,
}

/// Depth of one queue, sampled each time an item is pushed (the depth it sees
/// including itself).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct QueueStats {
    /// Most items it can hold.
    pub capacity: usize,
    /// Items in it now.
    pub depth: usize,
    /// Most items it held.
    pub max_depth: usize,
    /// Mean depth seen by a push.
    pub mean_depth: f64,
}

/// Occupancy of the prepared-frame pool.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PoolStats {
    /// Most frames it will ever allocate.
    pub capacity: usize,
    /// Frames allocated, all at start-up (freed with the pipeline).
    pub allocated: usize,
    /// Frames held now (being prepared, queued, previous, reference, or waiting for
    /// the geometry stage).
    pub in_use: usize,
    /// Most frames held at once.
    pub max_in_use: usize,
}

/// A snapshot of the pipeline's statistics (Table 2 of the paper and more).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PipelineStats {
    /// Filter stage (frame preparation) time per frame.
    pub filter: StageStats,
    /// Tracker stage (motion estimation and error correction) time per frame.
    pub tracker: StageStats,
    /// Filter plus tracker time of each tracked frame (its preparation and its
    /// tracking, \[A\] computed ahead included): the work one frame costs on one
    /// core, whose median and p95 the per-stage figures cannot give.
    pub work: StageStats,
    /// The same work as CPU time of the compute thread that ran it (0 where the
    /// platform has no thread CPU clock): with one compute thread it is the frame's
    /// whole cost on one core, unaffected by time spent descheduled on a loaded
    /// machine; with more, what rayon ran on other threads is not in it.
    pub work_cpu: StageStats,
    /// Geometry stage time per reference frame added to the cloud.
    pub geometry: StageStats,
    /// Time from `push` to the frame's pose being published, per tracked frame.
    pub latency: StageStats,
    /// Wall time from the first push to the last tracked frame, divided by the
    /// frames tracked: the paper's "Total" (0 before the first frame).
    pub wall_ms_per_frame: f64,
    /// Frames given to `push` (accepted, whether tracked or dropped later).
    pub pushed: u64,
    /// Frames the tracker processed.
    pub tracked: u64,
    /// Frames dropped in live mode, at the input queue plus at the tracker's queue.
    pub dropped: u64,
    /// Of `dropped`: frames evicted from the input queue before filtering.
    pub dropped_at_input: u64,
    /// Of `dropped`: prepared frames evicted from the tracker's queue.
    pub dropped_at_tracker: u64,
    /// Frames whose preparation failed (not tracked).
    pub failed_preparations: u64,
    /// Reference frames not added to the cloud because the geometry stage lagged
    /// (live mode only).
    pub geometry_skipped: u64,
    /// Outputs not sent because the output queue was full (live mode only).
    pub outputs_discarded: u64,
    /// Frames whose \[A\] (`frame_to_frame`) the filter stage computed ahead, because
    /// the tracker was behind.
    pub ahead_computed: u64,
    /// Of those, the ones the tracker used (the others were registered against an
    /// older frame, the previous one having been lost or dropped).
    pub ahead_used: u64,
    /// Frames refused by `push` because their timestamp was not after the previous
    /// frame's ([`crate::Error::TimestampNotIncreasing`]); not in `pushed`.
    pub timestamps_rejected: u64,
    /// Frames bit-identical to the previous one, not queued
    /// ([`crate::PushStatus::Repeated`]); not in `pushed`.
    pub repeated_frames: u64,
    /// Poses no longer kept because the [`crate::PipelineOptions::trajectory_window`]
    /// was full: the index of the first kept pose.
    pub poses_discarded: u64,
    /// Calls of [`crate::Pipeline::set_intrinsics`] that changed the intrinsics.
    pub intrinsics_changes: u64,
    /// Input queue (raw frames waiting for the filter).
    pub input_queue: QueueStats,
    /// Tracker queue (prepared frames waiting for the tracker).
    pub tracker_queue: QueueStats,
    /// Geometry queue (reference frames waiting to be added to the cloud).
    pub geometry_queue: QueueStats,
    /// Prepared-frame pool occupancy.
    pub frame_pool: PoolStats,
    /// The tracker's counters (the paper's Table 1 and 2 rows).
    pub counters: Counters,
    /// Points in the cloud.
    pub cloud_points: usize,
    /// The depth-noise model the tracker used last (under `DepthNoiseModel::Fitted`,
    /// the one fitted so far).
    pub depth_noise: ecvo_core::DepthNoiseModel,
}

/// Copies `src` into `dst` reusing `dst`'s buffers (a derived `clone_from` would
/// allocate). Destructures exhaustively so a new counter is a compile error here.
pub(crate) fn copy_counters(dst: &mut Counters, src: &Counters) {
    let Counters {
        frames,
        motion_estimations,
        references,
        lost_frames,
        failed_corrections,
        rejected_corrections,
        stale_references,
        recovered_frames,
        predicted_starts,
        refinements,
        refused_refinements,
        reanchors,
        implausible_motions,
        spread_jumps,
        keyframe_fallbacks,
        overlap_keyframes,
        keyframe_spread_refusals,
        keyframe_fusions,
        noise_refits,
        imu,
    } = src;
    dst.frames = *frames;
    dst.motion_estimations = *motion_estimations;
    dst.references.clone_from(references);
    dst.lost_frames = *lost_frames;
    dst.failed_corrections = *failed_corrections;
    dst.rejected_corrections = *rejected_corrections;
    dst.stale_references = *stale_references;
    dst.recovered_frames = *recovered_frames;
    dst.predicted_starts = *predicted_starts;
    dst.refinements = *refinements;
    dst.refused_refinements = *refused_refinements;
    dst.reanchors = *reanchors;
    dst.implausible_motions = *implausible_motions;
    dst.spread_jumps = *spread_jumps;
    dst.keyframe_fallbacks = *keyframe_fallbacks;
    dst.overlap_keyframes = *overlap_keyframes;
    dst.keyframe_spread_refusals = *keyframe_spread_refusals;
    dst.keyframe_fusions = *keyframe_fusions;
    dst.noise_refits = *noise_refits;
    dst.imu = *imu;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn histogram_median_and_mean() {
        let mut h = Histogram::default();
        for ms in [10.0, 20.0, 30.0, 40.0, 1000.0] {
            h.record(Duration::from_secs_f64(ms / 1e3));
        }
        let s = h.summary();
        assert_eq!(s.frames, 5);
        assert!((s.mean_ms - 220.0).abs() < 1e-9);
        assert!((s.median_ms / 30.0 - 1.0).abs() < 0.025, "{}", s.median_ms);
        assert!((s.max_ms - 1000.0).abs() < 1e-9);
        assert_eq!(Histogram::default().summary(), StageStats::default());
        h.record(Duration::ZERO);
        h.record(Duration::from_secs(1 << 20));
        assert_eq!(h.summary().frames, 7);
    }
}
