//! Simulated IMUs (issue 47): a gyroscope and an accelerometer riding on the camera
//! of any trajectory given as a function of time, with a phone IMU's white noise,
//! turn-on bias and bias random walk, a camera-IMU rotation and a time offset; and
//! [`SplinePath`], a smooth cumulative cubic B-spline through sampled poses (a motion
//! capture's ground truth), whose derivatives feed the same simulation.
//!
//! These are simulated gyroscopes: the rates are the trajectory's exact derivatives
//! (central differences of the analytic or spline pose, accurate to about 1e-9 rad/s)
//! plus modelled noise, not a real sensor's output. The IMU sits at the camera's
//! centre (no lever arm).

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

use crate::rng::Rng;

/// Standard gravity, m/s², along world −z.
pub const GRAVITY: f64 = 9.80665;

/// A simulated IMU: how it samples, sits and errs.
#[derive(Clone, Debug, PartialEq)]
pub struct ImuModel {
    /// Samples per second.
    pub rate_hz: f64,
    /// The rotation taking IMU-frame vectors into the camera frame.
    pub camera_from_imu: UnitQuaternion<f64>,
    /// Seconds added to an IMU timestamp to put it on the frames' clock:
    /// `t_frames = t_imu + time_offset`.
    pub time_offset: f64,
    /// Gyro white noise density, rad/s/√Hz.
    pub gyro_noise_density: f64,
    /// Gyro bias random walk, rad/s/√s.
    pub gyro_bias_random_walk: f64,
    /// Gyro bias at the start, rad/s in the IMU frame.
    pub gyro_turn_on_bias: [f64; 3],
    /// Accelerometer white noise density, m/s²/√Hz.
    pub accel_noise_density: f64,
    /// Accelerometer bias random walk, m/s²/√s.
    pub accel_bias_random_walk: f64,
    /// Accelerometer bias at the start, m/s².
    pub accel_turn_on_bias: [f64; 3],
    /// Seed of the noise.
    pub seed: u64,
}

/// One simulated sample, with the true biases for tests.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImuReading {
    /// Seconds on the IMU's clock.
    pub t: f64,
    /// Measured angular velocity, rad/s in the IMU frame.
    pub w: [f64; 3],
    /// Measured specific force, m/s² in the IMU frame.
    pub a: [f64; 3],
    /// The gyro bias in `w`, rad/s.
    pub gyro_bias: [f64; 3],
}

impl ImuModel {
    /// A phone IMU drawn from `seed`, at datasheet figures: 200-400 Hz; gyro white
    /// noise 0.007 °/s/√Hz, turn-on bias 0.5-3 °/s per axis (either sign), bias walk
    /// 0.0008 °/s/√s; accelerometer 150 µg/√Hz, turn-on bias up to 40 mg, walk
    /// 1e-4 m/s²/√s; a camera-IMU rotation of 2-5° about a random axis; a time offset
    /// of 5-20 ms (either sign).
    pub fn phone(seed: u64) -> Self {
        let mut rng = Rng::new(seed ^ 0x1A2B_3C4D_0000_0047);
        let deg = std::f64::consts::PI / 180.0;
        let rate_hz = [200.0, 250.0, 400.0][(rng.next_u64() % 3) as usize];
        let axis = Vector3::new(gauss(&mut rng), gauss(&mut rng), gauss(&mut rng)).normalize();
        let angle = rng.range(2.0, 5.0) * deg;
        let time_offset = rng.sign() * rng.range(0.005, 0.020);
        let gyro_turn_on_bias = std::array::from_fn(|_| rng.sign() * rng.range(0.5, 3.0) * deg);
        let accel_turn_on_bias = std::array::from_fn(|_| rng.range(-0.4, 0.4));
        ImuModel {
            rate_hz,
            camera_from_imu: UnitQuaternion::from_scaled_axis(axis * angle),
            time_offset,
            gyro_noise_density: 0.007 * deg,
            gyro_bias_random_walk: 1.4e-5,
            gyro_turn_on_bias,
            accel_noise_density: 150e-6 * GRAVITY,
            accel_bias_random_walk: 1e-4,
            accel_turn_on_bias,
            seed,
        }
    }

    /// The IMU's samples over `[from, to]` on the frames' clock for the
    /// camera-to-world trajectory `pose_at` (seconds on the frames' clock; world z up),
    /// stamped on the IMU's clock.
    pub fn simulate(
        &self,
        pose_at: impl Fn(f64) -> Isometry3<f64>,
        from: f64,
        to: f64,
    ) -> Vec<ImuReading> {
        let mut rng = Rng::new(self.seed ^ 0x5EED_0000_0000_0047);
        let dt = 1.0 / self.rate_hz;
        let n = ((to - from) / dt).floor().max(0.0) as usize + 1;
        let ci = self.camera_from_imu.inverse();
        let mut bg = Vector3::from(self.gyro_turn_on_bias);
        let mut ba = Vector3::from(self.accel_turn_on_bias);
        let (sg, sa) = (
            self.gyro_noise_density * self.rate_hz.sqrt(),
            self.accel_noise_density * self.rate_hz.sqrt(),
        );
        let (wg, wa) = (
            self.gyro_bias_random_walk * dt.sqrt(),
            self.accel_bias_random_walk * dt.sqrt(),
        );
        let mut out = Vec::with_capacity(n);
        for k in 0..n {
            let tau = from + k as f64 * dt;
            let (w_cam, f_cam) = derivatives(&pose_at, tau);
            let noise =
                |rng: &mut Rng, s: f64| Vector3::new(gauss(rng), gauss(rng), gauss(rng)) * s;
            let w = ci * w_cam + bg + noise(&mut rng, sg);
            let a = ci * f_cam + ba + noise(&mut rng, sa);
            out.push(ImuReading {
                t: tau - self.time_offset,
                w: w.into(),
                a: a.into(),
                gyro_bias: bg.into(),
            });
            bg += noise(&mut rng, wg);
            ba += noise(&mut rng, wa);
        }
        out
    }
}

/// The body angular velocity (rad/s) and the specific force (m/s²), both in the
/// camera frame, of `pose_at` at `t`, by central differences.
pub fn derivatives(
    pose_at: &impl Fn(f64) -> Isometry3<f64>,
    t: f64,
) -> (Vector3<f64>, Vector3<f64>) {
    const H_ROT: f64 = 1e-4;
    const H_POS: f64 = 1e-3;
    let (a, b) = (pose_at(t - H_ROT), pose_at(t + H_ROT));
    let w = (a.rotation.inverse() * b.rotation).scaled_axis() / (2.0 * H_ROT);
    let p = |s: f64| pose_at(s).translation.vector;
    let acc = (p(t + H_POS) - 2.0 * p(t) + p(t - H_POS)) / (H_POS * H_POS);
    let here = pose_at(t);
    let f = here.rotation.inverse() * (acc + Vector3::new(0.0, 0.0, GRAVITY));
    (w, f)
}

/// A standard normal draw (Box-Muller).
fn gauss(rng: &mut Rng) -> f64 {
    let u1 = rng.uniform().max(1e-300);
    let u2 = rng.uniform();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// A smooth trajectory through sampled poses: the samples resampled at a uniform
/// `knot` spacing (slerp and lerp between neighbours), then a cumulative cubic
/// B-spline on SO(3) (Kim et al. 1995, as in spline-fusion) and a cubic B-spline on
/// positions through those control poses. C² continuous; an approximating spline, so
/// it smooths the samples' jitter over about a knot.
#[derive(Clone, Debug)]
pub struct SplinePath {
    t0: f64,
    knot: f64,
    control: Vec<Isometry3<f64>>,
}

impl SplinePath {
    /// The spline through `poses` at `stamps` (strictly increasing, at least two) with
    /// control poses every `knot` seconds; `None` if there are too few samples or the
    /// stamps do not increase.
    pub fn fit(stamps: &[f64], poses: &[Isometry3<f64>], knot: f64) -> Option<SplinePath> {
        let n = stamps.len().min(poses.len());
        if n < 2 || !(knot > 0.0) || stamps.windows(2).any(|w| !(w[1] > w[0])) {
            return None;
        }
        let (first, last) = (stamps[0], stamps[n - 1]);
        let count = ((last - first) / knot).floor() as usize + 1;
        let mut control = Vec::with_capacity(count + 2);
        let mut j = 0;
        for k in 0..count {
            let t = first + k as f64 * knot;
            while j + 2 < n && stamps[j + 1] <= t {
                j += 1;
            }
            let f = ((t - stamps[j]) / (stamps[j + 1] - stamps[j])).clamp(0.0, 1.0);
            let (a, b) = (&poses[j], &poses[j + 1]);
            let r = a.rotation.slerp(&b.rotation, f);
            let p = a.translation.vector.lerp(&b.translation.vector, f);
            control.push(Isometry3::from_parts(Translation3::from(p), r));
        }
        // One more at each end, so that the spline spans every sample's time.
        let (c0, cn) = (control[0], control[control.len() - 1]);
        control.insert(0, c0);
        control.push(cn);
        control.push(cn);
        Some(SplinePath {
            t0: first - knot,
            knot,
            control,
        })
    }

    /// The first and last time the spline covers.
    pub fn span(&self) -> (f64, f64) {
        (
            self.t0 + self.knot,
            self.t0 + (self.control.len() - 3) as f64 * self.knot,
        )
    }

    /// The camera-to-world pose at `t` (clamped to the span).
    pub fn pose_at(&self, t: f64) -> Isometry3<f64> {
        let (lo, hi) = self.span();
        let s = (t.clamp(lo, hi) - self.t0) / self.knot;
        let i = (s.floor() as usize).clamp(1, self.control.len() - 3);
        let u = s - i as f64;
        let (u2, u3) = (u * u, u * u * u);
        let b = [
            (5.0 + 3.0 * u - 3.0 * u2 + u3) / 6.0,
            (1.0 + 3.0 * u + 3.0 * u2 - 2.0 * u3) / 6.0,
            u3 / 6.0,
        ];
        let c = &self.control;
        let mut r = c[i - 1].rotation;
        let mut p = c[i - 1].translation.vector;
        for k in 0..3 {
            let (a, bb) = (&c[i - 1 + k], &c[i + k]);
            let omega = (a.rotation.inverse() * bb.rotation).scaled_axis();
            r *= UnitQuaternion::from_scaled_axis(omega * b[k]);
            p += (bb.translation.vector - a.translation.vector) * b[k];
        }
        r.renormalize();
        Isometry3::from_parts(Translation3::from(p), r)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A spin at a constant rate about a fixed camera axis: the simulated gyro,
    /// averaged, is the rate in the IMU frame plus the turn-on bias.
    #[test]
    fn gyro_measures_the_path_rate() {
        let mut m = ImuModel::phone(3);
        m.gyro_bias_random_walk = 0.0;
        let rate = Vector3::new(0.2, -1.0, 0.5);
        let pose_at = |t: f64| {
            Isometry3::from_parts(
                Translation3::new(0.0, 0.0, 0.5 * t * t),
                UnitQuaternion::from_scaled_axis(rate * t),
            )
        };
        let s = m.simulate(pose_at, 0.0, 2.0);
        assert!((s.len() as f64 - 2.0 * m.rate_hz).abs() <= 1.0);
        assert!((s[1].t - s[0].t - 1.0 / m.rate_hz).abs() < 1e-12);
        assert!((s[0].t + m.time_offset).abs() < 1e-12);
        let mean: Vector3<f64> =
            s.iter().map(|x| Vector3::from(x.w)).sum::<Vector3<f64>>() / s.len() as f64;
        let want = m.camera_from_imu.inverse() * rate + Vector3::from(m.gyro_turn_on_bias);
        // White noise of 0.007 °/s/√Hz over 2 s averages to about 1e-4 rad/s.
        assert!((mean - want).norm() < 5e-4, "{mean} vs {want}");
        // The accelerometer at rest in z up reads +g in the world's z (plus 1 m/s²).
        let f = derivatives(&pose_at, 1.0).1;
        let world = pose_at(1.0).rotation * f;
        assert!((world - Vector3::new(0.0, 0.0, GRAVITY + 1.0)).norm() < 1e-5);
    }

    #[test]
    fn spline_follows_smooth_samples() {
        let truth = |t: f64| {
            Isometry3::from_parts(
                Translation3::new(t.sin(), 0.3 * t, 0.1 * (2.0 * t).cos()),
                UnitQuaternion::from_scaled_axis(Vector3::new(0.3 * t.sin(), 0.8 * t, 0.1)),
            )
        };
        let stamps: Vec<f64> = (0..400).map(|i| i as f64 * 0.01).collect();
        let poses: Vec<_> = stamps.iter().map(|&t| truth(t)).collect();
        let s = SplinePath::fit(&stamps, &poses, 0.02).unwrap();
        for t in [0.5, 1.234, 2.0, 3.3] {
            let (a, b) = (s.pose_at(t), truth(t));
            assert!(
                (a.translation.vector - b.translation.vector).norm() < 1e-3,
                "{t}"
            );
            assert!(a.rotation.angle_to(&b.rotation) < 1e-3, "{t}");
            let (wa, wb) = (
                derivatives(&|x| s.pose_at(x), t).0,
                derivatives(&truth, t).0,
            );
            assert!((wa - wb).norm() < 5e-3, "{t}: {wa} vs {wb}");
        }
        assert!(SplinePath::fit(&[0.0, 0.0], &poses[..2], 0.02).is_none());
    }
}
