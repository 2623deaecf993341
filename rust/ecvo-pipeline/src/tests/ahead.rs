//! The filter stage's [A] computed ahead gives the sequential engine's poses, bit for
//! bit: with a depth-noise model that changes mid-stream, and around lost frames.

use super::*;

/// The tracker stage's sleep per frame in these tests (see
/// [`pipelined_with_slow_tracker`]).
const SLOW_TRACKER_MS: u64 = 15;

/// The sequential engine's outputs for `frames`.
fn sequential(odo: &mut ecvo_core::Odometry, frames: &[Frame]) -> Vec<FrameOutput> {
    frames
        .iter()
        .map(|f| {
            odo.push(FrameView {
                timestamp: f.timestamp,
                intensity: &f.intensity,
                depth: &f.depth,
            })
            .unwrap()
        })
        .collect()
}

/// Runs `frames` through a two-thread pipeline whose tracker stage sleeps `delay_ms`
/// a frame (so the filter stage computes \[A\] ahead: the delay must outlast the
/// filter stage's frame, preparation and \[A\], even on a loaded machine; at 4 ms
/// the around-lost-frames test once saw 1 \[A\] used, at load 12), checks that every pose is
/// `expected`'s bit for bit and every state the same, and returns the statistics.
fn pipelined_with_slow_tracker(
    config: Config,
    frames: Vec<Frame>,
    delay_ms: u64,
    expected: Vec<FrameOutput>,
) -> PipelineStats {
    within_a_minute(move || {
        let p = Pipeline::new(
            config,
            PipelineOptions {
                threads: 2,
                keep_trajectory: true,
                test_hooks: TestHooks {
                    delay: Some((Stage::Tracker, Duration::from_millis(delay_ms))),
                    ..TestHooks::default()
                },
                ..PipelineOptions::default()
            },
        )
        .unwrap();
        for f in &frames {
            push(&p, f).unwrap();
        }
        let summary = p.finish().unwrap();
        assert_eq!(summary.trajectory.len(), expected.len());
        for (i, (r, e)) in summary.trajectory.iter().zip(&expected).enumerate() {
            assert_eq!(
                r.pose.to_homogeneous().map(f64::to_bits),
                e.pose.to_homogeneous().map(f64::to_bits),
                "frame {i}"
            );
            assert_eq!(r.state, e.state, "frame {i}");
        }
        summary.stats
    })
}

/// Under the fitted depth-noise model (the default) the tracker changes its model
/// while tracking; the \[A\]s the filter stage computed ahead with the old model are
/// not used after a change, and the poses stay the sequential engine's, bit for bit.
#[test]
fn a_depth_noise_model_that_changes_mid_stream_keeps_the_sequential_poses() {
    // [A] is computed ahead only for the chain (with keyframe tracking the
    // filter stage does not know the keyframe).
    let (mut config, frames) = stream(60);
    config.keyframes = false;
    assert_eq!(
        config.motion.depth_noise,
        ecvo_core::DepthNoiseModel::Fitted
    );
    let mut odo = ecvo_core::Odometry::new(config.clone()).unwrap();
    let expected = sequential(&mut odo, &frames);
    let refits = odo.tracker().counters().noise_refits;
    assert!(
        refits >= 1,
        "the model never changed: {:?}",
        odo.tracker().counters()
    );
    let model = odo.tracker().depth_noise();
    let stats = pipelined_with_slow_tracker(config, frames, SLOW_TRACKER_MS, expected);
    assert_eq!(stats.counters.noise_refits, refits);
    assert_eq!(stats.depth_noise, model);
    assert!(stats.ahead_used > 10, "{} used", stats.ahead_used);
}

/// With a slow tracker the filter stage computes \[A\] ahead; a frame whose previous
/// frame was lost must not use the \[A\] computed against it. Either way the poses
/// are those of the sequential engine, bit for bit.
#[test]
fn frame_to_frame_computed_ahead_gives_the_sequential_poses_even_around_lost_frames() {
    // The chain: see above.
    let (mut config, mut frames) = stream(40);
    config.keyframes = false;
    // Frames 12, 13 and 25 are blank: they are lost, and the frames after them
    // register against an older frame than the one the filter stage used.
    for k in [12, 13, 25] {
        frames[k].depth.fill(0);
        frames[k].intensity.fill(128);
    }
    let mut odo = ecvo_core::Odometry::new(config.clone()).unwrap();
    let expected = sequential(&mut odo, &frames);
    assert_eq!(
        odo.tracker().counters().lost_frames,
        3,
        "{:?}",
        odo.tracker().counters()
    );
    let stats = pipelined_with_slow_tracker(config, frames, SLOW_TRACKER_MS, expected);
    assert!(stats.ahead_used > 10, "{} used", stats.ahead_used);
    // The frames after a lost one: computed against it, and not used.
    assert!(
        stats.ahead_computed > stats.ahead_used,
        "{} computed, {} used",
        stats.ahead_computed,
        stats.ahead_used
    );
}
