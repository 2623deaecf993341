//! Depth turned to the intensity image's time. An RGB-D camera whose depth and colour
//! streams are not triggered together stamps the two images of a frame apart: up to
//! 19 ms in the TUM recordings (`docs/imu.md`), 1° of a 57 °/s pan, 9 pixels at
//! 640x480. Each intensity pixel is then paired with the depth of another ray. With
//! a gyroscope the camera's rotation between the two times is known: over such an
//! interval the camera's translation moves the image far less than its rotation, and
//! a pure rotation moves every pixel by the same homography `K R K⁻¹` whatever its
//! depth, so the depth image can be resampled to the intensity's time before it is
//! prepared ([`crate::Preparer::prepare_turned_into`], `prepare/turn.rs`).
//!
//! The rotation comes from the raw gyro, without the bias estimate (which lives in
//! the tracker, behind the pipeline's filter stage): a turn-on bias of 3 °/s over
//! 20 ms is 0.06°, half a pixel at 640x480. [`DepthClock`] keeps its own ring of the
//! samples pushed, so that the sequential engine and the pipeline compute the same
//! rotation for a frame from the samples pushed before it.

use nalgebra::{UnitQuaternion, Vector3};

use super::{Coverage, GyroRing, GyroSample, ImuCalibration, integrate};

/// Samples [`DepthClock`] keeps: 0.64 s at 400 Hz, 8 KiB, allocated at the first
/// push. The interval it integrates is at most [`MAX_DEPTH_TIME_GAP_S`] back from the
/// newest frame.
pub const DEPTH_CLOCK_CAPACITY: usize = 256;

/// The largest gap between a frame's depth and intensity times that is turned,
/// seconds: the frame readers pair images at most 20 ms apart; beyond 50 ms the
/// frame's depth is left as it is and counted.
pub const MAX_DEPTH_TIME_GAP_S: f64 = 0.05;

/// What became of a frame's depth time ([`crate::PreparedFrame::depth_time`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum DepthTime {
    /// Depth and intensity have the same time (or no depth time was given).
    #[default]
    Same,
    /// The depth was turned by the gyro's rotation between the two times.
    Turned(UnitQuaternion<f64>),
    /// The times differ, but no gyro sample was pushed: the depth was left as it is.
    NoGyro,
    /// The times differ and the samples do not cover the interval (or it is longer
    /// than [`MAX_DEPTH_TIME_GAP_S`]): the depth was left as it is.
    Uncovered,
}

/// Checks a frame's depth timestamp: a non-finite one is refused
/// ([`crate::Error::BadFrame`]), never taken as the intensity's time in silence.
pub fn check_depth_timestamp(depth_timestamp: f64) -> crate::error::Result<()> {
    if depth_timestamp.is_finite() {
        Ok(())
    } else {
        Err(crate::error::Error::BadFrame(format!(
            "depth timestamp {depth_timestamp} is not finite"
        )))
    }
}

/// The raw gyro samples pushed, for the rotation between a frame's depth and
/// intensity times.
#[derive(Clone, Debug)]
pub struct DepthClock {
    calibration: ImuCalibration,
    ring: GyroRing,
}

impl DepthClock {
    /// A clock for an IMU with `calibration`, with no sample yet (nothing allocated).
    pub fn new(calibration: ImuCalibration) -> Self {
        DepthClock {
            calibration,
            ring: GyroRing::new(DEPTH_CLOCK_CAPACITY),
        }
    }

    /// Takes finite `samples` in time order (checked by the caller); one not after
    /// the last one taken is skipped (the tracker counts it).
    pub fn push(&mut self, samples: &[GyroSample]) {
        for s in samples {
            if self.ring.last().is_none_or(|l| s.t > l.t) {
                self.ring.push(*s);
            }
        }
    }

    /// What to do with a frame whose intensity is stamped `intensity_t` and depth
    /// `depth_t` (frames' clock): with a different time, the rotation `R_{d←c}`
    /// taking a ray of the camera at the intensity's time into the camera at the
    /// depth's time, in the camera's frame.
    pub fn depth_time(&self, intensity_t: f64, depth_t: f64) -> DepthTime {
        // Non-finite: refused by the callers ([`check_depth_timestamp`]).
        if depth_t == intensity_t || !depth_t.is_finite() {
            return DepthTime::Same;
        }
        if self.ring.pushed() == 0 {
            return DepthTime::NoGyro;
        }
        if (depth_t - intensity_t).abs() > MAX_DEPTH_TIME_GAP_S {
            return DepthTime::Uncovered;
        }
        let off = self.calibration.time_offset;
        let (a, b) = (
            depth_t.min(intensity_t) - off,
            depth_t.max(intensity_t) - off,
        );
        let q = match integrate(&self.ring, a, b, &Vector3::zeros()) {
            Ok(q) => q,
            Err(Coverage::Late | Coverage::Missing | Coverage::Empty) => {
                return DepthTime::Uncovered;
            }
        };
        // `integrate` gives R_{a←b}: the depth's frame at `a` when it came first.
        let q = if depth_t < intensity_t {
            q
        } else {
            q.inverse()
        };
        let c = self.calibration.camera_from_imu;
        let mut r = c * q * c.inverse();
        r.renormalize();
        DepthTime::Turned(r)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The clock: the same time, no gyro, uncovered and turned, with the turn's sense
    /// following which image came first.
    #[test]
    fn the_clock_says_what_it_can() {
        let mut k = DepthClock::new(ImuCalibration::default());
        assert_eq!(k.depth_time(1.0, 1.0), DepthTime::Same);
        assert_eq!(k.depth_time(1.0, 1.01), DepthTime::NoGyro);
        let w = [0.0, 1.0, 0.0];
        let samples: Vec<GyroSample> = (0..100)
            .map(|i| GyroSample {
                t: 0.5 + i as f64 * 0.005,
                w,
            })
            .collect();
        k.push(&samples);
        // Depth 10 ms after the intensity: the camera turned +0.01 rad about y from
        // the one to the other, so a ray of the intensity camera is at -0.01 rad in
        // the depth camera.
        let DepthTime::Turned(r) = k.depth_time(0.7, 0.71) else {
            panic!("turned")
        };
        let a = r.scaled_axis();
        assert!((a - Vector3::new(0.0, -0.01, 0.0)).norm() < 1e-9, "{a:?}");
        let DepthTime::Turned(r2) = k.depth_time(0.71, 0.70) else {
            panic!("turned")
        };
        assert!(
            (r2.scaled_axis() + a).norm() < 1e-9,
            "the other order turns the other way"
        );
        assert_eq!(
            k.depth_time(0.7, 0.8),
            DepthTime::Uncovered,
            "beyond the gap"
        );
        assert_eq!(
            k.depth_time(5.0, 5.01),
            DepthTime::Uncovered,
            "no samples then"
        );
    }
}
