//! The filter stage's side of the constant-velocity prior: which prior the tracker
//! will start a frame's \[A\] from, as far as the filter stage can know it, so that \[A\]
//! computed ahead is the tracker's own computation.

use ecvo_core::tracker::{Velocity, predict};
use ecvo_core::{Config, MotionPrior, Pose};

use crate::pool::{Ahead, PooledFrame};

/// A frame's \[A\] as the next prediction needs it: motion and interval, `None` when it
/// failed (nothing to predict from).
pub(crate) type Link = Option<(Pose, f64)>;

/// What the tracker published after its last frame: that frame's sequence and link.
pub(crate) type Published = Option<(u64, Link)>;

/// The filter stage's knowledge of the tracker's constant-velocity prediction: the
/// tracker predicts a frame's \[A\] from the previous frame's \[A\] (when that one
/// registered), so the filter stage can compute \[A\] ahead with the same prior only
/// if it computed the previous frame's \[A\] itself. The tracker checks the prior
/// before it uses a result, so a wrong guess here costs time, never a pose.
#[derive(Default)]
pub(crate) struct Chain {
    /// Frames prepared so far.
    prepared: u64,
    /// Sequence and timestamp of the last frame prepared, and its \[A\] if this stage
    /// computed it: `Some(None)` when it failed (nothing to predict from).
    last: Option<(u64, f64, Option<Link>)>,
}

impl Chain {
    /// Whether to compute \[A\] ahead for a frame stamped `timestamp` registered
    /// against `prev`, and with which prior (`Some(prior)`), or not (`None`). Without
    /// the constant-velocity prior: whenever the tracker is `behind`. With it, only
    /// when the prior is known: `prev` is the first frame, or this stage computed
    /// `prev`'s \[A\] itself (its chain, which it then keeps going whatever the
    /// tracker's load when `offline`; live, where latency counts, only while the
    /// tracker is behind), or the tracker has just `published` its velocity after
    /// `prev` (it is idle, so the chain restarts at no cost in latency).
    pub(crate) fn prior(
        &self,
        config: &Config,
        prev: &PooledFrame,
        timestamp: f64,
        behind: bool,
        offline: bool,
        published: Published,
    ) -> Option<Option<Pose>> {
        // With keyframe tracking a frame registers against the keyframe, which this
        // stage does not know (nor the prediction, which comes from those
        // registrations): nothing to compute ahead.
        if config.keyframes {
            return None;
        }
        let (seq, prev_stamp, own) = self.last?;
        if seq != prev.sequence() {
            return None;
        }
        let from_tracker = published.filter(|(s, _)| *s == seq).map(|(_, v)| v);
        if config.motion.prior != MotionPrior::ConstantVelocity {
            // No prior to know: help whenever the tracker is behind.
            return behind.then_some(None);
        }
        // With the prior, a chain this stage stops cannot restart until the tracker is
        // idle, so once it runs it runs whatever the queue: the tracker then does the
        // corrections only.
        let first = self.prepared == 1;
        let keep_going = offline && (first || own.is_some());
        if !(behind || keep_going || from_tracker.is_some()) {
            return None;
        }
        let a = if first {
            // `prev` is the first frame: the tracker anchors on it, with no velocity.
            None
        } else {
            from_tracker.or(own)?
        };
        Some(a.and_then(|(motion, dt)| {
            let v = Velocity {
                index: 0,
                motion,
                dt,
            };
            predict(&v, timestamp - prev_stamp)
        }))
    }

    /// Records a prepared frame and the \[A\] computed ahead for it, if any.
    pub(crate) fn prepared(&mut self, sequence: u64, timestamp: f64, ahead: Option<&Ahead>) {
        let prev_stamp = self.last.map(|(_, t, _)| t);
        let a = ahead.map(|a| {
            a.result
                .is_ok()
                .then(|| (a.result.pose, timestamp - prev_stamp.unwrap_or(timestamp)))
        });
        self.prepared += 1;
        self.last = Some((sequence, timestamp, a));
    }
}
