//! What the tracker says: its state and the output of each frame.

use crate::Pose;
use crate::lost::LostReason;
use crate::motion::MotionResult;

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
    /// The frame-to-frame estimate `T_{c,p}` of box \[A\] (None for the first frame);
    /// with keyframe tracking, the registration that gave the pose: against the
    /// keyframe, or against the previous frame (when it is the keyframe, or after a
    /// fall-back).
    pub frame_to_frame: Option<MotionResult>,
    /// After too many lost frames the tracker started afresh at this frame, keeping
    /// the last good pose.
    pub reanchored: bool,
    /// \[A\] failed but the frame registered against a kept reference frame instead.
    pub recovered: bool,
    /// Corrections of this frame that failed or were rejected (it kept the pose it
    /// had before each of them and did not become that level's reference).
    pub refused_corrections: u8,
    /// The registration the frame's pose came from before any correction: \[A\]
    /// (with keyframe tracking the one that gave the pose), or the recovery against a
    /// kept reference. None for the first frame, a re-anchored one and a lost one.
    /// Its `information` (`JᵀWJ` in the tangent space of the registered motion),
    /// `scale` and `valid_pixels / template_points` are the frame's quality.
    pub registration: Option<MotionResult>,
    /// Why the frame was lost (None unless [`TrackingState::Lost`]).
    pub lost_reason: Option<LostReason>,
}
