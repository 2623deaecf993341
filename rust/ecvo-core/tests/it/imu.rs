//! The gyroscope's prior ([`ecvo_core::imu`]) against the ground truth of simulated
//! phone IMUs riding on ecvo-synth's fast pans.

use ecvo_core::imu::{Gyro, GyroSample, ImuCalibration, ImuCounters};
use ecvo_synth::SynthSequence;
use ecvo_synth::imu::ImuModel;

fn calibration(m: &ImuModel) -> ImuCalibration {
    ImuCalibration {
        camera_from_imu: m.camera_from_imu,
        time_offset: m.time_offset,
        gyro_noise_density: Some(m.gyro_noise_density),
        gyro_bias_random_walk: Some(m.gyro_bias_random_walk),
    }
}

fn samples(seq: &SynthSequence, m: &ImuModel, to: f64) -> Vec<GyroSample> {
    m.simulate(|t| seq.path.pose_at(t), -0.1, to)
        .iter()
        .map(|r| GyroSample { t: r.t, w: r.w })
        .collect()
}

/// Over a 200 °/s pan the gyro's rotation between two frames 0.1 s apart, in the
/// camera's frame and on its clock, matches the ground truth to within what the
/// turn-on bias (at most 3 °/s) explains.
#[test]
fn gyro_rotation_matches_the_ground_truth() {
    let seq = SynthSequence::pan_320x180(120, 5, 2.5, 200f64.to_radians());
    let m = ImuModel::phone(5);
    let mut gyro = Gyro::new(calibration(&m));
    let mut c = ImuCounters::default();
    gyro.push(&samples(&seq, &m, 4.0), &mut c).unwrap();
    let (mut worst, mut fastest) = (0.0f64, 0.0f64);
    for i in (0..110).step_by(7) {
        let (tp, tc) = (seq.timestamp(i), seq.timestamp(i + 3));
        let truth = seq.pose(i).rotation.inverse() * seq.pose(i + 3).rotation;
        let g = gyro.rotation_between(tp, tc).unwrap();
        fastest = fastest.max(truth.angle().to_degrees());
        worst = worst.max(g.angle_to(&truth).to_degrees());
    }
    assert!(
        fastest > 15.0,
        "the pan turns by {fastest}° in 0.1 s at most"
    );
    // 3 °/s over 0.1 s is 0.3°, per axis.
    assert!(worst < 0.55, "worst error {worst}°");
}
