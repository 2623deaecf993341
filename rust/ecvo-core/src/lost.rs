//! Why a frame was lost ([`LostReason`]), for [`crate::FrameOutput::lost_reason`].

use crate::motion::{Failure, MotionResult, Status};

/// Why the tracker lost a frame: the first thing that went wrong with the frame's
/// registration (\[A\], or with keyframe tracking the keyframe's), after recovery
/// against the kept references failed too. A refused correction never loses a frame
/// (it keeps the pose it had: [`crate::FrameOutput::refused_corrections`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LostReason {
    /// The frame has no valid depth pixel (a covered lens, a sensor dropout).
    NoValidDepth,
    /// Too few template points landed on valid pixels of the other frame (too little
    /// overlap or depth): [`Failure::TooFewPixels`].
    TooFewPoints,
    /// The normal equations are singular or nearly so (flat, featureless input):
    /// [`Failure::Degenerate`].
    Degenerate,
    /// The solve diverged: a non-finite estimate, or a motion larger than a
    /// frame-to-frame motion can be ([`Failure::NotFinite`], [`Failure::TooLarge`]).
    Diverged,
    /// The residuals at the result spread too widely: the frames do not show the same
    /// scene at that alignment ([`Failure::Inconsistent`]).
    Inconsistent,
    /// The registration converged but implies a camera faster than
    /// [`crate::Config::max_speed_m_s`] (`implausible_motions`).
    ImplausibleSpeed,
    /// The registration converged but its residuals spread far wider than the recent
    /// frames' (`spread_jumps`, `keyframe_spread_refusals`).
    SpreadJump,
}

impl LostReason {
    /// The reason for a frame with `valid_depth` depth pixels whose registration `r`
    /// was not believed; `speed_ok` says whether its motion passed the speed check.
    pub fn of(valid_depth: usize, r: &MotionResult, speed_ok: bool) -> LostReason {
        if valid_depth == 0 {
            return LostReason::NoValidDepth;
        }
        match r.status {
            Status::Failed(Failure::TooFewPixels) => LostReason::TooFewPoints,
            Status::Failed(Failure::Degenerate) => LostReason::Degenerate,
            Status::Failed(Failure::NotFinite | Failure::TooLarge) => LostReason::Diverged,
            Status::Failed(Failure::Inconsistent) => LostReason::Inconsistent,
            Status::Converged | Status::MaxIterations if !speed_ok => LostReason::ImplausibleSpeed,
            Status::Converged | Status::MaxIterations => LostReason::SpreadJump,
        }
    }

    /// A short snake_case name (`"no_valid_depth"`, `"too_few_points"`, ...).
    pub fn name(self) -> &'static str {
        match self {
            LostReason::NoValidDepth => "no_valid_depth",
            LostReason::TooFewPoints => "too_few_points",
            LostReason::Degenerate => "degenerate",
            LostReason::Diverged => "diverged",
            LostReason::Inconsistent => "inconsistent",
            LostReason::ImplausibleSpeed => "implausible_speed",
            LostReason::SpreadJump => "spread_jump",
        }
    }
}
