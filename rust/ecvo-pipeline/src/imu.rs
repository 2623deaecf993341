//! The IMU's way through the pipeline: [`Pipeline::push_imu`] puts samples in an
//! inbox; each frame remembers how many had been pushed before it; the tracker stage
//! hands the tracker those samples before the frame, so the tracker sees exactly the
//! samples the sequential engine would, and the poses stay bit-identical.

use ecvo_core::imu::{DepthClock, GyroRing, GyroSample, ImuCalibration, check_finite};
use ecvo_core::{PreparedFrame, Tracker};

use crate::queue::lock;
use crate::{Pipeline, Result, Shared};

/// Samples the inbox holds between `push_imu` and the tracker: 20 s at 400 Hz,
/// 256 KiB, allocated at the first push. Samples the tracker has not read when they
/// are overwritten are counted (`Counters::imu.dropped`).
pub const IMU_INBOX_CAPACITY: usize = 8192;

/// The samples pushed, in push order, not yet known to be read; and the depth
/// clock, which turns a frame's depth to its intensity's time when pushed
/// ([`Pipeline::push_with_depth_time`]).
pub(crate) struct ImuInbox {
    pub(crate) ring: GyroRing,
    pub(crate) clock: DepthClock,
}

impl ImuInbox {
    pub(crate) fn new(calibration: ImuCalibration) -> Self {
        ImuInbox {
            ring: GyroRing::new(IMU_INBOX_CAPACITY),
            clock: DepthClock::new(calibration),
        }
    }
}

impl Pipeline {
    /// Takes gyroscope samples, in time order, for the frames pushed after this call
    /// (as [`ecvo_core::Odometry::push_imu`]; [`ecvo_core::imu`]): fails, taking none,
    /// on a batch with a non-finite value ([`ecvo_core::Error::BadImuSample`]); the
    /// tracker drops and counts a sample not after the last one it took. Push them
    /// from the thread that pushes the frames (or order the two calls): a frame's
    /// prior uses the samples pushed before it. With an IMU the filter stage
    /// computes no \[A\] ahead (its prior depends on the bias the tracker estimates).
    pub fn push_imu(&self, samples: &[GyroSample]) -> Result<()> {
        check_finite(samples)?;
        let s = &*self.shared;
        if s.aborted() || s.input_closed.load(std::sync::atomic::Ordering::Acquire) {
            return Err(s.stopped_error());
        }
        let mut inbox = lock(&s.imu);
        for x in samples {
            inbox.ring.push(*x);
        }
        inbox.clock.push(samples);
        Ok(())
    }
}

/// Hands `tracker` the samples pushed before the frame that saw `upto` of them and
/// after the ones already handed (`fed`); counts those overwritten meanwhile.
pub(crate) fn feed<F: Clone + std::ops::Deref<Target = PreparedFrame>>(
    s: &Shared,
    tracker: &mut Tracker<F>,
    fed: &mut u64,
    upto: u64,
) {
    if upto <= *fed {
        return;
    }
    let inbox = lock(&s.imu);
    let (lost, a, b) = inbox.ring.range(*fed, upto);
    // Finite: checked when pushed.
    let taken = tracker.push_imu(a).and_then(|()| tracker.push_imu(b));
    debug_assert!(taken.is_ok());
    tracker.count_imu_dropped(lost);
    *fed = upto;
}
