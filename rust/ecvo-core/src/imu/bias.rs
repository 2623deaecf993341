//! The gyro's bias, estimated online from the rotations the tracker believes: a
//! Kalman filter on the three bias components (in the IMU's frame).
//!
//! Over a frame interval of `dt` seconds the gyro, less the bias estimate `b̂`, says
//! the camera rotated by `R_g`; the believed \[A\] says `R_v`. To first order
//! `Log(R_gᵀ R_v) = (b̂ − b) dt` (in the IMU's frame), so each interval measures the
//! bias with the noise of the visual rotation over `dt²` plus the gyro's white noise
//! over `dt`. Between intervals the bias walks ([`super::ImuCalibration`]'s random
//! walk). A measurement further than the gate from the estimate (a misregistration)
//! is left out.

use nalgebra::{Matrix3, Vector3};

/// The bias's prior spread, rad/s: a phone gyroscope's turn-on bias is within
/// 0.5-3 °/s.
pub const INITIAL_BIAS_SIGMA: f64 = 3.0 * std::f64::consts::PI / 180.0;

/// The least standard deviation granted to a visual rotation, radians (0.29°): the
/// registration's information matrix treats every pixel as independent, which they
/// are not, so its covariance is far too small on its own. The frame-to-frame
/// rotation error of keyframe tracking against the ground truth of fr1/xyz and
/// fr1/desk (half size) is 0.3° and 0.6° RMS: with a floor of 1 mrad (0.06°) the gate
/// refused 330 of 791 frames of fr1/xyz and the estimate settled 8σ off the simulated
/// gyro's bias (0.012 rad/s about x); with 5 mrad, 1 of 791, and within 1σ
/// (`docs/imu.md`).
pub const MIN_VISUAL_SIGMA_RAD: f64 = 5e-3;

/// How many times the registration's own rotation covariance is counted.
pub const VISUAL_COVARIANCE_INFLATION: f64 = 10.0;

/// The gate on a measurement's squared Mahalanobis distance (χ² with 3 degrees of
/// freedom at 99.9 % is 16.3).
pub const GATE: f64 = 16.3;

/// The bias estimate and its covariance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BiasFilter {
    /// The estimate, rad/s in the IMU's frame.
    pub bias: Vector3<f64>,
    /// Its covariance, (rad/s)².
    pub covariance: Matrix3<f64>,
}

impl Default for BiasFilter {
    fn default() -> Self {
        BiasFilter {
            bias: Vector3::zeros(),
            covariance: Matrix3::identity() * INITIAL_BIAS_SIGMA.powi(2),
        }
    }
}

impl BiasFilter {
    /// Lets the bias walk for `dt` seconds at `random_walk` rad/s/√s.
    pub fn predict(&mut self, dt: f64, random_walk: f64) {
        if dt > 0.0 && dt.is_finite() {
            self.covariance += Matrix3::identity() * (random_walk * random_walk * dt);
        }
    }

    /// Takes the residual rotation `r = Log(R_gᵀ R_v)` of an interval of `dt` seconds
    /// (rotation vector in the IMU's frame), whose visual rotation has variance
    /// `visual_var` rad² per axis, with the gyro's `noise_density` rad/s/√Hz. Returns
    /// whether it passed the gate (and was taken).
    pub fn update(
        &mut self,
        r: &Vector3<f64>,
        dt: f64,
        visual_var: f64,
        noise_density: f64,
    ) -> bool {
        if !(dt > 0.0 && dt.is_finite() && r.iter().all(|x| x.is_finite())) {
            return false;
        }
        // The bias the interval measures, minus the estimate.
        let y = -r / dt;
        let var = visual_var / (dt * dt) + noise_density * noise_density / dt;
        let s = self.covariance + Matrix3::identity() * var;
        let Some(s_inv) = s.try_inverse() else {
            return false;
        };
        if (y.transpose() * s_inv * y)[0] > GATE {
            return false;
        }
        let k = self.covariance * s_inv;
        self.bias += k * y;
        let i_k = Matrix3::identity() - k;
        // Joseph form: stays symmetric and positive.
        self.covariance = i_k * self.covariance * i_k.transpose() + k * k.transpose() * var;
        true
    }
}
