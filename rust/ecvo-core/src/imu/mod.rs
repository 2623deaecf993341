//! Gyroscope-aided tracking (issue 47): a rotation prior for \[A\] from the gyroscope.
//!
//! The caller pushes gyroscope samples ([`GyroSample`]: seconds on the IMU's clock,
//! rad/s in the IMU's frame) in time order beside the frames
//! ([`crate::Odometry::push_imu`], [`crate::Tracker::push_imu`]). For each frame the
//! tracker integrates the samples between the previous frame's time and this one's
//! (both moved onto the IMU's clock by [`ImuCalibration::time_offset`]), less the
//! estimated bias, turns the rotation into the camera's frame by
//! [`ImuCalibration::camera_from_imu`], and starts \[A\] from it (with the
//! constant-velocity prediction's translation) besides the identity: the better start
//! at the coarsest step goes on, as with [`crate::Tracker::set_guess`]. Each believed
//! \[A\] between consecutive frames then corrects the gyro's bias estimate (a Kalman
//! filter on the three bias components, [`bias`]).
//!
//! - Samples are kept in a fixed ring ([`GyroRing`], [`RING_CAPACITY`] samples,
//!   allocated once at the first push): no allocation per frame.
//! - A batch with a non-finite value is refused whole with an error
//!   ([`crate::Error::BadImuSample`]); a sample not after the last one accepted is
//!   dropped and counted ([`ImuCounters::refused`]), never an error: sensor streams
//!   repeat and reorder.
//! - A frame whose interval the samples do not cover (late: the newest sample ends
//!   before the frame; missing: none that early, or a hole longer than
//!   [`MAX_SAMPLE_GAP_S`]) is tracked without the IMU, as if there were none, and
//!   counted ([`ImuCounters::late`], [`ImuCounters::missing`]).
//! - With no sample ever pushed nothing changes: the poses are those of a tracker
//!   without an IMU, bit for bit.

pub mod bias;
pub mod depth_time;
mod gyro;
pub mod integrate;
mod ring;

pub use depth_time::{DepthClock, DepthTime};
pub use gyro::{Gyro, MIN_GYRO_SIGMA_RAD};
pub use integrate::{Coverage, integrate};
pub use ring::GyroRing;

use nalgebra::UnitQuaternion;

use crate::error::{Error, Result};

/// Samples the tracker keeps: 2.5 s at 400 Hz, 32 KiB. A frame interval longer than
/// what the ring holds is tracked without the IMU (counted as missing).
pub const RING_CAPACITY: usize = 1024;

/// The longest hole between two samples (and the longest stretch past the newest or
/// before the oldest sample) the integration bridges, seconds: a phone gyroscope
/// samples at 100-500 Hz, so a longer hole is lost samples.
pub const MAX_SAMPLE_GAP_S: f64 = 0.025;

/// The gyro's white noise density assumed when the calibration does not say,
/// rad/s/√Hz (0.007 °/s/√Hz, a phone IMU's datasheet figure).
pub const DEFAULT_GYRO_NOISE_DENSITY: f64 = 0.007 * std::f64::consts::PI / 180.0;

/// The gyro bias random walk assumed when the calibration does not say,
/// rad/s/√s (about 0.0008 °/s/√s).
pub const DEFAULT_GYRO_BIAS_RANDOM_WALK: f64 = 1.4e-5;

/// One gyroscope sample.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GyroSample {
    /// Seconds on the IMU's clock (see [`ImuCalibration::time_offset`]).
    pub t: f64,
    /// Angular velocity in the IMU's frame, rad/s.
    pub w: [f64; 3],
}

impl GyroSample {
    /// Whether its time and rates are finite.
    pub fn is_finite(&self) -> bool {
        self.t.is_finite() && self.w.iter().all(|x| x.is_finite())
    }
}

/// Checks a batch of samples for non-finite values; the error names the first bad
/// sample.
pub fn check_finite(samples: &[GyroSample]) -> Result<()> {
    match samples.iter().position(|s| !s.is_finite()) {
        None => Ok(()),
        Some(i) => Err(Error::BadImuSample(format!(
            "sample {i} of the batch (t {}, w {:?}) is not finite; the batch was not taken",
            samples[i].t, samples[i].w
        ))),
    }
}

/// How the IMU sits against the camera, in space and in time, and how noisy its
/// gyroscope is. The default is an IMU aligned with the camera on the frames' clock,
/// with the default noise figures.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImuCalibration {
    /// The rotation taking a vector in the IMU's frame into the camera's frame
    /// (`w_camera = camera_from_imu * w_imu`). The camera's frame is ecvo's: x right,
    /// y down, z forward.
    pub camera_from_imu: UnitQuaternion<f64>,
    /// Seconds to add to an IMU timestamp to put it on the frames' clock:
    /// `t_frames = t_imu + time_offset`. A gyro sample stamped `t` was taken at the
    /// same moment as a frame stamped `t + time_offset`.
    pub time_offset: f64,
    /// The gyro's white noise density, rad/s/√Hz ([`DEFAULT_GYRO_NOISE_DENSITY`] if
    /// `None`).
    pub gyro_noise_density: Option<f64>,
    /// The gyro's bias random walk, rad/s/√s ([`DEFAULT_GYRO_BIAS_RANDOM_WALK`] if
    /// `None`).
    pub gyro_bias_random_walk: Option<f64>,
}

impl Default for ImuCalibration {
    fn default() -> Self {
        ImuCalibration {
            camera_from_imu: UnitQuaternion::identity(),
            time_offset: 0.0,
            gyro_noise_density: None,
            gyro_bias_random_walk: None,
        }
    }
}

impl ImuCalibration {
    /// Checks every field: a finite unit rotation, a time offset within ±1 s, and
    /// finite non-negative noise figures.
    pub fn validate(&self) -> Result<()> {
        let bad = |field: &'static str, why: String| Err(Error::InvalidConfig { field, why });
        let q = self.camera_from_imu.quaternion();
        if !q.coords.iter().all(|x| x.is_finite()) || (q.norm() - 1.0).abs() > 1e-6 {
            return bad(
                "imu.camera_from_imu",
                format!("{:?} is not a finite unit quaternion", q.coords.as_slice()),
            );
        }
        if !(self.time_offset.abs() <= 1.0) {
            return bad(
                "imu.time_offset",
                format!("{} s is not within ±1 s", self.time_offset),
            );
        }
        for (field, v) in [
            ("imu.gyro_noise_density", self.gyro_noise_density),
            ("imu.gyro_bias_random_walk", self.gyro_bias_random_walk),
        ] {
            if let Some(v) = v
                && !(v >= 0.0 && v.is_finite())
            {
                return bad(field, format!("{v} is not finite and non-negative"));
            }
        }
        Ok(())
    }

    /// The gyro's white noise density in use, rad/s/√Hz.
    pub fn noise_density(&self) -> f64 {
        self.gyro_noise_density
            .unwrap_or(DEFAULT_GYRO_NOISE_DENSITY)
    }

    /// The gyro's bias random walk in use, rad/s/√s.
    pub fn bias_random_walk(&self) -> f64 {
        self.gyro_bias_random_walk
            .unwrap_or(DEFAULT_GYRO_BIAS_RANDOM_WALK)
    }
}

/// What became of the IMU's samples and of its priors (part of
/// [`crate::Counters`]). All zero when no sample was ever pushed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ImuCounters {
    /// Samples taken.
    pub samples: u64,
    /// Samples dropped because they were not after the last one taken.
    pub refused: u64,
    /// Samples lost before the tracker read them (the pipeline's inbox overflowed:
    /// the tracker was further behind than [`RING_CAPACITY`]-odd samples).
    pub dropped: u64,
    /// Frames whose \[A\] started from a gyro prior.
    pub priors: u64,
    /// Frames tracked without the IMU because the newest sample ended before the
    /// frame (by more than [`MAX_SAMPLE_GAP_S`]).
    pub late: u64,
    /// Frames tracked without the IMU because the samples did not reach back to the
    /// previous frame or had a hole longer than [`MAX_SAMPLE_GAP_S`].
    pub missing: u64,
    /// Believed \[A\]s that corrected the bias estimate.
    pub bias_updates: u64,
    /// Believed \[A\]s whose rotation disagreed with the gyro beyond the filter's gate
    /// (a misregistration or a bad calibration): the bias was left alone.
    pub bias_outliers: u64,
    /// Frames whose depth was turned to their intensity's time by the gyro
    /// ([`depth_time`]).
    pub depth_turned: u64,
    /// Frames whose depth and intensity times differ but whose depth was left as it
    /// is: the samples did not cover the interval, or it was longer than
    /// [`depth_time::MAX_DEPTH_TIME_GAP_S`].
    pub depth_unturned: u64,
}
