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

/// The 10 Hz pan of these tests (a 30 Hz camera tracked every third frame): 200 °/s
/// peaks, up to 20° between frames. Rendered once.
fn pan() -> &'static (SynthSequence, Vec<ecvo_synth::SynthFrame>) {
    static PAN: std::sync::OnceLock<(SynthSequence, Vec<ecvo_synth::SynthFrame>)> =
        std::sync::OnceLock::new();
    PAN.get_or_init(|| {
        let mut seq = SynthSequence::pan_320x180(40, 3, 2.5, 200f64.to_radians());
        seq.fps = 10.0;
        let frames = (0..seq.frames).map(|i| seq.frame(i)).collect();
        (seq, frames)
    })
}

/// Tracks the pan with `Odometry`, pushing before each frame the samples of `imu`
/// (stamped on the IMU's clock, whose offset is `true_offset`) up to 5 ms after it.
fn track(
    config: ecvo_core::Config,
    imu: &[GyroSample],
    true_offset: f64,
) -> (ecvo_core::Odometry, Vec<ecvo_core::FrameOutput>) {
    let (_, frames) = pan();
    let mut odo = ecvo_core::Odometry::new(config).unwrap();
    let mut next = 0;
    let outs = frames
        .iter()
        .map(|f| {
            let start = next;
            while next < imu.len() && imu[next].t + true_offset <= f.timestamp + 0.005 {
                next += 1;
            }
            odo.push_imu(&imu[start..next]).unwrap();
            super::common::push(&mut odo, f)
        })
        .collect();
    (odo, outs)
}

/// RMS rotation error (degrees) of the tracked poses against the ground truth.
fn rotation_rmse(outs: &[ecvo_core::FrameOutput]) -> f64 {
    let (seq, _) = pan();
    let p0 = seq.pose(0);
    let se: f64 = outs
        .iter()
        .map(|o| {
            let truth = p0.rotation.inverse() * seq.pose(o.index as usize).rotation;
            truth.angle_to(&o.pose.rotation).powi(2)
        })
        .sum();
    (se / outs.len() as f64).sqrt().to_degrees()
}

fn pan_config() -> ecvo_core::Config {
    super::common::config(&pan().0, ecvo_core::Mode::L2)
}

/// Without the IMU the 10 Hz pan loses frames (the identity and the constant-velocity
/// prediction are out of MOTION's basin when the pan speeds up); with the simulated
/// gyro it loses none, and tracks within 1° RMS. A gyro whose time offset is 20 ms
/// off (about 4° at the peak rate) still loses none.
#[test]
fn the_gyro_keeps_a_fast_pan() {
    let (seq, frames) = pan();
    let m = ImuModel::phone(11);
    let imu = samples(seq, &m, seq.timestamp(frames.len() - 1) + 0.1);
    // The chain and keyframe tracking (the default): without the gyro the chain loses
    // 22 of the 40 frames, keyframe tracking 2 (measured); with it, neither loses any.
    for keyframes in [false, true] {
        let mut base = pan_config();
        base.keyframes = keyframes;
        let (_, without) = track(base.clone(), &[], 0.0);
        let mut config = base;
        config.imu = calibration(&m);
        let (odo, with) = track(config.clone(), &imu, m.time_offset);
        let lost = |o: &[ecvo_core::FrameOutput]| {
            o.iter()
                .filter(|o| o.state == ecvo_core::TrackingState::Lost)
                .count()
        };
        let (lw, lo) = (lost(&with), lost(&without));
        let (rw, ro) = (rotation_rmse(&with), rotation_rmse(&without));
        eprintln!(
            "keyframes {keyframes}: lost {lw} with the IMU, {lo} without; rotation RMSE {rw:.3}° / {ro:.3}°"
        );
        let at_least = if keyframes { 1 } else { 5 };
        assert!(
            lo >= at_least,
            "keyframes {keyframes}: without the IMU {lo} frames lost"
        );
        assert_eq!(lw, 0, "keyframes {keyframes}: with the IMU");
        assert!(
            rw < 1.0 && rw < ro,
            "keyframes {keyframes}: rotation RMSE {rw}° with, {ro}° without"
        );
        let c = &odo.tracker().counters().imu;
        assert_eq!((c.priors, c.late, c.missing), (39, 0, 0), "{c:?}");

        config.imu.time_offset += 0.020;
        let (_, shifted) = track(config, &imu, m.time_offset);
        let rs = rotation_rmse(&shifted);
        eprintln!(
            "keyframes {keyframes}: 20 ms off: lost {}, rotation RMSE {rs:.3}°",
            lost(&shifted)
        );
        assert_eq!(lost(&shifted), 0, "keyframes {keyframes}");
        assert!(rs < 1.5, "rotation RMSE {rs}° with the offset 20 ms off");
    }
}

/// The bias estimate converges to the simulated gyro's turn-on bias (no random walk
/// here) from the believed rotations of the pan.
#[test]
fn bias_estimate_converges_to_the_true_bias() {
    let (seq, frames) = pan();
    let mut m = ImuModel::phone(12);
    m.gyro_bias_random_walk = 0.0;
    let imu = samples(seq, &m, seq.timestamp(frames.len() - 1) + 0.1);
    let mut config = pan_config();
    config.imu = calibration(&m);
    let (odo, _) = track(config, &imu, m.time_offset);
    let truth = nalgebra::Vector3::from(m.gyro_turn_on_bias);
    let est = odo.tracker().gyro().bias().bias;
    let err = (est - truth).norm().to_degrees();
    eprintln!(
        "bias {:.3} °/s, estimate {:.3} °/s, error {err:.3} °/s",
        truth.norm().to_degrees(),
        est.norm().to_degrees()
    );
    // From up to 5 °/s (3 per axis) to within 0.3 °/s.
    assert!(truth.norm().to_degrees() > 1.0);
    assert!(err < 0.3, "bias error {err} °/s");
}

/// Samples that never cover a frame leave every frame tracked as without an IMU,
/// bit for bit, and are counted late.
#[test]
fn late_samples_change_nothing() {
    let (seq, _) = pan();
    let m = ImuModel::phone(13);
    let early: Vec<GyroSample> = samples(seq, &m, 0.5)
        .into_iter()
        .map(|s| GyroSample { t: s.t - 10.0, ..s })
        .collect();
    let (_, without) = track(pan_config(), &[], 0.0);
    let (odo, with) = track(pan_config(), &early, 0.0);
    for (a, b) in with.iter().zip(&without) {
        assert_eq!(
            a.pose.to_homogeneous(),
            b.pose.to_homogeneous(),
            "frame {}",
            a.index
        );
    }
    let c = &odo.tracker().counters().imu;
    assert_eq!((c.priors, c.late, c.missing), (0, 39, 0), "{c:?}");
}

/// A batch with a non-finite value is refused whole; samples out of order are
/// counted and dropped.
#[test]
fn bad_samples_are_refused() {
    let mut odo = ecvo_core::Odometry::new(pan_config()).unwrap();
    let s = |t: f64, w: f64| GyroSample {
        t,
        w: [w, 0.0, 0.0],
    };
    let e = odo.push_imu(&[s(0.0, 0.0), s(0.01, f64::NAN)]).unwrap_err();
    assert!(e.to_string().contains("sample 1"), "{e}");
    odo.push_imu(&[s(1.0, 0.0), s(1.0, 0.0), s(0.5, 0.0), s(1.01, 0.0)])
        .unwrap();
    let c = &odo.tracker().counters().imu;
    assert_eq!((c.samples, c.refused), (2, 2), "{c:?}");
    assert!(odo.push_imu(&[s(f64::INFINITY, 0.0)]).is_err());
}

/// The gyro's prior term in the normal equations (`Config::imu_prior_term`): on the
/// 10 Hz pan with the simulated gyro it loses no frame and tracks within 1° RMS;
/// and without IMU samples it changes nothing, bit for bit.
#[test]
fn the_prior_term_keeps_the_pan_and_is_inert_without_samples() {
    let (seq, frames) = pan();
    let m = ImuModel::phone(11);
    let imu = samples(seq, &m, seq.timestamp(frames.len() - 1) + 0.1);
    let mut config = pan_config();
    config.imu = calibration(&m);
    for term in [false, true] {
        config.imu_prior_term = term;
        let (odo, outs) = track(config.clone(), &imu, m.time_offset);
        let lost = outs
            .iter()
            .filter(|o| o.state == ecvo_core::TrackingState::Lost)
            .count();
        let rmse = rotation_rmse(&outs);
        eprintln!("prior term {term}: lost {lost}, rotation RMSE {rmse:.4}°");
        assert_eq!(lost, 0, "prior term {term}");
        assert!(rmse < 1.0, "prior term {term}: rotation RMSE {rmse}°");
        assert_eq!(odo.tracker().counters().imu.priors, 39);
    }
    let mut off = pan_config();
    off.imu_prior_term = false;
    let mut on = off.clone();
    on.imu_prior_term = true;
    let (_, a) = track(off, &[], 0.0);
    let (_, b) = track(on, &[], 0.0);
    let poses = |o: &[ecvo_core::FrameOutput]| -> Vec<_> { o.iter().map(|o| o.pose).collect() };
    assert_eq!(poses(&a), poses(&b), "no samples: the prior term is inert");
}

/// Depth captured 16.7 ms after the intensity (a 60 Hz render paired two by two: the
/// intensity of frame 2k, the depth of frame 2k + 1) on a pan reaching 190 °/s, up to
/// 3° between the two images: pushed with its depth time, the depth is turned to the
/// intensity's time by the gyro (`Odometry::push_with_depth_time`), and the tracked
/// positions stay closer to the ground truth (the camera pans in place) than when the
/// depth is taken as it is. Every frame is counted turned.
#[test]
fn depth_turned_to_the_intensity_time_tracks_better() {
    let mut seq = SynthSequence::pan_320x180(48, 3, 2.5, 200f64.to_radians());
    seq.fps = 60.0;
    let rendered: Vec<_> = (0..seq.frames).map(|i| seq.frame(i)).collect();
    let m = ImuModel::phone(14);
    let imu = samples(&seq, &m, seq.timestamp(seq.frames - 1) + 0.1);
    let mut config = super::common::config(&seq, ecvo_core::Mode::L2);
    config.imu = calibration(&m);
    let run = |turn: bool| {
        let mut odo = ecvo_core::Odometry::new(config.clone()).unwrap();
        let mut next = 0;
        let mut worst = 0.0f64;
        let mut se = 0.0;
        for k in 0..seq.frames / 2 {
            let (c, d) = (&rendered[2 * k], &rendered[2 * k + 1]);
            let start = next;
            while next < imu.len() && imu[next].t + m.time_offset <= d.timestamp + 0.005 {
                next += 1;
            }
            odo.push_imu(&imu[start..next]).unwrap();
            let view = ecvo_core::FrameView {
                timestamp: c.timestamp,
                intensity: &c.intensity,
                depth: &d.depth,
            };
            let o = if turn {
                odo.push_with_depth_time(view, d.timestamp).unwrap()
            } else {
                odo.push(view).unwrap()
            };
            assert_ne!(
                o.state,
                ecvo_core::TrackingState::Lost,
                "turn {turn}, frame {k}"
            );
            // The camera pans in place: its position is the tracking's error.
            let truth = seq.pose(0).inverse() * c.pose;
            let e = (o.pose.translation.vector - truth.translation.vector).norm();
            worst = worst.max(e);
            se += e * e;
        }
        let rmse = (se / (seq.frames / 2) as f64).sqrt();
        (odo.tracker().counters().imu, rmse, worst)
    };
    let (plain, r0, w0) = run(false);
    let (turned, r1, w1) = run(true);
    eprintln!("position RMSE {r0:.4} m (worst {w0:.4}) as is, {r1:.4} m (worst {w1:.4}) turned");
    assert_eq!(
        (plain.depth_turned, plain.depth_unturned),
        (0, 0),
        "{plain:?}"
    );
    assert_eq!(
        (turned.depth_turned, turned.depth_unturned),
        (24, 0),
        "{turned:?}"
    );
    // Measured 0.0053 m as is, 0.0009 m turned.
    assert!(r1 < 0.4 * r0, "position RMSE {r1} m turned, {r0} m as is");
}

/// A depth time is checked and accounted for: a non-finite one is refused with a
/// clear error (the tracker goes on); without a gyro, or with a gap over 50 ms, the
/// depth is left as it is, and only the latter is counted (`depth_unturned`).
#[test]
fn depth_times_are_checked_and_counted() {
    let (seq, frames) = pan();
    fn view(f: &ecvo_synth::SynthFrame) -> ecvo_core::FrameView<'_> {
        ecvo_core::FrameView {
            timestamp: f.timestamp,
            intensity: &f.intensity,
            depth: &f.depth,
        }
    }
    let mut odo = ecvo_core::Odometry::new(pan_config()).unwrap();
    let e = odo
        .push_with_depth_time(view(&frames[0]), f64::NAN)
        .unwrap_err();
    assert!(e.to_string().contains("depth timestamp NaN"), "{e}");
    assert_eq!(
        odo.tracker().counters().frames,
        0,
        "the refused frame is not tracked"
    );
    // No gyro yet: neither turned nor counted.
    odo.push_with_depth_time(view(&frames[0]), frames[0].timestamp + 0.01)
        .unwrap();
    // Samples up to just after frame 2's depth (the depth clock keeps the newest
    // 256: pushed as they come, they cover the frames).
    let m = ImuModel::phone(15);
    let imu = samples(seq, &m, frames[2].timestamp + 0.07);
    odo.push_imu(&imu).unwrap();
    // Covered, then a gap over 50 ms.
    odo.push_with_depth_time(view(&frames[1]), frames[1].timestamp + 0.01)
        .unwrap();
    odo.push_with_depth_time(view(&frames[2]), frames[2].timestamp + 0.06)
        .unwrap();
    let c = odo.tracker().counters().imu;
    assert_eq!((c.depth_turned, c.depth_unturned), (1, 1), "{c:?}");
}
