//! \[A\] as a free function (the pipeline's filter stage computes it ahead) and the
//! settings a tracker's `MOTION` calls start from.

use crate::Pose;
use crate::config::{DepthNoiseModel, MotionConfig};
use crate::motion::{MotionEstimator, MotionResult};
use crate::prepare::PreparedFrame;

/// \[A\] of Figure 1(b): `MOTION(Fc, Fp, ·)`, the motion from the current frame to the
/// previous one, from the identity and, when given, from the constant-velocity
/// prediction `prior` (the better start at the coarsest step wins). It depends on
/// the two frames and the prior alone, so it may run before the tracker reaches
/// `current` (the pipeline's filter stage does so when the tracker is behind) and
/// be handed to [`Tracker::track_with`](super::Tracker::track_with).
pub fn frame_to_frame(
    estimator: &mut MotionEstimator,
    current: &PreparedFrame,
    previous: &PreparedFrame,
    prior: Option<&Pose>,
    motion: &MotionConfig,
) -> MotionResult {
    match prior {
        Some(p) => estimator.motion_from(current, previous, &[Pose::identity(), *p], motion),
        None => estimator.motion(current, previous, &Pose::identity(), motion),
    }
}

/// The settings a tracker starts its `MOTION` calls with for `motion`: under
/// [`DepthNoiseModel::Fitted`], `Quadratic` until the fit moves it, and the depth
/// spread measured.
pub fn working_motion(motion: &MotionConfig) -> MotionConfig {
    let mut m = motion.clone();
    if m.depth_noise == DepthNoiseModel::Fitted {
        m.depth_noise = DepthNoiseModel::Quadratic;
        m.depth_spread = true;
    }
    m
}
