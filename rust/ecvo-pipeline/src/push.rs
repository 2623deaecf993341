//! The input side of [`Pipeline`]: pushing frames (with the order, repeat and admission
//! checks), changing the intrinsics, closing the input.

use std::sync::atomic::Ordering;
use std::time::Instant;

use ecvo_core::Camera;

use crate::queue::lock;
use crate::shared::*;
use crate::{Admission, FrameView, Pipeline, PushStatus, Result, frame_hash};

impl Pipeline {
    /// Queues one frame: `fill` writes its intensity and raw depth (each `width *
    /// height`, row-major) into a pooled buffer, which it must overwrite entirely
    /// (the buffer holds an older frame). Offline, waits while the input queue is
    /// full; live, returns at once, dropping the oldest waiting frame if need be.
    ///
    /// Push from one thread at a time for frames to be tracked in push order. Fails
    /// on a non-finite timestamp, on one not greater than the last accepted frame's
    /// ([`Error::TimestampNotIncreasing`](crate::Error::TimestampNotIncreasing); the frame is not queued, the pipeline goes
    /// on), after [`Pipeline::close_input`], or once a stage has failed (with that
    /// failure). A frame bit-identical to the previous one is not queued:
    /// [`PushStatus::Repeated`].
    pub fn push(
        &self,
        timestamp: f64,
        fill: impl FnOnce(&mut [u8], &mut [u16]),
    ) -> Result<PushStatus> {
        self.push_stamped(timestamp, None, None, fill)
    }

    /// [`Pipeline::push`] for a frame whose depth image was captured at
    /// `depth_timestamp` (seconds, the frames' clock), not at its intensity's
    /// `timestamp`: with gyro samples pushed that cover the two times (and
    /// [`ecvo_core::Config::imu_depth_time`]), its depth is turned to the intensity's
    /// time before it is prepared, as [`ecvo_core::Odometry::push_with_depth_time`]
    /// does, from the samples pushed before this call.
    pub fn push_with_depth_time(
        &self,
        timestamp: f64,
        depth_timestamp: f64,
        fill: impl FnOnce(&mut [u8], &mut [u16]),
    ) -> Result<PushStatus> {
        self.push_stamped(timestamp, None, Some(depth_timestamp), fill)
    }

    /// [`Pipeline::push`] with the timestamp in integer nanoseconds, as cameras give
    /// it (Android's `Image.getTimestamp`): the order check compares the integers
    /// ([`Error::TimestampNsNotIncreasing`](crate::Error::TimestampNsNotIncreasing), in nanoseconds), so two frames 1 ns apart
    /// are told apart at any magnitude, where their seconds as `f64` may be equal
    /// (above 2^53 ns, about 104 days). The engine gets `ns / 1e9` seconds.
    pub fn push_ns(
        &self,
        timestamp_ns: i64,
        fill: impl FnOnce(&mut [u8], &mut [u16]),
    ) -> Result<PushStatus> {
        self.push_stamped(timestamp_ns as f64 / 1e9, Some(timestamp_ns), None, fill)
    }

    fn push_stamped(
        &self,
        timestamp: f64,
        timestamp_ns: Option<i64>,
        depth_timestamp: Option<f64>,
        fill: impl FnOnce(&mut [u8], &mut [u16]),
    ) -> Result<PushStatus> {
        let pushed_at = Instant::now();
        let s = &*self.shared;
        if !timestamp.is_finite() {
            return Err(
                ecvo_core::Error::BadFrame(format!("timestamp {timestamp} is not finite")).into(),
            );
        }
        if let Some(d) = depth_timestamp {
            ecvo_core::imu::depth_time::check_depth_timestamp(d)?;
        }
        // A closed or failed pipeline says so before anything else.
        if s.aborted() || s.input_closed.load(Ordering::Acquire) {
            return Err(s.stopped_error());
        }
        s.check_timestamp(&lock(&s.last_input), timestamp, timestamp_ns)?;
        let raw = s.take_raw()?;
        let mut guard = RawGuard {
            shared: s,
            raw: Some(raw),
        };
        let (hash, blank) = {
            let r = guard.raw.as_mut().expect("the guard holds the frame");
            fill(&mut r.intensity, &mut r.depth);
            (
                frame_hash(&r.intensity, &r.depth),
                r.depth.iter().all(|&d| d == 0),
            )
        };
        {
            // Checked again: another thread may have pushed meanwhile.
            let mut last = lock(&s.last_input);
            s.check_timestamp(&last, timestamp, timestamp_ns)?;
            // A frame without any depth (a covered lens) goes to the tracker, which
            // flags it lost, however often it comes.
            let repeated = !blank && last.hash == Some(hash);
            last.timestamp = Some(timestamp);
            last.timestamp_ns = timestamp_ns;
            last.hash = Some(hash);
            if repeated {
                drop(last);
                s.update_progress(|p| p.repeated_frames += 1);
                return Ok(PushStatus::Repeated);
            }
            if let Some(r) = guard.raw.as_mut() {
                r.camera = last.camera;
            }
        }
        let mut raw = guard.raw.take().expect("the guard holds the frame");
        raw.timestamp = timestamp;
        raw.pushed_at = pushed_at;
        raw.sequence = s.next_sequence.fetch_add(1, Ordering::Relaxed);
        {
            let inbox = lock(&s.imu);
            raw.imu_upto = inbox.ring.pushed();
            raw.depth_time = match depth_timestamp {
                Some(d) if self.config.imu_depth_time => inbox.clock.depth_time(timestamp, d),
                _ => ecvo_core::imu::DepthTime::Same,
            };
        }
        {
            let mut p = lock(&s.progress);
            p.pushed += 1;
            p.first_push.get_or_insert(pushed_at);
        }
        let queued = match s.admission {
            Admission::Offline => s.input.push_blocking(raw).map(|()| None),
            Admission::Live => s.input.push_evicting(raw),
        };
        match queued {
            Ok(None) => Ok(PushStatus::Accepted),
            Ok(Some(old)) => {
                s.give_raw(old);
                s.update_progress(|p| p.dropped_at_input += 1);
                Ok(PushStatus::DroppedOldest)
            }
            Err(raw) => {
                s.give_raw(raw);
                s.update_progress(|p| p.pushed -= 1);
                Err(s.stopped_error())
            }
        }
    }

    /// New intrinsics of the same image size for the frames pushed from now on: a
    /// zoom, a refocus, or a calibration the camera reports per frame (Android's
    /// `LENS_INTRINSIC_CALIBRATION`). Tracking goes on across the change: each frame
    /// is prepared with the intrinsics in force when it was pushed, and MOTION
    /// projects with each frame's own ([`ecvo_core::Preparer::set_intrinsics`]).
    /// Counted in [`PipelineStats::intrinsics_changes`](crate::PipelineStats::intrinsics_changes) when they differ from the
    /// current ones. Fails, changing nothing, on invalid intrinsics or another image
    /// size (which needs a new pipeline).
    ///
    /// The pipeline cannot see a zoom it is not told about: frames of a zoomed lens
    /// read as a camera moving along its axis.
    pub fn set_intrinsics(&self, camera: Camera) -> Result<()> {
        let s = &*self.shared;
        camera.validate_change_from(&s.camera)?;
        let mut last = lock(&s.last_input);
        if last.camera != camera {
            last.camera = camera;
            drop(last);
            s.update_progress(|p| p.intrinsics_changes += 1);
        }
        Ok(())
    }

    /// The intrinsics frames pushed now are prepared with.
    pub fn intrinsics(&self) -> Camera {
        lock(&self.shared.last_input).camera
    }

    /// Queues a copy of `view` (checked against the camera); see [`Pipeline::push`].
    pub fn push_view(&self, view: FrameView<'_>) -> Result<PushStatus> {
        view.validate(&self.config.camera)?;
        self.push(view.timestamp, |i, d| {
            i.copy_from_slice(view.intensity);
            d.copy_from_slice(view.depth);
        })
    }

    /// [`Pipeline::push_view`] for a frame whose depth image was taken at
    /// `depth_timestamp` ([`Pipeline::push_with_depth_time`]).
    pub fn push_view_with_depth_time(
        &self,
        view: FrameView<'_>,
        depth_timestamp: f64,
    ) -> Result<PushStatus> {
        view.validate(&self.config.camera)?;
        self.push_with_depth_time(view.timestamp, depth_timestamp, |i, d| {
            i.copy_from_slice(view.intensity);
            d.copy_from_slice(view.depth);
        })
    }

    /// Declares the end of the stream: further pushes fail with [`Error::Closed`](crate::Error::Closed),
    /// the stages finish the frames already queued, and the outputs channel closes
    /// after the last one.
    pub fn close_input(&self) {
        self.shared.input_closed.store(true, Ordering::Release);
        self.shared.input.close();
        let _g = lock(&self.shared.raw);
        self.shared.raw_freed.notify_all();
    }
}
