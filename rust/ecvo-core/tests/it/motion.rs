//! MOTION on synthetic frames rendered from a known textured scene under a known motion.

use crate::common;

use common::*;
use ecvo_core::motion::{Failure, MotionEstimator, Status};
use ecvo_core::{FrameView, Mode, Pose, PreparedFrame, Preparer, Schedule, Weighting};
use ecvo_synth::DepthNoise;

/// Frames `a` (reference) and `b` (current) of a sequence; returns the estimate of
/// `T_{b,a}` from the identity and the ground truth `P_a⁻¹ P_b`.
fn estimate(
    seq: &ecvo_synth::SynthSequence,
    a: usize,
    b: usize,
    cfg: &ecvo_core::Config,
) -> (ecvo_core::MotionResult, Pose) {
    let (fa, pa) = prepared(seq, a, cfg);
    let (fb, pb) = prepared(seq, b, cfg);
    let truth = pa.inverse() * pb;
    let r = MotionEstimator::new().motion(&fb, &fa, &Pose::identity(), &cfg.motion);
    (r, truth)
}

#[test]
fn recovers_motion_on_noise_free_frames() {
    let seq = sequence(DepthNoise::none(), 7);
    let cfg = config(&seq, Mode::Naive);
    // Consecutive frames and frames several steps apart (a few cm, a few degrees).
    for (a, b) in [(0, 1), (10, 11), (30, 33), (50, 55), (80, 84)] {
        let (r, truth) = estimate(&seq, a, b, &cfg);
        assert!(r.is_ok(), "{a}->{b}: {:?}", r.status);
        let (dt, da) = pose_error(&r.pose, &truth);
        let moved = truth.translation.vector.norm();
        println!(
            "{a}->{b}: moved {:.1} mm {:.2} deg; error {:.3} mm {:.4} deg, {} px, it {:?}",
            moved * 1e3,
            ecvo_core::se3::angle(&truth).to_degrees(),
            dt * 1e3,
            da,
            r.valid_pixels,
            &r.iterations[..r.steps]
        );
        assert!(dt < 1e-3, "{a}->{b}: translation error {:.3} mm", dt * 1e3);
        assert!(da < 0.05, "{a}->{b}: rotation error {da:.4} deg");
    }
}

#[test]
fn recovers_motion_with_depth_noise_and_outliers() {
    // Stated tolerances with Kinect-like depth noise (disparity steps of ~1 cm at 2 m)
    // and 20 % outliers. Measured worst cases: paper sampling 6.6 mm / 0.15 deg (its
    // finest step uses every 2nd pixel), full-resolution pyramid 3.3 mm / 0.06 deg.
    // The same with bivariate coarse steps and a scalar finest step (`--weighting
    // hybrid`).
    for (schedule, fine, max_mm, max_deg) in [
        (Schedule::PaperSampling, None, 10.0, 0.25),
        (Schedule::Pyramid, None, 5.0, 0.12),
        (Schedule::PyramidStride2, Some(Weighting::Scalar), 5.0, 0.12),
    ] {
        noisy_with_outliers(schedule, fine, max_mm, max_deg);
    }
}

fn noisy_with_outliers(schedule: Schedule, fine: Option<Weighting>, max_mm: f64, max_deg: f64) {
    let seq = sequence(DepthNoise::kinect_like(), 11);
    let mut cfg = config(&seq, Mode::Naive);
    cfg.motion.levels = schedule.levels();
    cfg.motion.fine_weighting = fine;
    let mut worst = (0.0f64, 0.0f64);
    for (a, b) in [(0, 1), (20, 22), (40, 43), (70, 72)] {
        let fa = seq.frame(a);
        let mut fb = seq.frame(b);
        // 20 % outliers in the current frame: random intensity and depth values.
        let mut state = 0x9E37_79B9_7F4A_7C15u64 ^ b as u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        for i in 0..fb.intensity.len() {
            if next() % 5 == 0 {
                fb.intensity[i] = (next() % 256) as u8;
                fb.depth[i] = 2500 + (next() % 20000) as u16;
            }
        }
        let (pa, ta) = prepare_raw(&cfg, fa.timestamp, &fa.intensity, &fa.depth, fa.pose);
        let (pb, tb) = prepare_raw(&cfg, fb.timestamp, &fb.intensity, &fb.depth, fb.pose);
        let r = MotionEstimator::new().motion(&pb, &pa, &Pose::identity(), &cfg.motion);
        assert!(r.is_ok(), "{a}->{b}: {:?}", r.status);
        if fine == Some(Weighting::Scalar) {
            // The finest step's scale is the scalar one: the same over both residuals.
            let s = r.scale.expect("a scale");
            assert_eq!((s.ii, s.iz), (s.zz, 0.0), "{a}->{b}: {s:?}");
        }
        let (dt, da) = pose_error(&r.pose, &(ta.inverse() * tb));
        println!(
            "{schedule:?} {a}->{b}: error {:.3} mm {:.4} deg",
            dt * 1e3,
            da
        );
        worst = (worst.0.max(dt), worst.1.max(da));
    }
    assert!(
        worst.0 < max_mm * 1e-3 && worst.1 < max_deg,
        "{schedule:?}: worst error {:.3} mm {:.4} deg",
        worst.0 * 1e3,
        worst.1
    );
}

#[test]
fn a_good_initial_guess_is_kept_and_refined() {
    // Box [B]: seeded with the accumulated motion, MOTION converges over a larger gap.
    let seq = sequence(DepthNoise::none(), 3);
    let cfg = config(&seq, Mode::L1);
    let (fa, pa) = prepared(&seq, 20, &cfg);
    let (fb, pb) = prepared(&seq, 32, &cfg);
    let truth = pa.inverse() * pb;
    let seed = truth
        * ecvo_core::se3::exp(&nalgebra::Vector6::new(
            0.004, -0.003, 0.002, 0.004, 0.003, -0.002,
        ));
    let r = MotionEstimator::new().motion(&fb, &fa, &seed, &cfg.motion);
    assert!(r.is_ok());
    let (dt, da) = pose_error(&r.pose, &truth);
    assert!(
        dt < 1e-3 && da < 0.05,
        "error {:.3} mm {:.4} deg",
        dt * 1e3,
        da
    );
}

fn flat(cfg: &ecvo_core::Config, gray: u8, depth: u16) -> PreparedFrame {
    let n = cfg.camera.pixels();
    let mut out = PreparedFrame::default();
    Preparer::new(cfg)
        .prepare_into(
            FrameView {
                timestamp: 0.0,
                intensity: &vec![gray; n],
                depth: &vec![depth; n],
            },
            &mut out,
        )
        .unwrap();
    out
}

#[test]
fn degenerate_input_fails_cleanly() {
    let seq = sequence(DepthNoise::none(), 1);
    let cfg = config(&seq, Mode::Naive);
    let (good, _) = prepared(&seq, 0, &cfg);
    let mut est = MotionEstimator::new();
    // All-zero depth in the reference: no template point to align.
    let empty = flat(&cfg, 128, 0);
    for (fi, fj) in [(&good, &empty), (&empty, &empty)] {
        let r = est.motion(fi, fj, &Pose::identity(), &cfg.motion);
        assert_eq!(r.status, Status::Failed(Failure::TooFewPixels));
        assert_eq!(r.pose, Pose::identity());
    }
    // A current frame without depth and without texture constrains nothing.
    let r = est.motion(&empty, &good, &Pose::identity(), &cfg.motion);
    assert_eq!(r.status, Status::Failed(Failure::Degenerate));
    assert_eq!(r.pose, Pose::identity());
    // Flat intensity on a fronto-parallel plane: three of six motions are unobservable.
    let plane = flat(&cfg, 90, 10000);
    let r = est.motion(&plane, &plane, &Pose::identity(), &cfg.motion);
    assert_eq!(r.status, Status::Failed(Failure::Degenerate));
    assert!(ecvo_core::se3::is_finite(&r.pose));
    // A non-finite initial guess never produces a NaN pose.
    let mut bad = Pose::identity();
    bad.translation.vector.x = f64::NAN;
    let r = est.motion(&good, &good, &bad, &cfg.motion);
    assert_eq!(r.status, Status::Failed(Failure::NotFinite));
}

#[test]
fn information_matrix_is_symmetric_positive_definite() {
    let seq = sequence(DepthNoise::none(), 5);
    let cfg = config(&seq, Mode::Naive);
    let (r, _) = estimate(&seq, 0, 1, &cfg);
    let h = r.information;
    assert!((h - h.transpose()).abs().max() < 1e-9 * h.abs().max());
    assert!(h.cholesky().is_some());
    assert!(r.valid_pixels > 10_000, "{} valid pixels", r.valid_pixels);
}

/// Runs MOTION with `cfg` and with `other` on frame pairs of a Kinect-like noisy
/// sequence; asserts that every pair succeeds with both, that the two poses lie
/// within 0.5 mm / 0.02° of each other and that `cfg`'s is within the noisy-frame
/// tolerance of the truth (5 mm / 0.12°). Returns the Gauss-Newton iterations of
/// each config, summed over the pairs.
fn agree_on_noisy_frames(cfg: &ecvo_core::Config, other: &ecvo_core::Config) -> (u32, u32) {
    let seq = sequence(DepthNoise::kinect_like(), 11);
    let (mut it, mut it_other) = (0u32, 0u32);
    for (a, b) in [(0, 1), (20, 22), (40, 43), (70, 72), (90, 91), (100, 104)] {
        let (r, truth) = estimate(&seq, a, b, cfg);
        let (r0, _) = estimate(&seq, a, b, other);
        assert!(
            r.is_ok() && r0.is_ok(),
            "{a}->{b}: {:?} {:?}",
            r.status,
            r0.status
        );
        it += r.iterations[..r.steps].iter().sum::<u32>();
        it_other += r0.iterations[..r0.steps].iter().sum::<u32>();
        let (dt, da) = pose_error(&r.pose, &r0.pose);
        let (et, ea) = pose_error(&r.pose, &truth);
        println!(
            "{a}->{b}: it {:?} vs {:?}; apart {:.3} mm {:.4} deg; error {:.3} mm {:.4} deg",
            &r.iterations[..r.steps],
            &r0.iterations[..r0.steps],
            dt * 1e3,
            da,
            et * 1e3,
            ea
        );
        assert!(
            dt < 5e-4 && da < 0.02,
            "{a}->{b}: {:.3} mm {da:.4} deg apart",
            dt * 1e3
        );
        assert!(
            et < 5e-3 && ea < 0.12,
            "{a}->{b}: {:.3} mm {ea:.4} deg from the truth",
            et * 1e3
        );
    }
    (it, it_other)
}

/// The predicted-decrease stop (`MotionConfig::min_predicted_decrease`) ends the
/// levels earlier without moving the result: the Gauss-Newton iterations drop
/// (measured: 109 to 72 over the pairs, without the pixel stop) and the poses agree
/// with those without the stop.
#[test]
fn predicted_decrease_stop_saves_iterations_not_accuracy() {
    let mut cfg = config(&sequence(DepthNoise::kinect_like(), 11), Mode::Naive);
    assert!(cfg.motion.min_predicted_decrease > 0.0, "on by default");
    // The pixel stop alone (below) would end most of the levels this one ends.
    cfg.motion.min_update_px = 0.0;
    let mut off = cfg.clone();
    off.motion.min_predicted_decrease = 0.0;
    let (with, without) = agree_on_noisy_frames(&cfg, &off);
    println!("iterations: {with} with the stop, {without} without");
    assert!(
        with < without,
        "{with} iterations with the stop, {without} without"
    );
}

/// The pixel stop (`MotionConfig::min_update_px`) ends a level after an update that
/// moves the image by less than a tenth of the level's pixel: fewer iterations, the
/// same poses within the tolerances of [`agree_on_noisy_frames`].
#[test]
fn pixel_update_stop_saves_iterations_not_accuracy() {
    let cfg = config(&sequence(DepthNoise::kinect_like(), 11), Mode::Naive);
    assert_eq!(cfg.motion.min_update_px, 0.1, "the default");
    let mut off = cfg.clone();
    off.motion.min_update_px = 0.0;
    let (with, without) = agree_on_noisy_frames(&cfg, &off);
    println!("iterations: {with} with the stop, {without} without");
    assert!(
        with < without,
        "{with} iterations with the stop, {without} without"
    );
}

/// One scale pass per accepted update (`MotionConfig::scale_passes_per_update`, the
/// default) instead of a fit to convergence at every one: the poses agree with the
/// converged fit's.
#[test]
fn one_scale_pass_per_update_keeps_the_pose() {
    let cfg = config(&sequence(DepthNoise::kinect_like(), 11), Mode::Naive);
    assert_eq!(cfg.motion.scale_passes_per_update, 1, "the default");
    let mut full = cfg.clone();
    full.motion.scale_passes_per_update = ecvo_core::motion::MAX_SCALE_PASSES;
    agree_on_noisy_frames(&cfg, &full);
}

/// A rotation prior 0.1° off the truth (a gyro's error over a frame is hundredths of
/// a degree) and far more certain than the images pulls `MOTION`'s pose onto it;
/// `images_pose` comes back to where the images alone put it (the same call without
/// the prior), which is what the gyro's bias is learnt from.
#[test]
fn images_pose_is_the_images_alone_under_a_rotation_prior() {
    let seq = sequence(DepthNoise::kinect_like(), 7);
    let cfg = config(&seq, Mode::Naive);
    let (fa, pa) = prepared(&seq, 30, &cfg);
    let (fb, pb) = prepared(&seq, 33, &cfg);
    let truth = pa.inverse() * pb;
    let off = nalgebra::UnitQuaternion::from_scaled_axis(nalgebra::Vector3::new(
        0.0,
        0.1f64.to_radians(),
        0.0,
    ));
    let target = Pose::from_parts(truth.translation, off * truth.rotation);
    let mut est = MotionEstimator::new();
    let plain = est.motion_from(&fb, &fa, &[Pose::identity(), target], &cfg.motion);
    assert!(plain.is_ok() && plain.images_pose.is_none());
    let mut m = cfg.motion.clone();
    m.rotation_prior_information = 1e12;
    let r = est.motion_from(&fb, &fa, &[Pose::identity(), target], &m);
    assert!(r.is_ok(), "{:?}", r.status);
    let images = r.images_pose.expect("with a prior term");
    let pulled = r.pose.rotation.angle_to(&target.rotation).to_degrees();
    let own = images.rotation.angle_to(&plain.pose.rotation).to_degrees();
    let (dt, _) = pose_error(&images, &plain.pose);
    println!(
        "pose {pulled:.4}° from the prior; images_pose {own:.4}°, {:.3} mm from the images' own",
        dt * 1e3
    );
    assert!(pulled < 0.05, "the prior wins: {pulled}°");
    // Measured 0.024° and 1.4 mm: within the estimator's own stopping tolerance
    // (`min_update_px` 0.1 px is 0.02° here), against the prior's 0.1°.
    assert!(
        own < 0.05 && dt < 2e-3,
        "images_pose {own}°, {} mm off",
        dt * 1e3
    );
}
