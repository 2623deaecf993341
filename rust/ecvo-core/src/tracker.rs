//! Adaptive multi-level pose error correction (section 3, Figure 1(b)).
//!
//! Every frame is registered against the previous one, `T_{c,p} = MOTION(Fc, Fp, I)`
//! (box \[A\]). When the motion accumulated since the level-1 reference,
//! `T_{p,r1} T_{c,p}`, passes `comp(·, (εd, εa))`, the pose is re-estimated against
//! that reference seeded with the accumulated motion (box \[B\]) and the frame
//! becomes the new level-1 reference; a new level-1 reference is checked the same
//! way against level 2 with looser thresholds (box \[C\]), and so on for N levels.
//! Only the previous frame and one frame per level are kept.

use std::ops::Deref;

use nalgebra::Matrix6;

use crate::Pose;
use crate::config::{
    Config, DepthNoiseModel, MotionConfig, MotionPrior, ReferenceLevel, Weighting,
};
pub use crate::correction::correction_distance;
use crate::correction::{chain_step, fuse_correction};
pub use crate::counters::Counters;
use crate::error::Result;
use crate::imu::{DepthTime, Gyro};
pub use crate::lost::LostReason;
use crate::motion::{MotionEstimator, MotionResult};
use crate::noise::NoiseFit;
use crate::prepare::{PreparedFrame, Preparer};
pub use crate::prior::{Velocity, predict};
use crate::se3;
use crate::spread::SpreadWatch;

mod belief;
mod frame_to_frame;
mod inertial;
use belief::{believable, plausible_speed};
mod keyframe;
mod output;
mod recovery;
pub use frame_to_frame::{frame_to_frame, working_motion};
use keyframe::KeyframeStep;
pub use output::{FrameOutput, TrackingState};

/// `comp(T, (εd, εa))`: true when `‖t‖ > εd` or `tr(R) < 2 cos εa + 1`, i.e. when the
/// motion since the reference calls for a correction (section 3.2).
pub fn comp(t: &Pose, level: &ReferenceLevel) -> bool {
    let trace = t.rotation.to_rotation_matrix().matrix().trace();
    t.translation.vector.norm() > level.max_distance_m
        || trace < 2.0 * level.max_angle_deg.to_radians().cos() + 1.0
}

/// After this many refused (failed or rejected) corrections in a row against the
/// same reference, the next frame that calls for a correction at that level becomes
/// its reference without one: the old reference is out of reach.
pub const MAX_REFUSED_CORRECTIONS: u32 = 3;

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
    velocity: Option<Velocity>,
    /// Refused corrections in a row against each level's current reference.
    refused: Vec<u32>,
    /// Residual spreads of the last believed \[A\]s.
    spread: SpreadWatch,
    /// Covariance of the motion chained frame to frame since each level's reference
    /// (the believed \[A\]s' inverse information matrices, carried along by
    /// [`chain_step`]; `None` after a recovery or a loss, when the chain is broken, and
    /// while `Config::fuse_corrections` is off): [`fuse_correction`].
    chain: Vec<Option<Matrix6<f64>>>,
    /// The settings every `MOTION` call uses: `config.motion` with the depth-noise
    /// model in use (under [`DepthNoiseModel::Fitted`], the fitted one).
    motion: MotionConfig,
    /// The same for corrections, refinements and recoveries: their depth spread is
    /// not fitted, so not measured.
    correcting: MotionConfig,
    /// The depth-noise model's fit ([`DepthNoiseModel::Fitted`]).
    noise: NoiseFit,
    /// With keyframe tracking: the covariance of the previous frame's pose relative
    /// to the keyframe (zero when it is the keyframe; `None` when unknown).
    keyframe_chain: Option<Matrix6<f64>>,
    /// With frames prepared for lookup only ([`Config::lookup_depth`]): finishes the
    /// reference side of a frame before it is first registered against.
    finisher: Option<Preparer>,
    /// An outside guess of the next frame's motion from the previous frame
    /// ([`Tracker::set_guess`]), used once in place of the prediction.
    guess: Option<Pose>,
    /// The IMU's samples and bias estimate ([`crate::imu`], [`Tracker::push_imu`]).
    gyro: Gyro,
}

/// Makes `frame` ready to be registered against: finishes its reference side when it
/// was prepared for lookup only (once; a no-op otherwise).
fn ready(finisher: &mut Option<Preparer>, frame: &PreparedFrame) {
    if let Some(p) = finisher {
        p.finish(frame);
    }
    debug_assert!(frame.is_reference_ready(), "a reference frame is finished");
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
            velocity: None,
            refused: vec![0; levels],
            spread: SpreadWatch::default(),
            chain: vec![None; levels],
            motion: working_motion(&config.motion),
            correcting: MotionConfig {
                depth_spread: false,
                ..working_motion(&config.motion)
            },
            noise: NoiseFit::new(config.motion.depth_noise),
            keyframe_chain: None,
            finisher: crate::prepare::lookup_depth(&config).map(|_| Preparer::whole(&config)),
            guess: None,
            gyro: Gyro::new(config.imu),
            config,
        })
    }

    /// Whether the frames this tracker finishes get their normals (the point cloud
    /// reads them; [`Preparer::set_normals`]).
    pub fn set_normals(&mut self, on: bool) {
        if let Some(p) = &mut self.finisher {
            p.set_normals(on);
        }
    }

    /// The configuration in use.
    pub fn config(&self) -> &Config {
        &self.config
    }

    /// The settings of the tracker's \[A\]: the configuration's, with the depth-noise
    /// model in use ([`Self::depth_noise`]) (its other `MOTION` calls differ only in
    /// not measuring the depth spread). \[A\] computed elsewhere ([`frame_to_frame`])
    /// must use these to be the tracker's own.
    pub fn motion_config(&self) -> &MotionConfig {
        &self.motion
    }

    /// The depth-noise model in use: the configured one, or under
    /// [`DepthNoiseModel::Fitted`] the one fitted so far (`Quadratic` until the first
    /// fit moves it).
    pub fn depth_noise(&self) -> DepthNoiseModel {
        self.motion.depth_noise
    }

    /// The depth-noise fit (its last `(a, b)` of `σ² = a + b·z⁴`).
    pub fn noise_fit(&self) -> &NoiseFit {
        &self.noise
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

    /// The motion of the last frame registered frame to frame (what the next frame's
    /// prediction comes from).
    pub fn velocity(&self) -> Option<&Velocity> {
        self.velocity.as_ref()
    }

    /// The constant-velocity prediction of \[A\] for a frame stamped `timestamp` that
    /// registers against the previous frame, or `None` (the identity alone).
    pub fn prior_for(&self, timestamp: f64) -> Option<Pose> {
        if self.config.motion.prior != MotionPrior::ConstantVelocity {
            return None;
        }
        let prev = self.prev.as_ref()?;
        let v = self.velocity.as_ref().filter(|v| v.index == prev.index)?;
        predict(v, timestamp - prev.frame.timestamp)
    }

    /// Seeds the next frame's \[A\] with an outside guess of its motion from the
    /// previous frame, `T_{c,p}` (the current camera in the previous camera's
    /// coordinates: from an IMU, wheel odometry, another tracker), in place of the
    /// constant-velocity prediction: \[A\] starts from the identity and from the
    /// guess, and the better start at the coarsest step wins (a wrong guess costs
    /// one coarse step). A recovery starts from it too. Used for the next frame only;
    /// on the first frame it is ignored.
    pub fn set_guess(&mut self, motion: Pose) {
        self.guess = Some(motion);
    }

    /// Tracks one prepared frame (Figure 1(b)).
    pub fn track(&mut self, frame: F) -> FrameOutput {
        self.track_with(frame, |_, _, _| None)
    }

    /// Tracks one prepared frame whose \[A\] may have been computed ahead of time:
    /// `ahead` is given the previous frame the tracker registers against, the
    /// prediction it starts from and the depth-noise model in use, and returns
    /// [`frame_to_frame`]`(frame, previous, prior)` if it was computed for exactly
    /// those, `None` otherwise (then the tracker computes it). \[A\] depends on
    /// nothing but the two frames, the prior and the settings, so the output is the
    /// same either way, bit for bit.
    pub fn track_with(
        &mut self,
        frame: F,
        ahead: impl FnOnce(&F, Option<&Pose>, DepthNoiseModel) -> Option<MotionResult>,
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
            recovered: false,
            refused_corrections: 0,
            registration: None,
            lost_reason: None,
        };
        match frame.depth_time {
            DepthTime::Turned(_) => self.counters.imu.depth_turned += 1,
            DepthTime::Uncovered => self.counters.imu.depth_unturned += 1,
            DepthTime::Same | DepthTime::NoGyro => {}
        }
        let guess = self.guess.take();
        if self.prev.is_none() {
            self.anchor(frame, Pose::identity(), index);
            self.state = TrackingState::Tracking;
            return out;
        }
        let prior = self.motion_prior(guess, index, frame.timestamp);
        let Some(prev) = self.prev.clone() else {
            unreachable!("checked above")
        };

        // [A] frame to frame, from the identity or the prediction; with keyframe
        // tracking, against the keyframe (the level-1 reference) from the previous
        // frame's pose and the prediction, unless the keyframe is the previous frame.
        let keyframe = self
            .config
            .keyframes
            .then(|| self.refs.first().and_then(|r| r.clone()))
            .flatten()
            .filter(|k| k.index != prev.index);
        let f2f = match &keyframe {
            Some(k) => self.register_keyframe(&frame, k, &prev, prior.as_ref()),
            None => match ahead(&prev.frame, prior.as_ref(), self.motion.depth_noise) {
                Some(r) => r,
                None => {
                    ready(&mut self.finisher, &prev.frame);
                    frame_to_frame(
                        &mut self.estimator,
                        &frame,
                        &prev.frame,
                        prior.as_ref(),
                        &self.motion,
                    )
                }
            },
        };
        out.motion_estimations += 1;
        self.counters.motion_estimations += 1;
        out.frame_to_frame = Some(f2f);
        let predicted = prior.map_or(prev.pose, |p| se3::compose(&prev.pose, &p));
        let dt = frame.timestamp - prev.frame.timestamp;
        // The pose the registration gives and the move from the previous frame.
        let base_pose = keyframe.as_ref().map_or(prev.pose, |k| k.pose);
        let mut registered = se3::compose(&base_pose, &f2f.pose);
        let mut moved = match &keyframe {
            Some(_) => se3::compose(&prev.pose.inverse(), &registered),
            None => f2f.pose,
        };
        let mut reg = f2f;
        let mut believed = f2f.is_ok()
            && believable(
                &self.config,
                &self.spread,
                &mut self.counters,
                &f2f,
                &moved,
                dt,
            );
        // Keyframe tracking, against the previous frame (the keyframe): a registration
        // that went wrong from the start that won the coarsest step is tried once more
        // from the other start alone (the chain keeps its \[A\] as the paper has it).
        if !believed
            && self.config.keyframes
            && keyframe.is_none()
            && let Some(p) = prior
        {
            let other = if f2f.start == 0 { p } else { Pose::identity() };
            let r = self
                .estimator
                .motion(&frame, &prev.frame, &other, &self.motion);
            out.motion_estimations += 1;
            self.counters.motion_estimations += 1;
            if r.is_ok()
                && believable(
                    &self.config,
                    &self.spread,
                    &mut self.counters,
                    &r,
                    &r.pose,
                    dt,
                )
            {
                believed = true;
                reg = r;
                out.frame_to_frame = Some(r);
                registered = se3::compose(&prev.pose, &r.pose);
                moved = r.pose;
            }
        }
        if believed
            && keyframe.is_some()
            && self.config.motion.weighting == Weighting::Bivariate
            && f2f.scale.is_some_and(|s| {
                self.spread
                    .is_wider(&s, self.config.keyframe_max_spread_growth)
            })
        {
            self.counters.keyframe_spread_refusals += 1;
            believed = false;
        }
        // Keyframe tracking: the keyframe did not register; try the previous frame,
        // which then becomes the new keyframe.
        let mut fell_back = false;
        if !believed
            && keyframe.is_some()
            && let Some(r) = self.keyframe_fallback(&frame, &prev, prior.as_ref(), dt, &mut out)
        {
            fell_back = true;
            believed = true;
            reg = r;
            out.frame_to_frame = Some(r);
            registered = se3::compose(&prev.pose, &r.pose);
            moved = r.pose;
        }
        let mut pose = if believed {
            if let Some(s) = &reg.scale {
                self.spread.record(s);
            }
            if reg.start > 0 {
                self.counters.predicted_starts += 1;
            }
            if self.config.motion.depth_noise == DepthNoiseModel::Fitted
                && let Some(m) = self.noise.record(&reg.depth_spread)
            {
                self.motion.depth_noise = m;
                self.correcting.depth_noise = m;
                self.counters.noise_refits += 1;
            }
            // With a gyro: its rotation fused in (`Config::imu_fusion`), its bias
            // learnt from the visual motion.
            if let Some(m) = self.gyro_step(index, &moved, &reg) {
                moved = m;
                registered = se3::compose(&prev.pose, &m);
            }
            // A velocity only from consecutive frames: after a lost frame, [A] spans
            // the gap and the next prediction starts afresh from the identity (which is
            // also what the pipeline's filter stage can know without the tracker).
            self.velocity = (prev.index + 1 == index).then(|| Velocity {
                index,
                motion: moved,
                dt: frame.timestamp - prev.frame.timestamp,
            });
            registered
        } else {
            self.velocity = None;
            let skip = keyframe.as_ref().map(|k| k.index);
            match self.recover(&frame, &predicted, dt, skip, &mut out) {
                Some(p) => p,
                None => {
                    let speed_ok = plausible_speed(&moved, dt, self.config.max_speed_m_s);
                    out.lost_reason = Some(LostReason::of(frame.valid_depth, &reg, speed_ok));
                    return self.lose(frame, index, out);
                }
            }
        };
        if believed {
            out.registration = Some(reg);
        }
        self.lost_run = 0;
        self.state = TrackingState::Tracking;
        let add = if believed && self.config.fuse_corrections {
            reg.information.try_inverse()
        } else {
            None
        };
        let new_keyframe = self.config.keyframes
            && self.keyframe_update(
                &frame,
                &prev,
                prior.as_ref(),
                &KeyframeStep {
                    index,
                    dt,
                    keyframe: keyframe.as_ref(),
                    reg: &reg,
                    believed,
                    fell_back,
                    add,
                },
                &mut pose,
                &mut out,
            );
        if !self.config.keyframes {
            for c in &mut self.chain {
                *c = match (*c, add) {
                    (Some(c), Some(a)) => Some(chain_step(&c, &f2f.pose, &a)),
                    _ => None,
                };
            }
        }

        if believed && !self.config.keyframes {
            self.refine(&frame, index, &mut pose, &mut out);
        }

        // [B], [C], ...: correct against each level's reference while the motion
        // accumulated since it is large enough. A correction that fails, or lands
        // implausibly far from its guess, changes nothing and ends the climb. With
        // keyframe tracking level 1 needs no correction (the frame is registered
        // against its reference): a new keyframe starts the climb at level 2.
        let mut became = 0usize;
        let first = match (self.config.keyframes, new_keyframe) {
            (false, _) => 0,
            (true, true) => {
                self.counters.references[0] += 1;
                self.refused[0] = 0;
                became = 1;
                1
            }
            (true, false) => self.config.reference_levels.len(),
        };
        for (k, level) in self.config.reference_levels.iter().enumerate().skip(first) {
            let Some(reference) = &self.refs[k] else {
                break;
            };
            let accumulated = se3::compose(&reference.pose.inverse(), &pose);
            if !comp(&accumulated, level) {
                break;
            }
            if self.refused[k] >= MAX_REFUSED_CORRECTIONS {
                // The reference is out of reach: replace it without a correction.
                self.counters.stale_references += 1;
                self.counters.references[k] += 1;
                self.refused[k] = 0;
                became = k + 1;
                continue;
            }
            ready(&mut self.finisher, &reference.frame);
            let r = self
                .estimator
                .motion(&frame, &reference.frame, &accumulated, &self.correcting);
            out.motion_estimations += 1;
            self.counters.motion_estimations += 1;
            if !r.is_ok() {
                self.counters.failed_corrections += 1;
            } else if correction_distance(&accumulated, &r) > self.config.max_correction_distance {
                self.counters.rejected_corrections += 1;
            } else {
                pose = se3::compose(&reference.pose, &r.pose);
                if self.config.fuse_corrections
                    && let Some(chain) = &self.chain[k]
                    && let Some(fused) = fuse_correction(&accumulated, chain, &r)
                {
                    pose = se3::compose(&reference.pose, &fused);
                }
                self.counters.references[k] += 1;
                self.refused[k] = 0;
                became = k + 1;
                continue;
            }
            self.refused[k] += 1;
            out.refused_corrections += 1;
            break;
        }
        for c in &mut self.chain[..became] {
            *c = Some(Matrix6::zeros());
        }
        if became > 0 {
            // A new reference is finished now, before the next frame and before the
            // point cloud read it.
            ready(&mut self.finisher, &frame);
        }
        for (r, refused) in self.refs[..became].iter_mut().zip(&mut self.refused) {
            *r = Some(Kept {
                frame: frame.clone(),
                pose,
                index,
            });
            *refused = 0;
        }
        self.prev = Some(Kept { frame, pose, index });
        out.pose = pose;
        out.reference_levels = became as u8;
        out
    }

    /// Between corrections, every [`Config::refine_every`]th frame after the level-1
    /// reference is registered against it, seeded with its chained `pose`, and the
    /// result fused into `pose` like a correction's, the chain's covariance becoming
    /// the fused one's; the frame does not become a reference. Nothing happens when a
    /// correction is due (it registers against the same reference), without a chain
    /// to fuse with, or when the registration fails or lands implausibly far.
    fn refine(&mut self, frame: &F, index: u64, pose: &mut Pose, out: &mut FrameOutput) {
        let every = u64::from(self.config.refine_every);
        let (Some(reference), Some(chain), Some(level)) = (
            &self.refs.first().and_then(|r| r.as_ref()),
            self.chain.first().copied().flatten(),
            self.config.reference_levels.first(),
        ) else {
            return;
        };
        let age = index - reference.index;
        if every == 0 || age < 2 || !age.is_multiple_of(every) {
            return;
        }
        let accumulated = se3::compose(&reference.pose.inverse(), pose);
        if comp(&accumulated, level) {
            return;
        }
        ready(&mut self.finisher, &reference.frame);
        let r = self
            .estimator
            .motion(frame, &reference.frame, &accumulated, &self.correcting);
        out.motion_estimations += 1;
        self.counters.motion_estimations += 1;
        self.counters.refinements += 1;
        let fused = (r.is_ok()
            && correction_distance(&accumulated, &r) <= self.config.max_correction_distance)
            .then(|| {
                let fused = fuse_correction(&accumulated, &chain, &r)?;
                let cr = r.information.try_inverse()?;
                // (Σ_c⁻¹ + Σ_r⁻¹)⁻¹ = Σ_c (Σ_c + Σ_r)⁻¹ Σ_r.
                let post = chain * (cr + chain).try_inverse()? * cr;
                Some((fused, post))
            })
            .flatten();
        match fused {
            Some((fused, post)) => {
                self.chain[0] = Some(post);
                *pose = se3::compose(&reference.pose, &fused);
            }
            None => self.counters.refused_refinements += 1,
        }
    }
}
