//! What each frame's output says about its quality: the registration its pose came
//! from, why a lost frame was lost, and an outside guess seeding \[A\].

use crate::common::*;
use ecvo_core::{FrameView, LostReason, Mode, MotionPrior, Odometry, Pose, TrackingState};
use ecvo_synth::DepthNoise;

fn push(odo: &mut Odometry, t: f64, intensity: &[u8], depth: &[u16]) -> ecvo_core::FrameOutput {
    odo.push(FrameView {
        timestamp: t,
        intensity,
        depth,
    })
    .unwrap()
}

#[test]
fn tracked_frames_carry_their_registration_and_lost_ones_a_reason() {
    let seq = sequence(DepthNoise::phone_like(), 4);
    let mut odo = Odometry::new(config(&seq, Mode::L2)).unwrap();
    let mut outs = Vec::new();
    for i in 0..12 {
        let f = seq.frame(i);
        // Frame 6 has no depth and a flat intensity; frame 9 is a far view turned
        // upside down (no rigid motion explains it).
        let depth = if i == 6 {
            vec![0; f.depth.len()]
        } else if i == 9 {
            seq.frame(60).depth.clone()
        } else {
            f.depth.clone()
        };
        let intensity = if i == 6 {
            vec![128; f.intensity.len()]
        } else if i == 9 {
            seq.frame(60).intensity.iter().rev().copied().collect()
        } else {
            f.intensity.clone()
        };
        outs.push(push(&mut odo, f.timestamp, &intensity, &depth));
    }
    assert!(outs[0].registration.is_none() && outs[0].lost_reason.is_none());
    for (k, o) in outs.iter().enumerate() {
        match o.state {
            TrackingState::Tracking => {
                assert!(o.lost_reason.is_none(), "frame {k}");
                if k == 0 {
                    continue;
                }
                let r = o
                    .registration
                    .expect("a tracked frame has its registration");
                assert!(r.is_ok(), "frame {k}");
                assert!(r.valid_pixels > 0 && r.valid_pixels <= r.template_points);
                let h = r.information;
                assert!((h - h.transpose()).abs().max() <= 1e-9 * h.abs().max());
                assert!(h.cholesky().is_some(), "frame {k}: information not SPD");
            }
            TrackingState::Lost => {
                assert!(o.registration.is_none(), "frame {k}");
                assert!(o.lost_reason.is_some(), "frame {k} lost without a reason");
            }
            TrackingState::Initialising => unreachable!(),
        }
    }
    assert_eq!(outs[6].state, TrackingState::Lost);
    assert_eq!(outs[6].lost_reason, Some(LostReason::NoValidDepth));
    assert_eq!(outs[9].state, TrackingState::Lost);
    assert_eq!(outs[9].lost_reason, Some(LostReason::Inconsistent));
    assert_eq!(
        odo.tracker().counters().lost_frames as usize,
        outs.iter()
            .filter(|o| o.state == TrackingState::Lost)
            .count()
    );
}

#[test]
fn an_outside_guess_seeds_the_registration_and_a_wrong_one_loses_to_the_identity() {
    // Frames 0 and 48 (0.43 m apart). [A] starts from the identity and from the guess;
    // the truth as the guess wins the coarsest step, a guess 1.2 m off loses to the
    // identity, and both end at the truth.
    let seq = sequence(DepthNoise::phone_like(), 21);
    let mut cfg = config(&seq, Mode::Naive);
    cfg.max_speed_m_s = 1e3;
    cfg.motion.prior = MotionPrior::Identity;
    let (a, b) = (seq.frame(0), seq.frame(48));
    let truth = seq.pose(0).inverse() * seq.pose(48);
    let wrong = Pose::translation(1.0, -0.5, 0.5) * truth;
    for (guess, winner) in [(truth, 1), (wrong, 0)] {
        let mut odo = Odometry::new(cfg.clone()).unwrap();
        odo.set_guess(Pose::translation(5.0, 0.0, 0.0)); // ignored: the first frame
        let first = push(&mut odo, a.timestamp, &a.intensity, &a.depth);
        assert_eq!(first.pose, Pose::identity());
        odo.set_guess(guess);
        let o = push(&mut odo, b.timestamp, &b.intensity, &b.depth);
        let (dt, da) = pose_error(&o.pose, &truth);
        assert_eq!(o.state, TrackingState::Tracking);
        assert_eq!(o.registration.unwrap().start, winner);
        assert!(dt < 0.002 && da < 0.1, "{dt} {da}");
        // Used once: the next frame starts from the identity alone.
        let c = seq.frame(49);
        let next = push(&mut odo, c.timestamp, &c.intensity, &c.depth);
        assert_eq!(next.registration.unwrap().start, 0);
    }
}
