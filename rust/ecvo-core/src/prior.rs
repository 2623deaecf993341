//! The constant-velocity prior of \[A\]: the previous frame's motion, scaled to the
//! next frame's interval.

use crate::Pose;
use crate::se3;

/// The motion of the last frame registered frame to frame, for the
/// constant-velocity prediction of the next one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Velocity {
    /// Index of the frame it ends at.
    pub index: u64,
    /// Its \[A\]: `T_{c,p}`.
    pub motion: Pose,
    /// Time between the two frames (seconds).
    pub dt: f64,
}

/// The constant-velocity prediction of `T_{c,p}` for a frame `dt` seconds after its
/// previous one, from the previous frame's \[A\] `v` over `v.dt` seconds: `v`'s twist
/// scaled by `dt / v.dt` (at most 4, and `v` itself when the stamps cannot say).
/// `None` when there is nothing to predict (no motion, or a non-finite one).
pub fn predict(v: &Velocity, dt: f64) -> Option<Pose> {
    let ratio = if v.dt > 0.0 && dt > 0.0 && (dt / v.dt).is_finite() {
        (dt / v.dt).min(4.0)
    } else {
        1.0
    };
    let xi = se3::log(&v.motion) * ratio;
    let p = se3::exp(&xi);
    (se3::is_finite(&p) && xi.iter().any(|x| *x != 0.0)).then_some(p)
}
