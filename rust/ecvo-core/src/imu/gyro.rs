//! [`Gyro`]: what the tracker keeps of the IMU (its samples, its calibration, the
//! bias estimate) and the prior it gives each frame's \[A\].

use nalgebra::{Isometry3, Matrix6, Translation3, UnitQuaternion, Vector3};

use super::bias::{BiasFilter, MIN_VISUAL_SIGMA_RAD, VISUAL_COVARIANCE_INFLATION};
use super::{
    Coverage, GyroRing, GyroSample, ImuCalibration, ImuCounters, RING_CAPACITY, check_finite,
    integrate,
};
use crate::Pose;
use crate::error::Result;

/// The gyro's rotation over the interval of the frame being tracked.
#[derive(Clone, Copy, Debug)]
struct Pending {
    /// The frame's index.
    index: u64,
    /// `R_{p←c}` in the camera's frame, bias taken off.
    rotation: UnitQuaternion<f64>,
    /// The interval, seconds.
    dt: f64,
}

/// The tracker's IMU: a ring of samples, the calibration and the bias estimate.
#[derive(Clone, Debug)]
pub struct Gyro {
    calibration: ImuCalibration,
    ring: GyroRing,
    bias: BiasFilter,
    pending: Option<Pending>,
}

impl Gyro {
    /// An IMU with `calibration` and no sample yet (nothing allocated).
    pub fn new(calibration: ImuCalibration) -> Self {
        Gyro {
            calibration,
            ring: GyroRing::new(RING_CAPACITY),
            bias: BiasFilter::default(),
            pending: None,
        }
    }

    /// Takes `samples` in time order: refuses the whole batch, taking none, if one
    /// has a non-finite value ([`crate::Error::BadImuSample`]); drops and counts
    /// (`refused`) a sample whose time is not after the last one taken.
    pub fn push(&mut self, samples: &[GyroSample], counters: &mut ImuCounters) -> Result<()> {
        check_finite(samples)?;
        for s in samples {
            if self.ring.last().is_some_and(|l| s.t <= l.t) {
                counters.refused += 1;
                continue;
            }
            self.ring.push(*s);
            counters.samples += 1;
        }
        Ok(())
    }

    /// Whether any sample was ever taken: without one, the tracker is the same as
    /// without an IMU.
    pub fn active(&self) -> bool {
        self.ring.pushed() > 0
    }

    /// The calibration in use.
    pub fn calibration(&self) -> &ImuCalibration {
        &self.calibration
    }

    /// The bias estimate (rad/s, in the IMU's frame) and its covariance.
    pub fn bias(&self) -> &BiasFilter {
        &self.bias
    }

    /// The samples kept.
    pub fn samples(&self) -> &GyroRing {
        &self.ring
    }

    /// The gyro's rotation `R_{p←c}` in the camera's frame, bias taken off, for a
    /// frame stamped `t_cur` after a previous frame stamped `t_prev` (frames' clock),
    /// or why the samples cannot say.
    pub fn rotation_between(
        &self,
        t_prev: f64,
        t_cur: f64,
    ) -> std::result::Result<UnitQuaternion<f64>, Coverage> {
        let off = self.calibration.time_offset;
        let q = integrate(&self.ring, t_prev - off, t_cur - off, &self.bias.bias)?;
        let c = self.calibration.camera_from_imu;
        let mut r = c * q * c.inverse();
        r.renormalize();
        Ok(r)
    }

    /// The prior of frame `index`'s \[A\] (`T_{c,p}`): the gyro's rotation over the
    /// frame's interval with the translation of `cv` (the constant-velocity
    /// prediction) if any, or `None` (not active, or the samples do not cover the
    /// interval: counted late or missing). Lets the bias estimate walk over the
    /// interval.
    pub fn prior(
        &mut self,
        index: u64,
        t_prev: f64,
        t_cur: f64,
        cv: Option<&Pose>,
        counters: &mut ImuCounters,
    ) -> Option<Pose> {
        self.pending = None;
        if !self.active() {
            return None;
        }
        let dt = t_cur - t_prev;
        self.bias.predict(dt, self.calibration.bias_random_walk());
        match self.rotation_between(t_prev, t_cur) {
            Ok(rotation) => {
                self.pending = Some(Pending {
                    index,
                    rotation,
                    dt,
                });
                counters.priors += 1;
                let t = cv.map_or_else(Vector3::zeros, |p| p.translation.vector);
                Some(Isometry3::from_parts(Translation3::from(t), rotation))
            }
            Err(Coverage::Late) => {
                counters.late += 1;
                None
            }
            Err(Coverage::Missing | Coverage::Empty) => {
                counters.missing += 1;
                None
            }
        }
    }

    /// Corrects the bias from frame `index`'s believed motion from the previous frame
    /// (`moved`, `T_{c,p}`) and its registration's information matrix, if the gyro
    /// gave that frame a prior.
    pub fn learn(
        &mut self,
        index: u64,
        moved: &Pose,
        information: &Matrix6<f64>,
        counters: &mut ImuCounters,
    ) {
        let Some(p) = self.pending.take().filter(|p| p.index == index) else {
            return;
        };
        let c = self.calibration.camera_from_imu;
        let r_cam = (p.rotation.inverse() * moved.rotation).scaled_axis();
        let r = c.inverse() * r_cam;
        let own = information.try_inverse().map_or(f64::INFINITY, |cov| {
            cov.fixed_view::<3, 3>(3, 3).trace() / 3.0 * VISUAL_COVARIANCE_INFLATION
        });
        let var = own.max(MIN_VISUAL_SIGMA_RAD * MIN_VISUAL_SIGMA_RAD);
        if !var.is_finite() {
            return;
        }
        if self
            .bias
            .update(&r, p.dt, var, self.calibration.noise_density())
        {
            counters.bias_updates += 1;
        } else {
            counters.bias_outliers += 1;
        }
    }
}

/// The least standard deviation granted to the gyro's rotation over a frame
/// interval, radians (0.03°): what its calibration (rotation, time offset, scale)
/// leaves besides the white noise and the bias.
pub const MIN_GYRO_SIGMA_RAD: f64 = 5e-4;

impl Gyro {
    /// The variance of the gyro's rotation over an interval of `dt` seconds, per
    /// axis, rad²: its white noise integrated over the interval and the bias
    /// estimate's spread times the interval, floored at [`MIN_GYRO_SIGMA_RAD`].
    pub fn rotation_variance(&self, dt: f64) -> f64 {
        let nd = self.calibration.noise_density();
        let bias_var = self.bias.covariance.trace() / 3.0;
        (nd * nd * dt + bias_var * dt * dt).max(MIN_GYRO_SIGMA_RAD.powi(2))
    }

    /// With [`crate::Config::imu_prior_term`]: the information (1/rad²) of the prior
    /// term the gyro's rotation over frame `index`'s interval adds to `MOTION`'s
    /// normal equations ([`crate::MotionConfig::rotation_prior_information`]), or
    /// 0 without a gyro prior for the frame. The inverse of
    /// [`Gyro::rotation_variance`], times the inflation the registration's own
    /// covariance gets everywhere else (its pixels' errors are not independent: the
    /// images' `JᵀWJ` overstates their information about as much), so that the two
    /// are weighed as [`Gyro::fuse`] weighs them.
    pub fn prior_information(&self, index: u64) -> f64 {
        self.pending.filter(|p| p.index == index).map_or(0.0, |p| {
            VISUAL_COVARIANCE_INFLATION / self.rotation_variance(p.dt)
        })
    }

    /// With [`crate::Config::imu_fusion`]: frame `index`'s registration `T_{c,p}`
    /// (`moved`, with its information matrix) fused with the gyro's rotation over the
    /// interval, each weighed by its covariance (the registration's inflated as for
    /// the bias; the gyro's from its white noise, the bias estimate's spread and
    /// [`MIN_GYRO_SIGMA_RAD`]): a Kalman update of the pose by a rotation
    /// measurement, in the left tangent of the registration's `T_{p,c}` (the
    /// translation follows through the cross-covariance). `None` without a gyro prior
    /// for the frame or a usable covariance.
    pub fn fuse(&self, index: u64, moved: &Pose, information: &Matrix6<f64>) -> Option<Pose> {
        let p = self.pending.filter(|p| p.index == index)?;
        let cov = information.try_inverse()? * VISUAL_COVARIANCE_INFLATION;
        let var = self.rotation_variance(p.dt);
        // The estimator's T = moved⁻¹, perturbed on the left; the gyro says its
        // rotation is p.rotation⁻¹.
        let t = moved.inverse();
        let omega = (t.rotation * p.rotation).scaled_axis();
        let s = cov.fixed_view::<3, 3>(3, 3) + nalgebra::Matrix3::identity() * var;
        let gain = cov.fixed_view::<6, 3>(0, 3) * s.try_inverse()?;
        let xi = gain * (-omega);
        let fused = crate::se3::compose(&crate::se3::exp(&xi), &t).inverse();
        crate::se3::is_finite(&fused).then_some(fused)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Translation3;

    /// A registration 1° off the gyro's rotation, with a rotation covariance far wider
    /// than the gyro's, is pulled onto the gyro's rotation; one far more certain is
    /// left nearly where it is.
    #[test]
    fn fusion_weighs_the_registration_against_the_gyro() {
        let mut g = Gyro::new(ImuCalibration::default());
        let mut c = ImuCounters::default();
        let w = [0.0, 2.0, 0.0];
        let samples: Vec<GyroSample> = (0..40)
            .map(|k| GyroSample {
                t: k as f64 * 0.005,
                w,
            })
            .collect();
        g.push(&samples, &mut c).unwrap();
        let truth = UnitQuaternion::from_scaled_axis(Vector3::new(0.0, 0.1, 0.0));
        let cv = Pose::from_parts(Translation3::new(0.01, 0.0, 0.0), Default::default());
        g.prior(1, 0.05, 0.1, Some(&cv), &mut c).unwrap();
        let off = UnitQuaternion::from_scaled_axis(Vector3::new(1f64.to_radians(), 0.0, 0.0));
        let moved = Pose::from_parts(Translation3::new(0.01, 0.0, 0.0), off * truth);
        let loose = Matrix6::identity() * 1e3;
        let fused = g.fuse(1, &moved, &loose).unwrap();
        assert!(fused.rotation.angle_to(&truth) < 0.05f64.to_radians());
        let tight = Matrix6::identity() * 1e12;
        let kept = g.fuse(1, &moved, &tight).unwrap();
        assert!(kept.rotation.angle_to(&moved.rotation) < 0.01f64.to_radians());
        assert!(g.fuse(2, &moved, &loose).is_none(), "no prior for frame 2");
    }
}
