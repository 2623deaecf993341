//! What the pipeline does with its input: timestamps out of order, repeated frames, the
//! trajectory window, live pushes from many threads, nanosecond timestamps, and the
//! per-frame work it records.

use super::*;

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

/// A non-finite depth timestamp is refused with a clear error, before the frame is
/// queued; the pipeline goes on and tracks the next frames.
#[test]
fn a_non_finite_depth_timestamp_is_refused_and_the_pipeline_goes_on() {
    let (config, frames) = stream(2);
    let p = Pipeline::new(config, PipelineOptions::default()).unwrap();
    fn fill(f: &Frame) -> impl FnOnce(&mut [u8], &mut [u16]) + '_ {
        move |i, d| {
            i.copy_from_slice(&f.intensity);
            d.copy_from_slice(&f.depth);
        }
    }
    for bad in [f64::NAN, f64::INFINITY] {
        let e = p
            .push_with_depth_time(frames[0].timestamp, bad, fill(&frames[0]))
            .unwrap_err();
        assert!(e.to_string().contains("depth timestamp"), "{e}");
    }
    for f in &frames {
        p.push_with_depth_time(f.timestamp, f.timestamp + 0.01, fill(f))
            .unwrap();
    }
    let summary = p.finish().unwrap();
    assert_eq!((summary.stats.pushed, summary.stats.tracked), (2, 2));
}
