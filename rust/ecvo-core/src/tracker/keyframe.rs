//! Keyframe tracking ([`Config::keyframes`], issue 26): each frame registered against
//! the level-1 reference, the keyframe, as DVO-SLAM and visual-odometry-rs do, instead
//! of against the previous frame; the keyframe replaced when the motion since it
//! passes level 1's thresholds, when its points stop landing on the frame, or when it
//! no longer registers. A new keyframe (and every `refine_every`th frame after one) is
//! fused with the chain through the previous frame, as a correction is.
//!
//! [`Config::keyframes`]: crate::Config::keyframes

use std::ops::Deref;

use nalgebra::Matrix6;

use super::frame_to_frame::frame_to_frame;
use super::{FrameOutput, Kept, Tracker, believable, comp, plausible_speed, ready};
use crate::Pose;
use crate::correction::{chain_step, correction_distance, fuse_correction};
use crate::motion::MotionResult;
use crate::prepare::PreparedFrame;
use crate::se3;

/// What [`Tracker::keyframe_update`] needs to know about a frame's registration.
pub(super) struct KeyframeStep<'a, F> {
    /// The frame's position in the stream.
    pub index: u64,
    /// Seconds since the previous frame.
    pub dt: f64,
    /// The keyframe registered against, when it is not the previous frame.
    pub keyframe: Option<&'a Kept<F>>,
    /// The registration that gave the pose (against the keyframe, or against the
    /// previous frame after a fall-back or when the keyframe is the previous frame).
    pub reg: &'a MotionResult,
    /// Whether it was believed (otherwise the pose came from a recovery).
    pub believed: bool,
    /// Whether the keyframe did not register and the previous frame did.
    pub fell_back: bool,
    /// The registration's covariance (with fused corrections only).
    pub add: Option<Matrix6<f64>>,
}

impl<F: Clone + Deref<Target = PreparedFrame>> Tracker<F> {
    /// `MOTION(frame, keyframe)` from the previous frame's pose relative to the
    /// keyframe and, with a prediction, from that pose moved by it (the better start
    /// at the coarsest step wins).
    pub(super) fn register_keyframe(
        &mut self,
        frame: &F,
        keyframe: &Kept<F>,
        prev: &Kept<F>,
        prior: Option<&Pose>,
    ) -> MotionResult {
        ready(&mut self.finisher, &keyframe.frame);
        let from_prev = se3::compose(&keyframe.pose.inverse(), &prev.pose);
        match prior {
            Some(p) => self.estimator.motion_from(
                frame,
                &keyframe.frame,
                &[from_prev, se3::compose(&from_prev, p)],
                &self.motion,
            ),
            None => self
                .estimator
                .motion(frame, &keyframe.frame, &from_prev, &self.motion),
        }
    }

    /// The keyframe did not register (or was not believed): \[A\] against the previous
    /// frame, if it is believed (the frame then becomes the new keyframe).
    pub(super) fn keyframe_fallback(
        &mut self,
        frame: &F,
        prev: &Kept<F>,
        prior: Option<&Pose>,
        dt: f64,
        out: &mut FrameOutput,
    ) -> Option<MotionResult> {
        ready(&mut self.finisher, &prev.frame);
        let r = frame_to_frame(&mut self.estimator, frame, &prev.frame, prior, &self.motion);
        out.motion_estimations += 1;
        self.counters.motion_estimations += 1;
        let believed = r.is_ok()
            && believable(
                &self.config,
                &self.spread,
                &mut self.counters,
                &r,
                &r.pose,
                dt,
            );
        if believed {
            self.counters.keyframe_fallbacks += 1;
        }
        believed.then_some(r)
    }

    /// After a frame registered (or recovered) with keyframe tracking: whether it
    /// becomes the new keyframe; the fusion of a new keyframe's (and every
    /// `refine_every`th frame's) registration with the chain through the previous
    /// frame, which may move `pose`; the covariances carried to the next frame.
    pub(super) fn keyframe_update(
        &mut self,
        frame: &F,
        prev: &Kept<F>,
        prior: Option<&Pose>,
        step: &KeyframeStep<'_, F>,
        pose: &mut Pose,
        out: &mut FrameOutput,
    ) -> bool {
        let KeyframeStep {
            index,
            dt,
            keyframe,
            reg,
            believed,
            fell_back,
            add,
        } = *step;
        let kf = self.refs.first().and_then(|r| r.as_ref());
        let far = match (kf, self.config.reference_levels.first()) {
            (Some(k), Some(level)) => comp(&se3::compose(&k.pose.inverse(), pose), level),
            _ => false,
        };
        let template = kf.map_or(0, |k| {
            k.frame.templates().last().map_or(0, |t| t.points.len())
        });
        let thin = !fell_back
            && believed
            && (reg.valid_pixels as f64) < self.config.keyframe_min_overlap * template as f64;
        if thin && !far {
            self.counters.overlap_keyframes += 1;
        }
        let new_keyframe = far || thin || fell_back || !believed;
        let every = u64::from(self.config.keyframe_fuse_every);
        let periodic =
            keyframe.is_some_and(|k| every > 0 && (index - k.index).is_multiple_of(every));
        let mut posterior = None;
        if (new_keyframe || periodic)
            && believed
            && !fell_back
            && self.config.fuse_corrections
            && let (Some(k), Some(cov)) = (keyframe, self.keyframe_chain)
        {
            ready(&mut self.finisher, &prev.frame);
            let r = frame_to_frame(&mut self.estimator, frame, &prev.frame, prior, &self.motion);
            out.motion_estimations += 1;
            self.counters.motion_estimations += 1;
            self.counters.keyframe_fusions += 1;
            if r.is_ok()
                && plausible_speed(&r.pose, dt, self.config.max_speed_m_s)
                && let Some(step) = r.information.try_inverse()
            {
                // The chain: the previous frame's registration against the keyframe,
                // then [A].
                let guess = se3::compose(&se3::compose(&k.pose.inverse(), &prev.pose), &r.pose);
                let chained = chain_step(&cov, &r.pose, &step);
                let to_keyframe =
                    if correction_distance(&guess, reg) > self.config.max_correction_distance {
                        // The registration landed implausibly far from the chain.
                        self.counters.rejected_corrections += 1;
                        posterior = Some(chained);
                        Some(guess)
                    } else {
                        // (Σ_c⁻¹ + Σ_r⁻¹)⁻¹ = Σ_c (Σ_c + Σ_r)⁻¹ Σ_r.
                        posterior =
                            add.and_then(|cr| Some(chained * (cr + chained).try_inverse()? * cr));
                        fuse_correction(&guess, &chained, reg)
                    };
                if let Some(m) = to_keyframe {
                    *pose = se3::compose(&k.pose, &m);
                    if let Some(v) = &mut self.velocity {
                        v.motion = se3::compose(&prev.pose.inverse(), pose);
                    }
                }
            }
        }
        // The covariance of the next frame's guess relative to the keyframe.
        self.keyframe_chain = if new_keyframe {
            self.config.fuse_corrections.then(Matrix6::zeros)
        } else {
            posterior.or(add)
        };
        // The chain since each higher level's reference: broken by a fall-back or a
        // recovery; otherwise, at a new keyframe, it takes the step from the old one.
        if new_keyframe {
            let step = if believed && !fell_back { add } else { None };
            for c in &mut self.chain[1..] {
                *c = match (*c, step) {
                    (Some(c), Some(a)) => Some(chain_step(&c, &reg.pose, &a)),
                    _ => None,
                };
            }
        }
        new_keyframe
    }
}
