//! Unit tests that use the fault-injection hooks: panics in each stage, a slow
//! tracker in live mode, dropping without `finish`.

use std::sync::mpsc;
use std::time::Duration;

use ecvo_core::{Camera, Config, Mode, Preset};
use ecvo_synth::SynthSequence;

use super::*;

struct Frame {
    timestamp: f64,
    intensity: Vec<u8>,
    depth: Vec<u16>,
}

fn stream(n: usize) -> (Config, Vec<Frame>) {
    let seq = SynthSequence::phone_320x180(n, 3);
    let c = seq.camera;
    let camera = Camera {
        width: c.width,
        height: c.height,
        fx: c.fx,
        fy: c.fy,
        cx: c.cx,
        cy: c.cy,
        depth_scale: c.depth_scale,
    };
    let frames = seq
        .iter()
        .map(|f| Frame {
            timestamp: f.timestamp,
            intensity: f.intensity,
            depth: f.depth,
        })
        .collect();
    (Config::new(camera, Preset::Pc, Mode::L2), frames)
}

fn push(p: &Pipeline, f: &Frame) -> Result<PushStatus> {
    p.push(f.timestamp, |i, d| {
        i.copy_from_slice(&f.intensity);
        d.copy_from_slice(&f.depth);
    })
}

/// Runs `f` on another thread and fails the test if it takes longer than a minute.
fn within_a_minute<T: Send + 'static>(f: impl FnOnce() -> T + Send + 'static) -> T {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(f());
    });
    rx.recv_timeout(Duration::from_secs(60))
        .expect("the pipeline hung")
}

#[test]
fn the_pipeline_is_send_and_sync() {
    fn check<T: Send + Sync>() {}
    check::<Pipeline>();
    check::<PooledFrame>();
}

#[test]
fn a_panic_in_any_stage_reaches_the_caller_as_an_error() {
    for stage in [Stage::Filter, Stage::Tracker, Stage::Geometry] {
        let (first_error, finished) = within_a_minute(move || {
            let (config, frames) = stream(12);
            let p = Pipeline::new(
                config,
                PipelineOptions {
                    geometry: Some(GeometryOptions::default()),
                    queue_capacity: 1,
                    test_hooks: TestHooks {
                        // Frame 0 is always a reference frame, so the geometry stage
                        // sees it.
                        panic_at: Some((stage, if stage == Stage::Geometry { 0 } else { 5 })),
                        delay: None,
                    },
                    ..PipelineOptions::default()
                },
            )
            .unwrap();
            // Keep pushing: once the stage has panicked, a push (even one blocked on a
            // full queue) fails instead of waiting forever.
            let mut first_error = None;
            for f in frames.iter().cycle().take(200) {
                if let Err(e) = push(&p, f) {
                    first_error = Some(e);
                    break;
                }
            }
            assert!(p.flush().is_err());
            (first_error, p.finish())
        });
        let want = |e: &Error| matches!(e, Error::StagePanicked { stage: s, message } if *s == stage && message.contains("injected panic"));
        assert!(
            first_error.as_ref().is_some_and(want),
            "{stage}: {first_error:?}"
        );
        assert!(finished.as_ref().is_err_and(want), "{stage}: {finished:?}");
    }
}

#[test]
fn a_panic_while_the_caller_waits_in_flush_or_finish_is_reported() {
    let result = within_a_minute(|| {
        let (config, frames) = stream(8);
        let p = Pipeline::new(
            config,
            PipelineOptions {
                queue_capacity: 8,
                test_hooks: TestHooks {
                    panic_at: Some((Stage::Tracker, 6)),
                    delay: None,
                },
                ..PipelineOptions::default()
            },
        )
        .unwrap();
        for f in &frames {
            // The queues hold all 8 frames, so every push succeeds before the panic.
            let _ = push(&p, f);
        }
        let flushed = p.flush();
        (flushed, p.finish().map(|s| s.stats.tracked))
    });
    assert!(matches!(
        result.0,
        Err(Error::StagePanicked {
            stage: Stage::Tracker,
            ..
        })
    ));
    assert!(matches!(
        result.1,
        Err(Error::StagePanicked {
            stage: Stage::Tracker,
            ..
        })
    ));
}

#[test]
fn live_mode_with_a_slow_tracker_keeps_latency_bounded() {
    let (config, frames) = stream(30);
    let p = Pipeline::new(
        config,
        PipelineOptions {
            admission: Admission::Live,
            queue_capacity: 2,
            test_hooks: TestHooks {
                panic_at: None,
                delay: Some((Stage::Tracker, Duration::from_millis(30))),
            },
            ..PipelineOptions::default()
        },
    )
    .unwrap();
    // A 100 Hz camera into a tracker that takes over 30 ms per frame.
    let mut statuses = Vec::new();
    let mut pushing = Duration::ZERO;
    for f in &frames {
        let t0 = Instant::now();
        statuses.push(push(&p, f).unwrap());
        pushing += t0.elapsed();
        std::thread::sleep(Duration::from_millis(10));
    }
    // Blocking on the tracker would take over 20 tracker periods (600 ms).
    assert!(
        pushing < Duration::from_millis(200),
        "push waited {pushing:?}"
    );
    p.flush().unwrap();
    let st = p.stats();
    assert_eq!(st.pushed, 30);
    assert!(st.dropped >= 10, "{st:?}");
    assert_eq!(st.tracked + st.dropped, st.pushed);
    // `push` reports the drops it made itself, at the input queue; the filter drops
    // at the tracker's queue when the filter keeps up and the tracker does not.
    let reported = statuses
        .iter()
        .filter(|s| **s == PushStatus::DroppedOldest)
        .count();
    assert_eq!(reported as u64, st.dropped_at_input);
    // At most the two queues and the frames in the two stages stand between a push and
    // its pose: about 6 tracker periods, never the whole backlog of 30 frames.
    assert!(st.latency.max_ms < 400.0, "{:?}", st.latency);
    p.finish().unwrap();
}

#[test]
fn dropping_without_finish_stops_and_joins_every_thread() {
    let (config, frames) = stream(6);
    let p = Pipeline::new(
        config,
        PipelineOptions {
            threads: 3,
            geometry: Some(GeometryOptions::default()),
            output_queue: Some(1),
            ..PipelineOptions::default()
        },
    )
    .unwrap();
    // Outputs nobody reads: the tracker is blocked on them when the pipeline is dropped.
    let rx = p.outputs().unwrap();
    for f in &frames {
        push(&p, f).unwrap();
    }
    let shared = Arc::downgrade(&p.shared);
    let workers = p.workers.clone();
    within_a_minute(move || drop(p));
    assert!(
        shared.upgrade().is_none(),
        "a stage thread still holds the state"
    );
    assert_eq!(*lock(&workers.alive), 0, "compute threads still running");
    drop(rx);
}

#[test]
fn a_panicking_fill_returns_the_buffer_and_the_pipeline_goes_on() {
    let (config, frames) = stream(3);
    let p = Pipeline::new(config, PipelineOptions::default()).unwrap();
    for _ in 0..10 {
        let r = std::panic::catch_unwind(AssertUnwindSafe(|| {
            p.push(0.0, |_, _| panic!("fill failed"))
        }));
        assert!(r.is_err());
    }
    for f in &frames {
        push(&p, f).unwrap();
    }
    assert_eq!(p.finish().unwrap().stats.tracked, 3);
}

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
/// a frame (so the filter stage computes \[A\] ahead), checks that every pose is
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
    let (config, frames) = stream(60);
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
    let stats = pipelined_with_slow_tracker(config, frames, 3, expected);
    assert_eq!(stats.counters.noise_refits, refits);
    assert_eq!(stats.depth_noise, model);
    assert!(stats.ahead_used > 10, "{} used", stats.ahead_used);
}

/// With a slow tracker the filter stage computes \[A\] ahead; a frame whose previous
/// frame was lost must not use the \[A\] computed against it. Either way the poses
/// are those of the sequential engine, bit for bit.
#[test]
fn frame_to_frame_computed_ahead_gives_the_sequential_poses_even_around_lost_frames() {
    let (config, mut frames) = stream(40);
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
    let stats = pipelined_with_slow_tracker(config, frames, 4, expected);
    assert!(stats.ahead_used > 10, "{} used", stats.ahead_used);
    // The frames after a lost one: computed against it, and not used.
    assert!(
        stats.ahead_computed > stats.ahead_used,
        "{} computed, {} used",
        stats.ahead_computed,
        stats.ahead_used
    );
}

#[test]
fn non_increasing_timestamps_are_refused_and_counted_and_the_pipeline_goes_on() {
    let (config, frames) = stream(4);
    for admission in [Admission::Offline, Admission::Live] {
        let p = Pipeline::new(
            config.clone(),
            PipelineOptions {
                admission,
                keep_trajectory: true,
                ..PipelineOptions::default()
            },
        )
        .unwrap();
        push(&p, &frames[0]).unwrap();
        push(&p, &frames[1]).unwrap();
        // The same timestamp again (new content), then an earlier one.
        let same = p.push(frames[1].timestamp, |i, d| {
            i.copy_from_slice(&frames[2].intensity);
            d.copy_from_slice(&frames[2].depth);
        });
        assert!(
            matches!(same, Err(Error::TimestampNotIncreasing { previous, timestamp })
                if previous == frames[1].timestamp && timestamp == frames[1].timestamp),
            "{same:?}"
        );
        let back = p.push(frames[0].timestamp, |_, _| {
            panic!("a refused frame is not copied")
        });
        assert!(
            matches!(back, Err(Error::TimestampNotIncreasing { .. })),
            "{back:?}"
        );
        push(&p, &frames[2]).unwrap();
        push(&p, &frames[3]).unwrap();
        p.flush().unwrap();
        let st = p.stats();
        assert_eq!(st.timestamps_rejected, 2, "{st:?}");
        assert_eq!(st.pushed, 4);
        assert_eq!(st.tracked + st.dropped, 4);
        let all = p.trajectory();
        let stamps: Vec<f64> = all.iter().map(|r| r.timestamp).collect();
        assert!(stamps.windows(2).all(|w| w[0] < w[1]), "{stamps:?}");
        // The incremental read returns exactly the tail, and nothing past the end.
        assert!(all.len() >= 2, "{}", all.len());
        for from in 0..=all.len() + 2 {
            let want = all.get(from..).unwrap_or(&[]);
            assert_eq!(p.trajectory_since(from as u64), want, "from {from}");
        }
        p.finish().unwrap();
    }
}

#[test]
fn a_frame_identical_to_the_previous_one_is_reported_repeated_and_not_tracked() {
    let (config, frames) = stream(3);
    let p = Pipeline::new(
        config,
        PipelineOptions {
            keep_trajectory: true,
            ..PipelineOptions::default()
        },
    )
    .unwrap();
    let same_as = |t: f64, f: &Frame| {
        p.push(t, |i, d| {
            i.copy_from_slice(&f.intensity);
            d.copy_from_slice(&f.depth);
        })
    };
    assert_eq!(push(&p, &frames[0]).unwrap(), PushStatus::Accepted);
    // Frame 0 again at new times: repeated, each time.
    assert_eq!(same_as(0.5, &frames[0]).unwrap(), PushStatus::Repeated);
    assert_eq!(same_as(0.6, &frames[0]).unwrap(), PushStatus::Repeated);
    // One pixel of depth differs: a new frame.
    let mut f = Frame {
        timestamp: 0.7,
        intensity: frames[0].intensity.clone(),
        depth: frames[0].depth.clone(),
    };
    f.depth[1234] ^= 1;
    assert_eq!(push(&p, &f).unwrap(), PushStatus::Accepted);
    // One pixel of intensity differs: new again.
    f.timestamp = 0.8;
    f.intensity[77] ^= 0x80;
    assert_eq!(push(&p, &f).unwrap(), PushStatus::Accepted);
    // The repeated frame's timestamp counted as the last one.
    assert!(matches!(
        same_as(0.55, &frames[1]),
        Err(Error::TimestampNotIncreasing { .. })
    ));
    assert_eq!(same_as(1.0, &frames[1]).unwrap(), PushStatus::Accepted);
    let summary = p.finish().unwrap();
    assert_eq!(summary.stats.repeated_frames, 2);
    assert_eq!(summary.stats.pushed, 4);
    assert_eq!(summary.stats.tracked, 4);
    let stamps: Vec<f64> = summary.trajectory.iter().map(|r| r.timestamp).collect();
    assert_eq!(stamps, [frames[0].timestamp, 0.7, 0.8, 1.0]);
}

#[test]
fn the_frame_hash_sees_every_sample() {
    let i = vec![7u8; 21];
    let d = vec![300u16; 21];
    let h = frame_hash(&i, &d);
    assert_eq!(h, frame_hash(&i.clone(), &d.clone()));
    for k in 0..21 {
        let mut i2 = i.clone();
        i2[k] ^= 1;
        assert_ne!(h, frame_hash(&i2, &d), "intensity {k}");
        let mut d2 = d.clone();
        d2[k] ^= 0x100;
        assert_ne!(h, frame_hash(&i, &d2), "depth {k}");
    }
    // The same bytes split differently between the planes are another frame.
    assert_ne!(frame_hash(&[], &[0; 4]), frame_hash(&[0; 8], &[]));
}

#[test]
fn frames_without_depth_are_never_repeated() {
    let (config, frames) = stream(1);
    let p = Pipeline::new(config, PipelineOptions::default()).unwrap();
    push(&p, &frames[0]).unwrap();
    for k in 1..4 {
        let st = p.push(k as f64, |i, d| {
            i.fill(0);
            d.fill(0);
        });
        assert_eq!(st.unwrap(), PushStatus::Accepted, "blank frame {k}");
    }
    let st = p.finish().unwrap().stats;
    assert_eq!((st.tracked, st.repeated_frames), (4, 0));
}

#[test]
fn a_trajectory_window_keeps_the_latest_poses_and_the_same_poses() {
    let (config, frames) = stream(14);
    let run = |window: Option<usize>| {
        let p = Pipeline::new(
            config.clone(),
            PipelineOptions {
                keep_trajectory: true,
                trajectory_window: window,
                ..PipelineOptions::default()
            },
        )
        .unwrap();
        for f in &frames {
            push(&p, f).unwrap();
        }
        p.flush().unwrap();
        let live = (
            p.trajectory(),
            p.references(),
            p.trajectory_start(),
            p.trajectory_since(0),
            p.trajectory_since(12),
        );
        (live, p.finish().unwrap())
    };
    let (_, all) = run(None);
    let ((kept, refs, start, since0, since12), summary) = run(Some(5));
    assert_eq!(all.trajectory.len(), 14);
    assert_eq!(start, 9);
    assert_eq!(summary.stats.poses_discarded, 9);
    assert_eq!(all.stats.poses_discarded, 0);
    // The window is the tail of the whole trajectory, bit for bit.
    assert_eq!(kept, all.trajectory[9..]);
    assert_eq!(summary.trajectory, kept);
    // Asked from before the window, the read starts at the window (see `index`).
    assert_eq!(since0, kept);
    assert_eq!(since12, all.trajectory[12..]);
    // The references kept are those among the kept poses.
    let want: Vec<PoseRecord> = all
        .references
        .iter()
        .filter(|r| r.index >= 9)
        .copied()
        .collect();
    assert_eq!(refs, want);
    assert_eq!(summary.references, want);
}

#[test]
fn an_empty_trajectory_window_is_refused() {
    let (config, _) = stream(1);
    let r = Pipeline::new(
        config,
        PipelineOptions {
            keep_trajectory: true,
            trajectory_window: Some(0),
            ..PipelineOptions::default()
        },
    );
    assert!(
        matches!(
            &r,
            Err(Error::InvalidOptions {
                field: "trajectory_window",
                ..
            })
        ),
        "{:?}",
        r.as_ref().err()
    );
}

#[test]
fn live_pushes_from_many_threads_report_every_drop_and_return_the_extra_buffers() {
    let (config, frames) = stream(4);
    let frames = Arc::new(frames);
    let p = Arc::new(
        Pipeline::new(
            config,
            PipelineOptions {
                admission: Admission::Live,
                queue_capacity: 1,
                test_hooks: TestHooks {
                    panic_at: None,
                    delay: Some((Stage::Filter, Duration::from_millis(3))),
                },
                ..PipelineOptions::default()
            },
        )
        .unwrap(),
    );
    // Six threads push at once, more than the pool's 4 raw buffers can serve, with
    // frames that often repeat the last one pushed by another thread. Each thread's
    // first push fills its buffer only once all six hold one, so that the pool must
    // allocate for the extra pushers whatever the scheduling.
    let clock = Arc::new(Mutex::new(0.0f64));
    let gate = Arc::new(std::sync::Barrier::new(6));
    let counts = within_a_minute({
        let (p, frames, clock) = (Arc::clone(&p), Arc::clone(&frames), Arc::clone(&clock));
        move || {
            let workers: Vec<_> = (0..6)
                .map(|t| {
                    let (p, frames, clock, gate) = (
                        Arc::clone(&p),
                        Arc::clone(&frames),
                        Arc::clone(&clock),
                        Arc::clone(&gate),
                    );
                    std::thread::spawn(move || {
                        let mut c = [0u64; 4];
                        for k in 0..150 {
                            let f = &frames[(t + k / 7) % 2];
                            let ts = {
                                let mut g = clock.lock().unwrap();
                                *g += 0.01;
                                *g
                            };
                            match p.push(ts, |i, d| {
                                if k == 0 {
                                    gate.wait();
                                }
                                i.copy_from_slice(&f.intensity);
                                d.copy_from_slice(&f.depth);
                            }) {
                                Ok(PushStatus::Accepted) => c[0] += 1,
                                Ok(PushStatus::DroppedOldest) => c[1] += 1,
                                Ok(PushStatus::Repeated) => c[2] += 1,
                                Err(Error::TimestampNotIncreasing { .. }) => c[3] += 1,
                                Err(e) => panic!("{e}"),
                            }
                        }
                        c
                    })
                })
                .collect();
            workers.into_iter().fold([0u64; 4], |mut a, w| {
                let c = w.join().unwrap();
                for (a, c) in a.iter_mut().zip(c) {
                    *a += c;
                }
                a
            })
        }
    });
    p.flush().unwrap();
    let st = p.stats();
    let [accepted, dropped, repeated, refused] = counts;
    assert_eq!(accepted + dropped + repeated + refused, 900);
    assert_eq!(st.pushed, accepted + dropped, "{st:?}");
    // Every frame dropped at the input was reported to a pusher, and none is lost
    // without a trace.
    assert_eq!(st.dropped_at_input, dropped, "{st:?}");
    assert_eq!(st.repeated_frames, repeated);
    assert_eq!(st.timestamps_rejected, refused);
    assert_eq!(st.tracked + st.dropped, st.pushed);
    assert!(dropped > 0 && repeated > 0, "{counts:?}");
    // The buffers allocated for the extra pushers were freed: the pool is back to
    // its size.
    let raw = lock(&p.shared.raw);
    assert_eq!((raw.extra, raw.free.len()), (0, 4));
    // The run did need them (else it tests nothing new).
    assert!(raw.allocated >= 2, "{}", raw.allocated);
}

#[test]
fn nanosecond_timestamps_are_compared_as_integers_at_any_magnitude() {
    let (config, frames) = stream(3);
    let p = Pipeline::new(config, PipelineOptions::default()).unwrap();
    let push_ns = |ns: i64, f: &Frame| {
        p.push_ns(ns, |i, d| {
            i.copy_from_slice(&f.intensity);
            d.copy_from_slice(&f.depth);
        })
    };
    let t = 9_000_000_000_000_000_000i64;
    // Equal as f64 seconds, one nanosecond apart as integers.
    assert_eq!(t as f64 / 1e9, (t + 1) as f64 / 1e9);
    push_ns(t, &frames[0]).unwrap();
    push_ns(t + 1, &frames[1]).unwrap();
    let again = push_ns(t + 1, &frames[2]);
    assert_eq!(
        again,
        Err(Error::TimestampNsNotIncreasing {
            previous_ns: t + 1,
            timestamp_ns: t + 1
        })
    );
    let msg = again.unwrap_err().to_string();
    assert!(msg.contains("9000000000000000001 ns"), "{msg}");
    push_ns(t + 2, &frames[2]).unwrap();
    p.flush().unwrap();
    let st = p.stats();
    assert_eq!((st.pushed, st.timestamps_rejected), (3, 1), "{st:?}");
}

/// The per-frame work (filter plus tracker of the same frame, wall and CPU time) is counted once per
/// tracked frame; its mean is the sum of the stages' means, and since every frame's
/// work is at least its tracking and at least its preparation, so are its median and
/// 95th percentile.
#[test]
fn the_work_of_a_frame_is_its_preparation_plus_its_tracking() {
    let (config, frames) = stream(30);
    let st = within_a_minute(move || {
        let p = Pipeline::new(
            config,
            PipelineOptions {
                threads: 1,
                ..PipelineOptions::default()
            },
        )
        .unwrap();
        for f in &frames {
            push(&p, f).unwrap();
        }
        p.finish().unwrap().stats
    });
    assert_eq!(st.tracked, 30);
    assert_eq!(st.work.frames, 30);
    let sum = st.filter.mean_ms + st.tracker.mean_ms;
    assert!(
        (st.work.mean_ms - sum).abs() <= 1e-9 * sum.max(1.0),
        "{} against {sum}",
        st.work.mean_ms
    );
    for stage in [st.filter, st.tracker] {
        assert!(st.work.median_ms >= stage.median_ms, "{st:?}");
        assert!(st.work.p95_ms >= stage.p95_ms, "{st:?}");
        assert!(st.work.max_ms >= stage.max_ms, "{st:?}");
    }
    assert!(st.work.max_ms <= st.filter.max_ms + st.tracker.max_ms + 1e-9);
    // On one compute thread the CPU time is the same work without the time spent
    // descheduled: never more than the wall time (to the clocks' resolution).
    assert_eq!(st.work_cpu.frames, 30);
    if cfg!(unix) {
        assert!(st.work_cpu.mean_ms > 0.0, "{st:?}");
    }
    assert!(
        st.work_cpu.mean_ms <= st.work.mean_ms * 1.001 + 0.01,
        "{st:?}"
    );
}
