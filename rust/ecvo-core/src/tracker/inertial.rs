//! The tracker's side of the IMU ([`crate::imu`]): taking samples, and the prior of
//! \[A\] (the gyro's, else the constant-velocity prediction).

use std::ops::Deref;

use super::Tracker;
use crate::Pose;
use crate::error::Result;
use crate::imu::{Gyro, GyroSample};
use crate::prepare::PreparedFrame;

impl<F: Clone + Deref<Target = PreparedFrame>> Tracker<F> {
    /// Takes gyroscope samples, in time order, for the frames tracked after this
    /// call ([`crate::imu`]): a batch with a non-finite value is refused whole
    /// ([`crate::Error::BadImuSample`]); a sample not after the last one taken is
    /// dropped and counted (`Counters::imu.refused`). Samples that come too late for
    /// a frame leave it tracked without the IMU, counted, never an error.
    pub fn push_imu(&mut self, samples: &[GyroSample]) -> Result<()> {
        self.gyro.push(samples, &mut self.counters.imu)
    }

    /// After frame `index`'s believed registration `reg`, by which the camera moved
    /// `moved` from the previous frame: with [`crate::Config::imu_fusion`], that
    /// motion fused with the gyro's rotation ([`Gyro::fuse`]); and the bias learnt
    /// from the visual motion ([`Gyro::learn`]).
    pub(super) fn gyro_step(
        &mut self,
        index: u64,
        moved: &Pose,
        reg: &crate::motion::MotionResult,
    ) -> Option<Pose> {
        let fused = if self.config.imu_fusion {
            self.gyro.fuse(index, moved, &reg.information)
        } else {
            None
        };
        // The bias is learnt from the images' own motion: the registration's, pulled
        // towards the gyro by the prior term, would count the gyro twice.
        let seen = reg.images_pose.map_or(*moved, |p| {
            crate::se3::compose(moved, &crate::se3::compose(&reg.pose.inverse(), &p))
        });
        self.gyro
            .learn(index, &seen, &reg.information, &mut self.counters.imu);
        fused
    }

    /// Counts `n` samples lost before they reached the tracker (the pipeline's inbox
    /// overflowed).
    pub fn count_imu_dropped(&mut self, n: u64) {
        self.counters.imu.dropped += n;
    }

    /// The IMU's state: samples kept, calibration, bias estimate.
    pub fn gyro(&self) -> &Gyro {
        &self.gyro
    }

    /// What frame `index`, stamped `timestamp`, starts \[A\] from besides the
    /// identity: an outside `guess` ([`Tracker::set_guess`]), else the gyro's
    /// rotation over its interval with the constant-velocity translation, else
    /// (without IMU cover) the constant-velocity prediction alone.
    pub(super) fn motion_prior(
        &mut self,
        guess: Option<Pose>,
        index: u64,
        timestamp: f64,
    ) -> Option<Pose> {
        self.motion.scale_from_last_start = false;
        self.motion.rotation_prior_information = 0.0;
        if guess.is_some() {
            return guess;
        }
        let cv = self.prior_for(timestamp);
        let prev = self.prev.as_ref()?.frame.timestamp;
        let gyro = self
            .gyro
            .prior(index, prev, timestamp, cv.as_ref(), &mut self.counters.imu);
        // The gyro's prior is trusted at the coarsest step: it is compared with the
        // identity at its own scale.
        self.motion.scale_from_last_start = gyro.is_some();
        // With `imu_prior_term`, its rotation is also a prior term in the normal
        // equations of the calls that start from it (their last start).
        if self.config.imu_prior_term {
            self.motion.rotation_prior_information = self.gyro.prior_information(index);
        }
        gyro.or(cv)
    }
}
