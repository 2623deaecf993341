//! The adaptive error-correcting tracker on synthetic streams.

use crate::common;

use common::*;
use ecvo_core::config::ReferenceLevel;
use ecvo_core::se3::{self, Twist};
use ecvo_core::{FrameView, Mode, Odometry, Pose, TrackingState, comp};
use ecvo_synth::DepthNoise;

fn rot_z(deg: f64) -> Pose {
    se3::exp(&Twist::new(0.0, 0.0, 0.0, 0.0, 0.0, deg.to_radians()))
}
fn trans(x: f64, y: f64, z: f64) -> Pose {
    se3::exp(&Twist::new(x, y, z, 0.0, 0.0, 0.0))
}

#[test]
fn comp_follows_section_3_2() {
    let l = ReferenceLevel::mm_deg(30.0, 7.0);
    assert!(!comp(&Pose::identity(), &l));
    // Translation alone: strictly greater than εd.
    assert!(!comp(&trans(0.0299, 0.0, 0.0), &l));
    assert!(comp(&trans(0.0301, 0.0, 0.0), &l));
    assert!(comp(&trans(0.02, 0.02, 0.02), &l)); // ‖t‖ = 34.6 mm
    // Rotation alone: tr(R) < 2 cos εa + 1, in any axis.
    assert!(!comp(&rot_z(6.99), &l));
    assert!(comp(&rot_z(7.01), &l));
    assert!(comp(
        &se3::exp(&Twist::new(0.0, 0.0, 0.0, 0.0, 7.01f64.to_radians(), 0.0)),
        &l
    ));
    assert!(comp(&rot_z(-7.5), &l));
    // Either condition is enough.
    assert!(comp(&(trans(0.031, 0.0, 0.0) * rot_z(1.0)), &l));
    // Zero thresholds: any motion at all triggers, none does not.
    let zero = ReferenceLevel::mm_deg(0.0, 0.0);
    assert!(comp(&trans(1e-6, 0.0, 0.0), &zero));
    assert!(!comp(&Pose::identity(), &zero));
}

#[test]
fn counters_obey_the_identity_and_l2_tracks() {
    let seq = sequence(DepthNoise::phone_like(), 21);
    let frames = 90;
    let rendered = common::frames(&seq, frames);
    for mode in [Mode::Naive, Mode::L1, Mode::L2] {
        let (odo, outs) = run_frames(config(&seq, mode), &rendered);
        let c = odo.tracker().counters();
        assert_eq!(c.frames, frames as u64);
        assert_eq!(c.lost_frames, 0, "{mode:?}");
        let refs: u64 = c.references.iter().sum();
        assert_eq!(
            c.motion_estimations,
            (frames as u64 - 1) + refs + c.refinements,
            "{mode:?}: {c:?}"
        );
        // Per-frame outputs agree with the counters.
        let per_frame: u64 = outs.iter().map(|o| o.motion_estimations as u64).sum();
        assert_eq!(per_frame, c.motion_estimations);
        for (k, &n) in c.references.iter().enumerate() {
            assert_eq!(
                outs.iter()
                    .filter(|o| o.reference_levels as usize > k)
                    .count() as u64,
                n
            );
        }
        match mode {
            Mode::Naive => assert!(c.references.is_empty()),
            Mode::L1 => assert!(c.references[0] > 5),
            Mode::L2 => assert!(
                c.references[0] > 5 && c.references[1] > 0 && c.references[1] <= c.references[0]
            ),
        }
        let rmse = drift_rmse(&seq, &outs);
        println!("{mode:?}: {c:?}, drift RMSE {:.2} mm", rmse * 1e3);
        // 3 s of hand-held motion with phone-like depth noise. Measured: naive 2.4 mm,
        // L1 1.1 mm, L2 0.5 mm; the bounds leave a margin of about 2x.
        let bound = if mode == Mode::Naive { 0.006 } else { 0.003 };
        assert!(rmse < bound, "{mode:?}: drift RMSE {:.2} mm", rmse * 1e3);
    }
}

#[test]
fn memory_is_bounded_by_the_levels() {
    let seq = sequence(DepthNoise::phone_like(), 4);
    let (odo, _) = run(&seq, config(&seq, Mode::L2), 60);
    // Previous frame, one per level, and the frame being prepared.
    assert!(
        odo.frames_allocated() <= 2 + 2,
        "{} frames allocated",
        odo.frames_allocated()
    );
    let kept: Vec<u64> = odo
        .tracker()
        .references()
        .map(|r| r.unwrap().index)
        .collect();
    assert_eq!(kept.len(), 2);
}

#[test]
fn lost_frames_keep_the_last_pose_and_tracking_resumes() {
    let seq = sequence(DepthNoise::phone_like(), 9);
    let cfg = config(&seq, Mode::L2);
    let mut odo = Odometry::new(cfg.clone()).unwrap();
    let n = cfg.camera.pixels();
    let (blank_i, blank_d) = (vec![0u8; n], vec![0u16; n]);
    let mut last_good = Pose::identity();
    let mut outs = Vec::new();
    for i in 0..40 {
        let f = seq.frame(i);
        let view = if (20..23).contains(&i) {
            FrameView {
                timestamp: f.timestamp,
                intensity: &blank_i,
                depth: &blank_d,
            }
        } else {
            FrameView {
                timestamp: f.timestamp,
                intensity: &f.intensity,
                depth: &f.depth,
            }
        };
        let o = odo.push(view).unwrap();
        if (20..23).contains(&i) {
            assert_eq!(o.state, TrackingState::Lost, "frame {i}");
            assert_eq!(o.pose, last_good, "a lost frame keeps the last good pose");
        } else {
            assert_eq!(o.state, TrackingState::Tracking, "frame {i}");
            last_good = o.pose;
        }
        outs.push(o);
    }
    assert_eq!(odo.tracker().counters().lost_frames, 3);
    // Frame 23 registered against frame 19, the last good one: still accurate.
    let rmse = drift_rmse(&seq, &outs);
    assert!(rmse < 0.02, "drift RMSE {:.1} mm", rmse * 1e3);
}

#[test]
fn a_long_loss_reanchors_at_the_last_pose_on_a_good_frame() {
    // Frames 0..3, then 6 blank frames (no depth, no texture: never an anchor), then
    // frames of another room, out of reach of the kept frames: the first of them
    // comes after more than max_lost_frames lost frames and becomes the new anchor
    // at the last good pose.
    let seq = sequence(DepthNoise::phone_like(), 2);
    let other = sequence(DepthNoise::phone_like(), 31);
    let mut cfg = config(&seq, Mode::L1);
    cfg.max_lost_frames = 2;
    let mut odo = Odometry::new(cfg.clone()).unwrap();
    let n = cfg.camera.pixels();
    let (blank_i, blank_d) = (vec![0u8; n], vec![0u16; n]);
    let mut outs = Vec::new();
    let frames: Vec<Option<usize>> = (0..3)
        .map(Some)
        .chain((0..6).map(|_| None))
        .chain((100..106).map(Some))
        .collect();
    for (k, f) in frames.iter().enumerate() {
        let o = match f {
            Some(i) => {
                let f = if *i < 100 {
                    seq.frame(*i)
                } else {
                    other.frame(*i)
                };
                odo.push(FrameView {
                    timestamp: k as f64 / 30.0,
                    intensity: &f.intensity,
                    depth: &f.depth,
                })
            }
            None => odo.push(FrameView {
                timestamp: k as f64 / 30.0,
                intensity: &blank_i,
                depth: &blank_d,
            }),
        }
        .unwrap();
        assert!(se3::is_finite(&o.pose));
        if f.is_none() {
            assert_eq!(o.state, TrackingState::Lost, "blank frame {k}");
            assert!(!o.reanchored, "blank frame {k} must not become an anchor");
        }
        outs.push(o);
    }
    let first_anchor = outs.iter().position(|o| o.reanchored);
    // Frame 9 is the first good frame after the blanks, already past max_lost_frames.
    assert_eq!(
        first_anchor,
        Some(9),
        "{:?}",
        outs.iter()
            .map(|o| (o.state, o.reanchored))
            .collect::<Vec<_>>()
    );
    assert_eq!(
        outs[9].pose, outs[2].pose,
        "the anchor keeps the last good pose"
    );
    for o in &outs[10..] {
        assert_eq!(
            o.state,
            TrackingState::Tracking,
            "frame {} after the anchor",
            o.index
        );
    }
    assert_eq!(odo.tracker().counters().reanchors, 1);
    assert_eq!(odo.tracker().counters().lost_frames, 7);
}

#[test]
fn a_frame_that_fails_frame_to_frame_recovers_against_a_reference() {
    // Frame 20 keeps depth on a few pixels only: it still registers (photometrically)
    // against frame 19, but as the previous frame it offers too few template points
    // for frame 21's [A]. Frame 21 is then registered against the level-1 reference
    // instead of being lost.
    let seq = sequence(DepthNoise::none(), 4);
    let cfg = config(&seq, Mode::L2);
    let mut odo = Odometry::new(cfg.clone()).unwrap();
    let mut outs = Vec::new();
    for i in 0..30 {
        let f = seq.frame(i);
        let mut depth = f.depth.clone();
        if i == 20 {
            for (k, d) in depth.iter_mut().enumerate() {
                if k % 997 != 0 {
                    *d = 0;
                }
            }
        }
        let o = odo
            .push(FrameView {
                timestamp: f.timestamp,
                intensity: &f.intensity,
                depth: &depth,
            })
            .unwrap();
        outs.push(o);
    }
    let c = odo.tracker().counters();
    assert!(
        !outs[21].frame_to_frame.unwrap().is_ok(),
        "[A] of frame 21 fails"
    );
    assert!(outs[21].recovered, "frame 21 recovered against a reference");
    assert_eq!(outs[21].state, TrackingState::Tracking);
    assert_eq!(c.lost_frames, 0);
    assert!(c.recovered_frames >= 1);
    let (dt, da) = pose_error(&outs[21].pose, &(seq.pose(0).inverse() * seq.pose(21)));
    assert!(
        dt < 0.01 && da < 0.5,
        "recovered pose off by {:.1} mm {da:.2} deg",
        dt * 1e3
    );
    let rmse = drift_rmse(&seq, &outs);
    assert!(rmse < 0.01, "drift RMSE {:.1} mm", rmse * 1e3);
}

#[test]
fn refused_corrections_do_not_promote_and_are_counted() {
    // A correction gate of ~0 refuses every correction: no frame becomes a reference
    // through a correction, each refusal is counted, and after
    // MAX_REFUSED_CORRECTIONS in a row the reference is replaced without one (counted
    // as stale). The counters add up to the MOTION calls made.
    let seq = sequence(DepthNoise::phone_like(), 6);
    // The chain's corrections ([B] after [A]; keyframe tracking corrects level 1
    // by registering against the keyframe).
    let mut cfg = config(&seq, Mode::L1);
    cfg.keyframes = false;
    cfg.max_correction_distance = 1e-12;
    let mut odo = Odometry::new(cfg.clone()).unwrap();
    let mut last_ref = 0;
    let rendered = common::frames(&seq, 90);
    for (i, f) in rendered.iter().enumerate() {
        let o = odo
            .push(FrameView {
                timestamp: f.timestamp,
                intensity: &f.intensity,
                depth: &f.depth,
            })
            .unwrap();
        if o.refused_corrections > 0 {
            assert_eq!(o.reference_levels, 0, "frame {i}: refused yet promoted");
            // The pose is the uncorrected one: previous pose times [A].
        }
        if o.reference_levels > 0 {
            last_ref = i;
        }
    }
    let c = odo.tracker().counters();
    assert!(c.rejected_corrections > 0, "{c:?}");
    assert_eq!(c.failed_corrections, 0);
    assert!(c.stale_references > 0, "{c:?}");
    assert_eq!(c.references[0], c.stale_references, "{c:?}");
    assert!(last_ref > 0);
    assert_eq!(
        c.motion_estimations,
        (c.frames - 1) + c.rejected_corrections + c.failed_corrections + c.refinements,
        "{c:?}"
    );
    // With the default gate the same stream's corrections are accepted.
    let mut chain = config(&seq, Mode::L1);
    chain.keyframes = false;
    let (odo, _) = run_frames(chain, &rendered);
    let c = odo.tracker().counters();
    assert!(
        c.references[0] > 0 && c.rejected_corrections * 10 <= c.references[0],
        "{c:?}"
    );
}

#[test]
fn correction_distance_grows_with_the_move() {
    let seq = sequence(DepthNoise::none(), 8);
    let cfg = config(&seq, Mode::L1);
    let (fa, pa) = prepared(&seq, 10, &cfg);
    let (fb, pb) = prepared(&seq, 14, &cfg);
    let truth = pa.inverse() * pb;
    let mut est = ecvo_core::MotionEstimator::new();
    let r = est.motion(&fb, &fa, &truth, &cfg.motion);
    assert!(r.is_ok());
    let d0 = ecvo_core::tracker::correction_distance(&r.pose, &r);
    assert!(d0.abs() < 1e-9, "{d0}");
    let mut last = 0.0;
    for mm in [1.0, 5.0, 20.0] {
        let off = truth * se3::exp(&nalgebra::Vector6::new(mm * 1e-3, 0.0, 0.0, 0.0, 0.0, 0.0));
        let d = ecvo_core::tracker::correction_distance(&off, &r);
        assert!(d > last, "{mm} mm: {d} <= {last}");
        last = d;
    }
}

#[test]
fn bad_frames_are_errors_not_panics() {
    let seq = sequence(DepthNoise::none(), 1);
    let mut odo = Odometry::new(config(&seq, Mode::L2)).unwrap();
    let short = vec![0u8; 10];
    let depth = vec![0u16; 320 * 180];
    assert!(
        odo.push(FrameView {
            timestamp: 0.0,
            intensity: &short,
            depth: &depth
        })
        .is_err()
    );
    let img = vec![0u8; 320 * 180];
    assert!(
        odo.push(FrameView {
            timestamp: f64::NAN,
            intensity: &img,
            depth: &depth
        })
        .is_err()
    );
    assert_eq!(odo.tracker().counters().frames, 0);
    let mut bad = config(&seq, Mode::L2);
    bad.camera.fx = f64::NAN;
    assert!(Odometry::new(bad).is_err());
}
