//! Adaptive multi-level pose error correction (section 3, Figure 1(b)).
//!
//! Every frame is registered against the previous one, `T_{c,p} = MOTION(Fc, Fp, I)`
//! (box [A]). When the motion accumulated since the level-1 reference,
//! `T_{p,r1} T_{c,p}`, passes `comp(·, (εd, εa))`, the pose is re-estimated against
//! that reference seeded with the accumulated motion (box [B]) and the frame
//! becomes the new level-1 reference; a new level-1 reference is checked the same
//! way against level 2 with looser thresholds (box [C]), and so on for N levels.
//! Only the previous frame and one frame per level are kept.

use std::ops::Deref;
use std::sync::Arc;

use crate::Pose;
use crate::camera::FrameView;
use crate::config::{Config, ReferenceLevel};
use crate::error::Result;
use crate::motion::{MotionEstimator, MotionResult};
use crate::prepare::{PreparedFrame, Preparer};
use crate::se3;

/// `comp(T, (εd, εa))`: true when `‖t‖ > εd` or `tr(R) < 2 cos εa + 1`, i.e. when the
/// motion since the reference calls for a correction (section 3.2).
pub fn comp(t: &Pose, level: &ReferenceLevel) -> bool {
    let trace = t.rotation.to_rotation_matrix().matrix().trace();
    t.translation.vector.norm() > level.max_distance_m
        || trace < 2.0 * level.max_angle_deg.to_radians().cos() + 1.0
}

/// Where the tracker stands.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TrackingState {
    /// No frame yet.
    Initialising,
    /// The last frame registered.
    Tracking,
    /// The last frame did not register; its pose is the last good one.
    Lost,
}

/// What the tracker says about one frame.
#[derive(Clone, Copy, Debug)]
pub struct FrameOutput {
    /// Position of the frame in the stream, from 0.
    pub index: u64,
    /// Capture time in seconds.
    pub timestamp: f64,
    /// Camera-to-world pose; the world is the first camera. For a lost frame, the
    /// last good pose.
    pub pose: Pose,
    /// Tracking or lost.
    pub state: TrackingState,
    /// The frame became the reference at levels `1..=reference_levels` (0: none).
    pub reference_levels: u8,
    /// `MOTION` calls spent on this frame.
    pub motion_estimations: u32,
    /// The frame-to-frame estimate `T_{c,p}` of box [A] (None for the first frame).
    pub frame_to_frame: Option<MotionResult>,
    /// After too many lost frames the tracker started afresh at this frame, keeping
    /// the last good pose.
    pub reanchored: bool,
}

/// The counters of the paper's Table 1, and what went wrong.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Counters {
    /// Frames pushed.
    pub frames: u64,
    /// `MOTION` calls.
    pub motion_estimations: u64,
    /// Reference frames chosen at each level (the first frame is not counted).
    pub references: Vec<u64>,
    /// Frames that did not register against the previous frame.
    pub lost_frames: u64,
    /// Corrections ([B], [C], ...) that failed; the frame kept its uncorrected pose.
    pub failed_corrections: u64,
    /// Times the tracker started afresh after a run of lost frames.
    pub reanchors: u64,
}

/// A frame the tracker keeps, with its pose.
#[derive(Clone, Debug)]
pub struct Kept<F> {
    /// The prepared frame.
    pub frame: F,
    /// Its camera-to-world pose.
    pub pose: Pose,
    /// Its position in the stream.
    pub index: u64,
}

/// The adaptive error-correcting tracker. `F` is any shared handle to a prepared
/// frame (`Arc<PreparedFrame>`, a pooled handle): the tracker clones it to keep a
/// frame as previous and as reference, and drops it when it no longer is one.
pub struct Tracker<F> {
    config: Config,
    estimator: MotionEstimator,
    prev: Option<Kept<F>>,
    refs: Vec<Option<Kept<F>>>,
    counters: Counters,
    lost_run: u32,
    next_index: u64,
    state: TrackingState,
}

impl<F: Clone + Deref<Target = PreparedFrame>> Tracker<F> {
    /// A tracker for `config`; fails on an invalid configuration.
    pub fn new(config: Config) -> Result<Self> {
        config.validate()?;
        let levels = config.reference_levels.len();
        Ok(Tracker {
            estimator: MotionEstimator::with_capacity(crate::prepare::max_template_points(&config)),
            prev: None,
            refs: vec![None; levels],
            counters: Counters {
                references: vec![0; levels],
                ..Counters::default()
            },
            lost_run: 0,
            next_index: 0,
            state: TrackingState::Initialising,
            config,
        })
    }

    /// The configuration in use.
    pub fn config(&self) -> &Config {
        &self.config
    }

    /// Counters so far.
    pub fn counters(&self) -> &Counters {
        &self.counters
    }

    /// State after the last frame.
    pub fn state(&self) -> TrackingState {
        self.state
    }

    /// The current reference frame of each level (level 1 first).
    pub fn references(&self) -> impl Iterator<Item = Option<&Kept<F>>> {
        self.refs.iter().map(|r| r.as_ref())
    }

    /// The previous frame.
    pub fn previous(&self) -> Option<&Kept<F>> {
        self.prev.as_ref()
    }

    /// Tracks one prepared frame (Figure 1(b)).
    pub fn track(&mut self, frame: F) -> FrameOutput {
        self.track_with(frame, |_| None)
    }

    /// Tracks one prepared frame whose [A] may have been computed ahead of time:
    /// `ahead` is given the previous frame the tracker registers against and returns
    /// [`frame_to_frame`]`(frame, previous)` if it was computed for exactly that pair,
    /// `None` otherwise (then the tracker computes it). [A] depends on nothing but
    /// the two frames, so the output is the same either way, bit for bit.
    pub fn track_with(
        &mut self,
        frame: F,
        ahead: impl FnOnce(&F) -> Option<MotionResult>,
    ) -> FrameOutput {
        let index = self.next_index;
        self.next_index += 1;
        self.counters.frames += 1;
        let mut out = FrameOutput {
            index,
            timestamp: frame.timestamp,
            pose: Pose::identity(),
            state: TrackingState::Tracking,
            reference_levels: 0,
            motion_estimations: 0,
            frame_to_frame: None,
            reanchored: false,
        };
        let Some(prev) = &self.prev else {
            self.anchor(frame, Pose::identity(), index);
            self.state = TrackingState::Tracking;
            return out;
        };

        // [A] frame to frame.
        let f2f = match ahead(&prev.frame) {
            Some(r) => r,
            None => frame_to_frame(&mut self.estimator, &frame, &prev.frame, &self.config),
        };
        out.motion_estimations += 1;
        self.counters.motion_estimations += 1;
        out.frame_to_frame = Some(f2f);
        if !f2f.is_ok() {
            self.counters.lost_frames += 1;
            self.lost_run += 1;
            out.pose = prev.pose;
            out.state = TrackingState::Lost;
            self.state = TrackingState::Lost;
            if self.lost_run > self.config.max_lost_frames {
                // The old frames are out of reach: start afresh here at the last good pose.
                let pose = prev.pose;
                self.anchor(frame, pose, index);
                self.counters.reanchors += 1;
                self.lost_run = 0;
                out.reanchored = true;
            }
            return out;
        }
        self.lost_run = 0;
        self.state = TrackingState::Tracking;
        let mut pose = se3::compose(&prev.pose, &f2f.pose);

        // [B], [C], ...: correct against each level's reference while the motion
        // accumulated since it is large enough.
        let mut became = 0usize;
        for (k, level) in self.config.reference_levels.iter().enumerate() {
            let Some(reference) = &self.refs[k] else {
                break;
            };
            let accumulated = se3::compose(&reference.pose.inverse(), &pose);
            if !comp(&accumulated, level) {
                break;
            }
            let r =
                self.estimator
                    .motion(&frame, &reference.frame, &accumulated, &self.config.motion);
            out.motion_estimations += 1;
            self.counters.motion_estimations += 1;
            if r.is_ok() {
                pose = se3::compose(&reference.pose, &r.pose);
            } else {
                self.counters.failed_corrections += 1;
            }
            self.counters.references[k] += 1;
            became = k + 1;
        }
        for r in &mut self.refs[..became] {
            *r = Some(Kept {
                frame: frame.clone(),
                pose,
                index,
            });
        }
        self.prev = Some(Kept { frame, pose, index });
        out.pose = pose;
        out.reference_levels = became as u8;
        out
    }

    /// Makes `frame` the previous frame and the reference at every level.
    fn anchor(&mut self, frame: F, pose: Pose, index: u64) {
        for r in &mut self.refs {
            *r = Some(Kept {
                frame: frame.clone(),
                pose,
                index,
            });
        }
        self.prev = Some(Kept { frame, pose, index });
    }
}

/// [A] of Figure 1(b): `MOTION(Fc, Fp, I)`, the motion from the current frame to the
/// previous one from the identity. It depends on the two frames alone, so it may run
/// before the tracker reaches `current` (the pipeline's filter stage does so when the
/// tracker is behind) and be handed to [`Tracker::track_with`].
pub fn frame_to_frame(
    estimator: &mut MotionEstimator,
    current: &PreparedFrame,
    previous: &PreparedFrame,
    config: &Config,
) -> MotionResult {
    estimator.motion(current, previous, &Pose::identity(), &config.motion)
}

/// The sequential engine: prepares each frame and tracks it, recycling prepared
/// frames so that memory stays constant and a warm engine does not allocate.
pub struct Odometry {
    preparer: Preparer,
    tracker: Tracker<Arc<PreparedFrame>>,
    pool: Vec<Arc<PreparedFrame>>,
}

impl Odometry {
    /// An engine for `config`; fails on an invalid configuration.
    pub fn new(config: Config) -> Result<Self> {
        let tracker = Tracker::new(config)?;
        Ok(Odometry {
            preparer: Preparer::new(tracker.config()),
            tracker,
            pool: Vec::new(),
        })
    }

    /// Prepares and tracks one frame; fails only on a frame that does not match the
    /// camera (wrong buffer sizes, non-finite timestamp).
    pub fn push(&mut self, view: FrameView<'_>) -> Result<FrameOutput> {
        // A pooled frame that only the pool still holds is free for reuse.
        let slot = self.pool.iter().position(|f| Arc::strong_count(f) == 1);
        let mut frame = match slot {
            Some(i) => self.pool.swap_remove(i),
            None => Arc::new(PreparedFrame::default()),
        };
        let prepared = Arc::get_mut(&mut frame).expect("a free pooled frame has one owner");
        if let Err(e) = self.preparer.prepare_into(view, prepared) {
            self.pool.push(frame);
            return Err(e);
        }
        self.pool.push(frame.clone());
        Ok(self.tracker.track(frame))
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
