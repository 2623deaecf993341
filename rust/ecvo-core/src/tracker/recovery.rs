//! When \[A\] fails: recovery against the kept references, losing the frame, and
//! anchoring afresh after too many lost frames in a row.

use std::ops::Deref;

use nalgebra::Matrix6;

use super::{FrameOutput, Kept, Tracker, TrackingState, believable, ready};
use crate::Pose;
use crate::prepare::PreparedFrame;
use crate::se3;

impl<F: Clone + Deref<Target = PreparedFrame>> Tracker<F> {
    /// \[A\] failed: registers the frame against the kept references (level 1 first,
    /// each frame once), seeded with the predicted pose. Returns the pose found, if
    /// it is a believable move from the previous frame, `dt` seconds before.
    pub(super) fn recover(
        &mut self,
        frame: &F,
        predicted: &Pose,
        dt: f64,
        tried_keyframe: Option<u64>,
        out: &mut FrameOutput,
    ) -> Option<Pose> {
        let prev_index = self.prev.as_ref().map(|p| p.index);
        let prev_pose = self.prev.as_ref().map_or(Pose::identity(), |p| p.pose);
        for k in 0..self.refs.len() {
            let Some(reference) = &self.refs[k] else {
                continue;
            };
            // Each frame once: not the previous frame, not the keyframe already tried,
            // not a lower level's reference that is the same frame.
            let seen = Some(reference.index) == prev_index
                || Some(reference.index) == tried_keyframe
                || self.refs[..k]
                    .iter()
                    .any(|r| r.as_ref().is_some_and(|r| r.index == reference.index));
            if seen {
                continue;
            }
            let init = se3::compose(&reference.pose.inverse(), predicted);
            ready(&mut self.finisher, &reference.frame);
            let r = self
                .estimator
                .motion(frame, &reference.frame, &init, &self.correcting);
            out.motion_estimations += 1;
            self.counters.motion_estimations += 1;
            if r.is_ok() {
                let pose = se3::compose(&reference.pose, &r.pose);
                let moved = se3::compose(&prev_pose.inverse(), &pose);
                if !believable(
                    &self.config,
                    &self.spread,
                    &mut self.counters,
                    &r,
                    &moved,
                    dt,
                ) {
                    continue;
                }
                self.counters.recovered_frames += 1;
                out.recovered = true;
                out.registration = Some(r);
                return Some(pose);
            }
        }
        None
    }

    /// The frame did not register: it keeps the last good pose; after too many in a
    /// row the tracker starts afresh at a frame good enough to anchor on.
    pub(super) fn lose(&mut self, frame: F, index: u64, mut out: FrameOutput) -> FrameOutput {
        self.keyframe_chain = None;
        for c in &mut self.chain {
            *c = None;
        }
        let last_pose = self.prev.as_ref().map_or(Pose::identity(), |p| p.pose);
        self.counters.lost_frames += 1;
        self.lost_run += 1;
        out.pose = last_pose;
        out.state = TrackingState::Lost;
        self.state = TrackingState::Lost;
        if self.lost_run > self.config.max_lost_frames && self.can_anchor(&frame) {
            // The old frames are out of reach: start afresh here at the last good pose.
            self.anchor(frame, last_pose, index);
            self.counters.reanchors += 1;
            self.lost_run = 0;
            out.reanchored = true;
        }
        out
    }

    /// True when `frame` has enough depth and texture to anchor tracking on.
    pub fn can_anchor(&self, frame: &PreparedFrame) -> bool {
        let n = self.config.camera.pixels().max(1) as f64;
        frame.valid_depth as f64 >= self.config.min_anchor_depth_fraction * n
            && frame.textured_pixels as f64 >= self.config.min_anchor_texture_fraction * n
    }

    /// Makes `frame` the previous frame and the reference at every level.
    pub(super) fn anchor(&mut self, frame: F, pose: Pose, index: u64) {
        ready(&mut self.finisher, &frame);
        self.keyframe_chain = Some(Matrix6::zeros());
        for c in &mut self.chain {
            *c = Some(Matrix6::zeros());
        }
        for r in &mut self.refs {
            *r = Some(Kept {
                frame: frame.clone(),
                pose,
                index,
            });
        }
        for r in &mut self.refused {
            *r = 0;
        }
        self.velocity = None;
        self.spread.clear();
        self.prev = Some(Kept { frame, pose, index });
    }
}
