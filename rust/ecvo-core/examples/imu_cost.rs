//! What the IMU path costs the tracker per frame (issue 47): pushing a frame's worth
//! of 400 Hz gyro samples, integrating them into the prior and correcting the bias,
//! timed frame by frame over 100,000 frames at 30 Hz (a 1 rad/s spin about a tilted
//! axis). Prints median, mean and p95 in microseconds, against the constant-velocity
//! prediction alone (`ecvo_core::prior::predict`) measured in the same run.
//!
//!     cargo run --release -p ecvo-core --example imu_cost

use std::time::Instant;

use ecvo_core::imu::{Gyro, GyroSample, ImuCalibration, ImuCounters};
use ecvo_core::prior::{Velocity, predict};
use ecvo_core::{Pose, se3};
use nalgebra::{Matrix6, UnitQuaternion, Vector3};

fn summary(mut v: Vec<f64>) -> (f64, f64, f64) {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    (v[n / 2], v.iter().sum::<f64>() / n as f64, v[n * 95 / 100])
}

fn main() {
    const FRAMES: usize = 100_000;
    const RATE: f64 = 400.0;
    const FPS: f64 = 30.0;
    let w = Vector3::new(0.3, 0.9, 0.2).normalize();
    let mut gyro = Gyro::new(ImuCalibration {
        camera_from_imu: UnitQuaternion::from_euler_angles(0.02, -0.03, 0.05),
        time_offset: 0.012,
        ..ImuCalibration::default()
    });
    let mut counters = ImuCounters::default();
    let information = Matrix6::identity() * 1e8;
    let v = Velocity {
        index: 0,
        motion: se3::exp(&se3::Twist::new(0.0, 0.0, 0.01, 0.0, 0.03, 0.0)),
        dt: 1.0 / FPS,
    };
    let (mut imu_us, mut cv_us) = (Vec::with_capacity(FRAMES), Vec::with_capacity(FRAMES));
    let mut batch = Vec::with_capacity(32);
    let mut k = 0u64;
    let mut sink = 0.0;
    for i in 1..FRAMES {
        let (tp, tc) = ((i - 1) as f64 / FPS, i as f64 / FPS);
        batch.clear();
        while (k as f64) / RATE - 0.012 <= tc + 0.005 {
            batch.push(GyroSample {
                t: k as f64 / RATE - 0.012,
                w: (w + Vector3::new(0.01, -0.02, 0.005)).into(),
            });
            k += 1;
        }
        let t0 = Instant::now();
        let cv = predict(&v, tc - tp);
        cv_us.push(t0.elapsed().as_secs_f64() * 1e6);
        let t0 = Instant::now();
        gyro.push(&batch, &mut counters).unwrap();
        let prior = gyro.prior(i as u64, tp, tc, cv.as_ref(), &mut counters);
        let moved = Pose::from_parts(
            Default::default(),
            UnitQuaternion::from_scaled_axis(w * (tc - tp)),
        );
        gyro.learn(i as u64, &moved, &information, &mut counters);
        imu_us.push(t0.elapsed().as_secs_f64() * 1e6);
        sink += prior.map_or(0.0, |p| p.rotation.angle());
    }
    let (m, a, p) = summary(imu_us);
    let (cm, ca, cp) = summary(cv_us);
    println!(
        "IMU path per frame ({} samples at {RATE} Hz, {FPS} fps): median {m:.2} us, mean {a:.2} us, \
         p95 {p:.2} us; constant-velocity prediction alone: median {cm:.2} us, mean {ca:.2} us, \
         p95 {cp:.2} us; priors {}, late {}, missing {} (checksum {sink:.3})",
        counters.samples, counters.priors, counters.late, counters.missing
    );
}
