//! The sequential engine [`Odometry`]: prepare, then track, recycling prepared
//! frames.

use std::sync::Arc;

use crate::Pose;
use crate::camera::{Camera, FrameView};
use crate::config::Config;
use crate::error::Result;
use crate::imu::{DepthClock, DepthTime, GyroSample};
use crate::prepare::{PreparedFrame, Preparer};
use crate::tracker::{FrameOutput, Tracker};

/// The sequential engine: prepares each frame and tracks it, recycling prepared
/// frames so that memory stays constant and a warm engine does not allocate.
pub struct Odometry {
    preparer: Preparer,
    tracker: Tracker<Arc<PreparedFrame>>,
    pool: Vec<Arc<PreparedFrame>>,
    /// The gyro samples pushed, for frames with a depth time of their own.
    clock: DepthClock,
}

impl Odometry {
    /// An engine for `config`; fails on an invalid configuration, and on one whose
    /// memory ([`crate::memory::estimate`]) exceeds [`Config::memory_budget`]
    /// ([`crate::Error::MemoryBudget`]), before allocating anything.
    pub fn new(config: Config) -> Result<Self> {
        config.validate()?;
        crate::memory::check_budget(crate::memory::estimate(&config).bytes, config.memory_budget)?;
        let tracker = Tracker::new(config)?;
        Ok(Odometry {
            preparer: Preparer::new(tracker.config()),
            clock: DepthClock::new(tracker.config().imu),
            tracker,
            pool: Vec::new(),
        })
    }

    /// Prepares and tracks one frame; fails only on a frame that does not match the
    /// camera (wrong buffer sizes, non-finite timestamp).
    pub fn push(&mut self, view: FrameView<'_>) -> Result<FrameOutput> {
        self.push_prepared(view, DepthTime::Same)
    }

    /// [`Odometry::push`] for a frame whose depth image was captured at
    /// `depth_timestamp` (seconds, the frames' clock), not at its intensity's
    /// `view.timestamp`: with gyro samples covering the two times (and
    /// [`crate::Config::imu_depth_time`]), the depth is turned to the intensity's
    /// time before it is prepared ([`crate::imu::depth_time`]); counted in
    /// `Counters::imu` either way. Fails, as [`Odometry::push`] does, on a bad frame,
    /// and on a non-finite `depth_timestamp`.
    pub fn push_with_depth_time(
        &mut self,
        view: FrameView<'_>,
        depth_timestamp: f64,
    ) -> Result<FrameOutput> {
        crate::imu::depth_time::check_depth_timestamp(depth_timestamp)?;
        let t = if self.tracker.config().imu_depth_time {
            self.clock.depth_time(view.timestamp, depth_timestamp)
        } else {
            DepthTime::Same
        };
        self.push_prepared(view, t)
    }

    fn push_prepared(&mut self, view: FrameView<'_>, depth_time: DepthTime) -> Result<FrameOutput> {
        // A pooled frame that only the pool still holds is free for reuse.
        let slot = self.pool.iter().position(|f| Arc::strong_count(f) == 1);
        let mut frame = match slot {
            Some(i) => self.pool.swap_remove(i),
            // Reserved at full size, so that memory is what `memory::estimate` says.
            None => Arc::new(PreparedFrame::for_config(self.tracker.config())),
        };
        let prepared = Arc::get_mut(&mut frame).expect("a free pooled frame has one owner");
        if let Err(e) = self
            .preparer
            .prepare_turned_into(view, depth_time, prepared)
        {
            self.pool.push(frame);
            return Err(e);
        }
        self.pool.push(frame.clone());
        Ok(self.tracker.track(frame))
    }

    /// Seeds the next frame's registration with an outside guess of its motion from
    /// the previous frame ([`Tracker::set_guess`]).
    pub fn set_guess(&mut self, motion: Pose) {
        self.tracker.set_guess(motion);
    }

    /// Takes gyroscope samples, in time order, for the frames pushed after this call
    /// ([`Tracker::push_imu`], [`crate::imu`]): fails, taking none, on a batch with a
    /// non-finite value; drops and counts a sample not after the last one taken.
    pub fn push_imu(&mut self, samples: &[GyroSample]) -> Result<()> {
        self.tracker.push_imu(samples)?;
        self.clock.push(samples);
        Ok(())
    }

    /// Prepares the frames from the next one on with new intrinsics of the same image
    /// size ([`Preparer::set_intrinsics`]); tracking goes on across the change.
    pub fn set_intrinsics(&mut self, camera: Camera) -> Result<()> {
        self.preparer.set_intrinsics(camera)
    }

    /// The tracker, for its counters, state and reference frames.
    pub fn tracker(&self) -> &Tracker<Arc<PreparedFrame>> {
        &self.tracker
    }

    /// Prepared frames alive (previous, references and free ones): bounded by the
    /// number of levels plus two, whatever the length of the stream.
    pub fn frames_allocated(&self) -> usize {
        self.pool.len()
    }
}
