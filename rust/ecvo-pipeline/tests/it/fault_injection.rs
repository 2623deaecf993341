//! Fault injection on the tracker through the sequential engine and the pipeline
//! (see `tests/it/faults/mod.rs`; `--example faults` prints the table). The bounds are
//! the measured behaviour of the tracker, so that a regression fails; where the
//! issue's goal (every fault flagged on its first frame) is not met yet, the test
//! says so and bounds what is measured.

use crate::faults;

use faults::{Engine, Fault, LEN, Report, report, run, stream};

fn both(fault: Fault) -> Report {
    let inputs = stream(fault);
    let core = report(fault, Engine::Core, &inputs, run(Engine::Core, &inputs));
    let pipeline = report(
        fault,
        Engine::Pipeline,
        &inputs,
        run(Engine::Pipeline, &inputs),
    );
    // Offline the pipeline is the sequential engine: the same states and poses.
    assert_eq!(
        core.outcomes, pipeline.outcomes,
        "{fault:?}: pipeline differs from core"
    );
    println!("{fault:?}: {core:?}");
    assert!(core.finite, "{fault:?}: a pose is not finite");
    core
}

/// The faults the pipeline's input checks (timestamps, repeated frames), which the
/// engine does not see: the pipeline's report, and the engine's.
fn input_fault(fault: Fault) -> (Report, Report) {
    let inputs = stream(fault);
    let core = report(fault, Engine::Core, &inputs, run(Engine::Core, &inputs));
    let pipeline = report(
        fault,
        Engine::Pipeline,
        &inputs,
        run(Engine::Pipeline, &inputs),
    );
    println!("{fault:?}: {pipeline:?}");
    assert!(
        core.finite && pipeline.finite,
        "{fault:?}: a pose is not finite"
    );
    (pipeline, core)
}

#[test]
fn a_covered_lens_is_flagged_at_once_and_tracking_resumes() {
    let r = both(Fault::CoveredLens);
    assert_eq!(r.lost, LEN, "{r:?}");
    assert_eq!(r.detected_after, Some(1));
    assert_eq!(r.silently_wrong, 0);
    assert_eq!(r.recovered_after, Some(1), "{r:?}");
    assert_eq!(r.wrong_after, 0);
    // Registered against the last good frame, the first frame after the fault finds
    // the camera where it is: the trajectory does not break.
    assert!(r.drift_m < 0.01 && r.drift_deg < 1.0, "{r:?}");
}

#[test]
fn frames_of_another_size_are_rejected_and_do_not_disturb_tracking() {
    let r = both(Fault::IntrinsicsResolution);
    assert_eq!(r.rejected, LEN);
    assert_eq!(r.detected_after, Some(1));
    assert_eq!(r.recovered_after, Some(1));
    assert_eq!(r.wrong_after, 0);
    assert!(r.drift_m < 0.01 && r.drift_deg < 1.0, "{r:?}");
}

#[test]
fn black_intensity_is_tracked_on_depth() {
    // Not a failure to flag: an untextured frame registers on depth alone
    // (`MotionConfig::depth_only_texture_fraction`), and every black frame is tracked
    // with the right motion.
    let r = both(Fault::BlackIntensity);
    assert_eq!(r.silently_wrong, 0, "{r:?}");
    assert_eq!((r.tracked_ok, r.lost), (LEN, 0), "{r:?}");
    assert_eq!(r.recovered_after, Some(1));
    assert!(r.drift_m < 0.01 && r.drift_deg < 1.0, "{r:?}");
}

#[test]
fn non_increasing_timestamps_are_refused_by_the_pipeline_on_their_first_frame() {
    // The pipeline refuses every frame whose timestamp is not after the last accepted
    // one (an error, counted); tracking goes on with the next good frame. The engine
    // itself does not look at time: there they are tracked, unflagged, poses right.
    for fault in [Fault::DuplicatedTimestamps, Fault::BackwardsTimestamps] {
        let (r, core) = input_fault(fault);
        assert_eq!(r.rejected, LEN, "{r:?}");
        assert_eq!(r.detected_after, Some(1), "{r:?}");
        assert_eq!(r.silently_wrong, 0, "{r:?}");
        assert_eq!(r.recovered_after, Some(1), "{r:?}");
        assert_eq!(r.wrong_after, 0, "{r:?}");
        assert!(r.drift_m < 0.01 && r.drift_deg < 1.0, "{r:?}");
        assert_eq!(core.detected_after, None, "{core:?}");
        assert_eq!(core.tracked_ok, LEN, "{core:?}");
    }
}

#[test]
fn a_frozen_frame_is_reported_repeated_by_the_pipeline_on_its_first_frame() {
    // Each repetition of the last good frame is `PushStatus::Repeated` and not
    // tracked; the first new frame registers against the last good one, across the
    // motion missed while frozen. The engine alone reads it as a still camera.
    let (r, core) = input_fault(Fault::FrozenFrame);
    assert_eq!(r.repeated, LEN, "{r:?}");
    assert_eq!(r.detected_after, Some(1), "{r:?}");
    assert_eq!(r.silently_wrong, 0, "{r:?}");
    assert_eq!(r.recovered_after, Some(1), "{r:?}");
    assert_eq!(r.wrong_after, 0, "{r:?}");
    assert!(r.drift_m < 0.01 && r.drift_deg < 1.0, "{r:?}");
    assert_eq!(core.detected_after, None, "{core:?}");
}

#[test]
fn garbage_is_flagged_within_two_frames_and_tracking_resumes() {
    // Measured: the first garbage frame can pass as tracked (goal: flagged at once);
    // the rest are lost, and tracking is back within max_lost_frames.
    let r = both(Fault::GarbageDepth);
    assert!(r.detected_after.is_some_and(|d| d <= 2), "{r:?}");
    assert!(r.silently_wrong <= 1, "{r:?}");
    assert!(r.lost >= LEN - 1, "{r:?}");
    let max_lost = faults::config().max_lost_frames as usize;
    assert!(r.recovered_after.is_some_and(|n| n <= max_lost), "{r:?}");
}

#[test]
fn a_jump_is_flagged_at_once_and_tracking_re_anchors() {
    // Measured: a 30 cm / 20° jump fails [A] and the recovery against the references
    // (the residual-spread check), so it is flagged on its first frame, never
    // reported as tracked, and tracking re-anchors after max_lost_frames (the jump
    // itself is lost, as drift).
    let max_lost = faults::config().max_lost_frames as usize;
    let r = both(Fault::Jump30cm20deg);
    assert_eq!(r.detected_after, Some(1), "{r:?}");
    assert_eq!(r.silently_wrong, 0, "{r:?}");
    assert!(r.recovered_after.is_some_and(|n| n <= max_lost), "{r:?}");
}

#[test]
fn an_unannounced_zoom_is_flagged_at_once_and_costs_no_drift() {
    // A 30 % zoom nobody announces widens the intensity and the depth residuals of
    // every registration at once (no rigid motion explains it): the spread watch
    // (`Config::max_spread_jump`) refuses [A] and the recoveries, so every zoomed
    // frame is lost, none is reported tracked, and the first frame after the zoom
    // registers against the last good one with no drift to speak of.
    let r = both(Fault::IntrinsicsZoom);
    assert_eq!(r.detected_after, Some(1), "{r:?}");
    assert_eq!(
        (r.lost, r.silently_wrong, r.wrong_after),
        (LEN, 0, 0),
        "{r:?}"
    );
    assert_eq!(r.recovered_after, Some(1), "{r:?}");
    assert!(r.drift_m < 0.01 && r.drift_deg < 0.5, "{r:?}");
}

#[test]
fn an_announced_zoom_is_tracked_right_through_and_after_the_change() {
    // The caller passes the zoomed intrinsics with the first zoomed frame and the old
    // ones back with the first frame after: every frame tracks with the right motion
    // (within WRONG_M / WRONG_DEG), nothing is lost, and the drift across the
    // change stays small.
    let r = both(Fault::IntrinsicsZoomAnnounced);
    assert_eq!(
        (r.lost, r.silently_wrong, r.wrong_after),
        (0, 0, 0),
        "{r:?}"
    );
    assert_eq!(r.tracked_ok, faults::LEN, "{r:?}");
    assert_eq!(r.recovered_after, Some(1), "{r:?}");
    assert!(r.drift_m < 0.02 && r.drift_deg < 1.0, "{r:?}");
}

#[test]
fn intrinsics_of_another_size_or_invalid_are_refused_and_change_nothing() {
    let config = faults::config();
    let p = ecvo_pipeline::Pipeline::new(config.clone(), Default::default()).unwrap();
    let mut smaller = config.camera;
    smaller.width /= 2;
    assert!(p.set_intrinsics(smaller).is_err());
    let mut bad = config.camera;
    bad.fx = f64::NAN;
    assert!(p.set_intrinsics(bad).is_err());
    assert_eq!(p.intrinsics(), config.camera);
    assert_eq!(p.stats().intrinsics_changes, 0);
    let mut zoomed = config.camera;
    zoomed.fx *= 1.3;
    p.set_intrinsics(zoomed).unwrap();
    p.set_intrinsics(zoomed).unwrap();
    assert_eq!(p.intrinsics(), zoomed);
    assert_eq!(p.stats().intrinsics_changes, 1);
}
