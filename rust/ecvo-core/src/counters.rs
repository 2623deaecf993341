//! The tracker's counters: the paper's Table 1 (motion estimations, reference frames
//! per level) and what went wrong or was done besides.

use crate::imu::ImuCounters;

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
    /// Corrections (\[B\], \[C\], ...) that failed; the frame kept its uncorrected pose
    /// and did not become a reference at that level or above.
    pub failed_corrections: u64,
    /// Corrections that converged implausibly far from their initial guess
    /// ([`crate::Config::max_correction_distance`]) and were rejected like failed ones.
    pub rejected_corrections: u64,
    /// References that were replaced without a correction after
    /// [`crate::tracker::MAX_REFUSED_CORRECTIONS`] refused corrections in a row against them (they
    /// also count in `references`).
    pub stale_references: u64,
    /// Frames whose \[A\] failed but that registered against a kept reference frame.
    pub recovered_frames: u64,
    /// \[A\]s that started from the constant-velocity prediction rather than the
    /// identity (the prediction explained the coarsest level better).
    pub predicted_starts: u64,
    /// Times the tracker started afresh after a run of lost frames.
    pub reanchors: u64,
    /// Registrations (\[A\] or a recovery) not believed because they implied a camera
    /// faster than [`crate::Config::max_speed_m_s`].
    pub implausible_motions: u64,
    /// Registrations of a frame against the level-1 reference between corrections
    /// ([`crate::Config::refine_every`]): one `MOTION` call each (also counted in
    /// `motion_estimations`).
    pub refinements: u64,
    /// Those of them that failed or landed implausibly far from the chained pose
    /// (or could not be fused): the frame kept its chained pose.
    pub refused_refinements: u64,
    /// Registrations (\[A\] or a recovery) not believed because their intensity and
    /// depth residuals both spread more than [`crate::Config::max_spread_jump`] times wider
    /// than the recent frame-to-frame registrations' ([`crate::spread`]).
    pub spread_jumps: u64,
    /// With keyframe tracking ([`crate::Config::keyframes`]): frames whose
    /// registration against the keyframe was not believed and that registered against
    /// the previous frame instead (they became the new keyframe).
    pub keyframe_fallbacks: u64,
    /// With keyframe tracking: keyframes made because too few of the old keyframe's
    /// points still landed on the frame ([`crate::Config::keyframe_min_overlap`]).
    pub overlap_keyframes: u64,
    /// With keyframe tracking: registrations against the keyframe refused because
    /// their residuals spread wider than the recent ones'
    /// ([`crate::Config::keyframe_max_spread_growth`]).
    pub keyframe_spread_refusals: u64,
    /// With keyframe tracking and fused corrections: new keyframes whose registration
    /// against the old one was fused with the chain through the previous frame (one
    /// more `MOTION` call each).
    pub keyframe_fusions: u64,
    /// Times the fitted depth-noise model ([`crate::DepthNoiseModel::Fitted`]) changed.
    pub noise_refits: u64,
    /// The IMU's samples and priors ([`crate::imu`]); all zero without one.
    pub imu: ImuCounters,
}
