//! Whether a registration is believed: the camera's speed and the residuals'
//! spread.

use super::Counters;
use crate::Pose;
use crate::config::{Config, Weighting};
use crate::motion::MotionResult;
use crate::spread::SpreadWatch;

/// Slack on the speed check, metres: registration noise on a short interval.
const SPEED_SLACK_M: f64 = 0.02;

/// Whether a camera that moved by `motion` in `dt` seconds stays under `max_speed`
/// (m/s). Without a usable interval (timestamps not increasing) nothing is refused.
pub(super) fn plausible_speed(motion: &Pose, dt: f64, max_speed: f64) -> bool {
    !(dt > 0.0) || motion.translation.vector.norm() <= max_speed * dt + SPEED_SLACK_M
}

/// Whether a registration `r` (\[A\] or a recovery) by which the camera moved `moved`
/// from the previous frame, `dt` seconds before, is believed: the speed stays under
/// [`Config::max_speed_m_s`], and its intensity and depth residuals do not both spread
/// more than [`Config::max_spread_jump`] times wider than the recent \[A\]s' (checked
/// with bivariate weighting only, the one that estimates the two spreads apart). A
/// refusal is counted (`implausible_motions`, `spread_jumps`).
pub(super) fn believable(
    config: &Config,
    spread: &SpreadWatch,
    counters: &mut Counters,
    r: &MotionResult,
    moved: &Pose,
    dt: f64,
) -> bool {
    if !plausible_speed(moved, dt, config.max_speed_m_s) {
        counters.implausible_motions += 1;
        return false;
    }
    let jumped = config.motion.weighting == Weighting::Bivariate
        && r.scale
            .is_some_and(|s| spread.is_jump(&s, config.max_spread_jump));
    if jumped {
        counters.spread_jumps += 1;
    }
    !jumped
}
