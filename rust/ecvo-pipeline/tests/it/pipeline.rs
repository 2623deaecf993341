//! The pipeline against the sequential engine, its frame pool, its concurrent
//! read-outs and its real-data behaviour.

use crate::common;

use std::collections::HashSet;
use std::sync::OnceLock;

use ecvo_core::{Config, FrameOutput, Odometry};
use ecvo_pipeline::{
    Admission, Error, GeometryOptions, Pipeline, PipelineOptions, PushStatus, TrackedFrame,
};

fn stream() -> &'static (Config, Vec<common::Frame>) {
    static S: OnceLock<(Config, Vec<common::Frame>)> = OnceLock::new();
    S.get_or_init(|| common::synthetic(60, 11))
}

fn sequential(config: &Config, frames: &[common::Frame]) -> (Vec<FrameOutput>, Odometry) {
    let mut odo = Odometry::new(config.clone()).unwrap();
    let outs = frames.iter().map(|f| odo.push(f.view()).unwrap()).collect();
    (outs, odo)
}

#[test]
fn offline_poses_equal_sequential_odometry_bit_for_bit_at_1_2_and_4_threads() {
    let (config, frames) = stream();
    let (expected, odo) = sequential(config, frames);
    assert!(
        odo.tracker().counters().references.iter().sum::<u64>() > 0,
        "the stream must exercise error correction"
    );
    for threads in [1, 2, 4] {
        let pipeline = Pipeline::new(
            config.clone(),
            PipelineOptions {
                threads,
                geometry: Some(GeometryOptions::default()),
                keep_trajectory: true,
                output_queue: Some(4),
                ..PipelineOptions::default()
            },
        )
        .unwrap();
        let rx = pipeline.outputs().unwrap();
        let outputs: Vec<TrackedFrame> = std::thread::scope(|s| {
            let consumer = s.spawn(move || rx.iter().collect::<Vec<_>>());
            for f in frames {
                assert_eq!(pipeline.push_view(f.view()).unwrap(), PushStatus::Accepted);
            }
            pipeline.close_input();
            consumer.join().unwrap()
        });
        let summary = pipeline.finish().unwrap();
        assert_eq!(outputs.len(), frames.len(), "{threads} threads");
        assert_eq!(summary.trajectory.len(), frames.len());
        for (i, ((got, rec), want)) in outputs
            .iter()
            .zip(&summary.trajectory)
            .zip(&expected)
            .enumerate()
        {
            assert_eq!(got.sequence, i as u64);
            assert_eq!(got.output.index, want.index);
            assert_eq!(
                common::bits(&got.output.pose),
                common::bits(&want.pose),
                "frame {i}, {threads} threads"
            );
            assert_eq!(common::bits(&rec.pose), common::bits(&want.pose));
            assert_eq!(got.output.state, want.state);
            assert_eq!(got.output.reference_levels, want.reference_levels);
            assert_eq!(got.output.motion_estimations, want.motion_estimations);
        }
        assert_eq!(&summary.stats.counters, odo.tracker().counters());
        assert_eq!(summary.stats.tracked, frames.len() as u64);
        assert_eq!(summary.stats.dropped, 0);
        // References: the first frame and every frame that became one.
        let refs: Vec<u64> = summary.references.iter().map(|r| r.index).collect();
        let want_refs: Vec<u64> = expected
            .iter()
            .filter(|o| o.index == 0 || o.reference_levels > 0)
            .map(|o| o.index)
            .collect();
        assert_eq!(refs, want_refs);
        assert_eq!(summary.stats.geometry.frames, want_refs.len() as u64);
        assert!(!summary.cloud.is_empty());
        assert_eq!(summary.stats.filter.frames, frames.len() as u64);
        assert!(summary.stats.filter.median_ms > 0.0 && summary.stats.tracker.mean_ms > 0.0);
        assert_eq!(
            summary.stats.frame_pool.in_use, 0,
            "every frame back in the pool"
        );
    }
}

#[test]
fn keyframe_tracking_offline_equals_sequential_odometry_bit_for_bit() {
    let (config, frames) = stream();
    // Every frame prepared whole, and frames prepared for lookup whose reference side
    // the tracker finishes (with a geometry stage reading the finished frames).
    for lookup in [
        ecvo_core::LookupDepth::Filtered,
        ecvo_core::LookupDepth::Raw,
        ecvo_core::LookupDepth::Bilateral,
    ] {
        keyframe_tracking_matches(config, frames, lookup);
    }
}

fn keyframe_tracking_matches(
    config: &Config,
    frames: &[common::Frame],
    lookup: ecvo_core::LookupDepth,
) {
    let mut config = config.clone();
    config.keyframes = true;
    config.lookup_depth = lookup;
    let (expected, odo) = sequential(&config, frames);
    let c = odo.tracker().counters();
    assert!(
        c.references[0] > 0 && c.keyframe_fusions > 0,
        "the stream must make keyframes: {c:?}"
    );
    let mut first_cloud = None;
    for threads in [1, 2] {
        let pipeline = Pipeline::new(
            config.clone(),
            PipelineOptions {
                threads,
                keep_trajectory: true,
                geometry: Some(Default::default()),
                ..PipelineOptions::default()
            },
        )
        .unwrap();
        for f in frames {
            assert_eq!(pipeline.push_view(f.view()).unwrap(), PushStatus::Accepted);
        }
        pipeline.close_input();
        let summary = pipeline.finish().unwrap();
        assert_eq!(summary.trajectory.len(), expected.len());
        for (i, (rec, want)) in summary.trajectory.iter().zip(&expected).enumerate() {
            assert_eq!(
                common::bits(&rec.pose),
                common::bits(&want.pose),
                "frame {i}, {threads} threads, {lookup:?}"
            );
        }
        assert_eq!(&summary.stats.counters, odo.tracker().counters());
        // The cloud has the reference frames' points, read after they were finished:
        // the same at every thread count.
        let cloud: Vec<[u32; 3]> = summary
            .cloud
            .iter()
            .map(|p| p.position.map(f32::to_bits))
            .collect();
        assert!(cloud.len() > 1000, "{lookup:?}: {} points", cloud.len());
        match &first_cloud {
            None => first_cloud = Some(cloud),
            Some(c) => assert!(c == &cloud, "{lookup:?}: cloud at {threads} threads"),
        }
        // The filter stage cannot know the keyframe: it computes nothing ahead.
        assert_eq!(summary.stats.ahead_computed, 0);
    }
}

/// Distinct frames the tracker holds after `outs`: the previous frame and the
/// reference of each level.
fn held_by_tracker(outs: &[FrameOutput], levels: usize) -> usize {
    let mut refs = vec![None; levels];
    for o in outs {
        if o.index == 0 || o.reanchored {
            refs.iter_mut().for_each(|r| *r = Some(o.index));
        }
        for r in refs.iter_mut().take(o.reference_levels as usize) {
            *r = Some(o.index);
        }
    }
    let mut held: HashSet<u64> = refs.into_iter().flatten().collect();
    if let Some(last) = outs.last() {
        held.insert(last.index);
    }
    held.len()
}

#[test]
fn a_reference_frame_lives_exactly_as_long_as_it_is_a_reference() {
    let (config, frames) = stream();
    let (expected, _) = sequential(config, frames);
    let levels = config.reference_levels.len();
    let queue = 2;
    let pipeline = Pipeline::new(
        config.clone(),
        PipelineOptions {
            queue_capacity: queue,
            ..PipelineOptions::default()
        },
    )
    .unwrap();
    for (i, f) in frames.iter().enumerate() {
        pipeline.push_view(f.view()).unwrap();
        pipeline.flush().unwrap();
        let pool = pipeline.stats().frame_pool;
        // Once a frame is tracked, the only prepared frames alive are the ones the
        // tracker keeps: the previous frame and the current references.
        assert_eq!(
            pool.in_use,
            held_by_tracker(&expected[..=i], levels),
            "frame {i}"
        );
    }
    // Streaming at full speed: bounded by the levels and the queue depth. The same
    // frames again, later (timestamps must increase).
    for f in frames {
        pipeline
            .push_view(ecvo_core::FrameView {
                timestamp: f.timestamp + 1000.0,
                ..f.view()
            })
            .unwrap();
    }
    let summary = pipeline.finish().unwrap();
    let pool = summary.stats.frame_pool;
    // Previous + references, the frame being tracked, the tracker queue, the frame
    // being prepared, and the filter stage's last frame (kept to compute [A] ahead).
    let bound = levels + 1 + 1 + queue + 1 + 1;
    assert_eq!(pool.capacity, bound);
    assert!(
        pool.allocated <= bound && pool.max_in_use <= bound,
        "{pool:?}"
    );
    assert_eq!(pool.in_use, 0);
    assert!(summary.stats.tracker_queue.max_depth <= queue);
    assert!(summary.stats.input_queue.max_depth <= queue);
}

#[test]
fn ui_reads_latest_pose_stats_and_cloud_while_frames_stream() {
    let (config, frames) = stream();
    let geometry = GeometryOptions {
        voxel_size_m: Some(0.02),
        max_points: 20_000,
        point_stride: 2,
    };
    let pipeline = Pipeline::new(
        config.clone(),
        PipelineOptions {
            geometry: Some(geometry),
            keep_trajectory: true,
            ..PipelineOptions::default()
        },
    )
    .unwrap();
    let done = std::sync::atomic::AtomicBool::new(false);
    std::thread::scope(|s| {
        let ui = s.spawn(|| {
            let (mut last_tracked, mut last_cloud, mut reads) = (0, 0, 0);
            let mut cloud = Vec::new();
            while !done.load(std::sync::atomic::Ordering::Acquire) {
                let l = pipeline.latest();
                assert!(l.tracked >= last_tracked);
                last_tracked = l.tracked;
                let n = pipeline.cloud_snapshot_into(cloud.len(), &mut cloud);
                assert!(n >= last_cloud && n == cloud.len());
                last_cloud = n;
                let st = pipeline.stats();
                assert!(st.tracked <= st.pushed);
                reads += 1;
                std::thread::yield_now();
            }
            (reads, cloud)
        });
        for f in frames {
            pipeline.push_view(f.view()).unwrap();
        }
        pipeline.flush().unwrap();
        done.store(true, std::sync::atomic::Ordering::Release);
        let (reads, incremental) = ui.join().unwrap();
        assert!(reads > 0);
        let full = pipeline.cloud_snapshot();
        assert!(incremental.len() <= full.len());
        assert_eq!(incremental[..], full[..incremental.len()]);
        // A sample is the points at i * n / k, or the whole cloud when it is small.
        let n = full.len();
        for k in [0, 1, 7, n / 3, n, n + 5] {
            let sample = pipeline.cloud_sample(k);
            let want: Vec<_> = (0..k.min(n))
                .map(|i| full[if k >= n { i } else { i * n / k }])
                .collect();
            assert_eq!(sample, want, "k {k}");
        }
    });
    let latest = pipeline.latest();
    assert_eq!(latest.tracked, frames.len() as u64);
    assert_eq!(latest.sequence, frames.len() as u64 - 1);
    assert_eq!(latest.timestamp, frames.last().unwrap().timestamp);
    let summary = pipeline.finish().unwrap();
    assert_eq!(latest.pose, summary.trajectory.last().unwrap().pose);
    // One point per 2 cm voxel, never more than the cap.
    let cloud = &summary.cloud;
    assert!(!cloud.is_empty() && cloud.len() <= geometry.max_points);
    let voxels: HashSet<_> = cloud
        .iter()
        .map(|p| p.position.map(|c| (c / 0.02).floor() as i32))
        .collect();
    assert_eq!(voxels.len(), cloud.len());
}

#[test]
fn live_mode_drops_the_oldest_frames_and_counts_them() {
    let (config, frames) = stream();
    let pipeline = Pipeline::new(
        config.clone(),
        PipelineOptions {
            admission: Admission::Live,
            queue_capacity: 1,
            keep_trajectory: true,
            ..PipelineOptions::default()
        },
    )
    .unwrap();
    // A camera far faster than the tracker: every push returns at once.
    let mut dropped_status = 0;
    for f in frames {
        if pipeline.push_view(f.view()).unwrap() == PushStatus::DroppedOldest {
            dropped_status += 1;
        }
    }
    pipeline.flush().unwrap();
    let summary = pipeline.finish().unwrap();
    let st = &summary.stats;
    assert_eq!(st.pushed, frames.len() as u64);
    assert!(st.dropped > 0, "{st:?}");
    assert_eq!(st.tracked + st.dropped, st.pushed);
    assert!(dropped_status as u64 <= st.dropped_at_input);
    assert!(st.input_queue.max_depth <= 1 && st.tracker_queue.max_depth <= 1);
    // Tracked frames are in push order, the newest is always tracked.
    let seq: Vec<u64> = summary.trajectory.iter().map(|r| r.sequence).collect();
    assert!(seq.windows(2).all(|w| w[0] < w[1]));
    assert_eq!(*seq.last().unwrap(), frames.len() as u64 - 1);
}

#[test]
fn bad_frames_and_options_are_errors() {
    let (config, frames) = stream();
    assert!(matches!(
        Pipeline::new(
            config.clone(),
            PipelineOptions {
                threads: 0,
                ..PipelineOptions::default()
            }
        ),
        Err(Error::InvalidOptions {
            field: "threads",
            ..
        })
    ));
    assert!(matches!(
        Pipeline::new(
            config.clone(),
            PipelineOptions {
                geometry: Some(GeometryOptions {
                    voxel_size_m: Some(-1.0),
                    ..GeometryOptions::default()
                }),
                ..PipelineOptions::default()
            }
        ),
        Err(Error::InvalidOptions {
            field: "geometry.voxel_size_m",
            ..
        })
    ));
    let mut bad = config.clone();
    bad.camera.fx = f64::NAN;
    assert!(matches!(
        Pipeline::new(bad, PipelineOptions::default()),
        Err(Error::Core(_))
    ));
    let pipeline = Pipeline::new(config.clone(), PipelineOptions::default()).unwrap();
    let f = &frames[0];
    let short = ecvo_core::FrameView {
        depth: &f.depth[1..],
        ..f.view()
    };
    assert!(matches!(pipeline.push_view(short), Err(Error::Core(_))));
    assert!(matches!(
        pipeline.push(f64::NAN, |_, _| {}),
        Err(Error::Core(_))
    ));
    pipeline.push_view(f.view()).unwrap();
    pipeline.close_input();
    assert_eq!(pipeline.push_view(f.view()), Err(Error::Closed));
    assert_eq!(pipeline.finish().unwrap().stats.tracked, 1);
}

/// The first `n` frames of a shared TUM sequence through the pipeline at each of
/// `threads` (with geometry on), against `Odometry` on a one-thread rayon pool, bit
/// for bit. Nothing to do when the sequence is absent (`dataset_for_test` says so,
/// or fails the test when datasets are required).
fn tum_stream_matches_one_thread_odometry(name: &str, n: usize, threads: &[usize]) {
    let Some(dir) = ecvo_io::dataset_for_test(name) else {
        return;
    };
    let seq = ecvo_io::Sequence::open(&dir, None).unwrap();
    let frames: Vec<ecvo_io::Frame> = (0..n).map(|i| seq.load_frame(i).unwrap()).collect();
    let config = Config::new(*seq.camera(), ecvo_core::Preset::Pc, ecvo_core::Mode::L2);
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let mut odo = Odometry::new(config.clone()).unwrap();
    let expected: Vec<_> =
        one.install(|| frames.iter().map(|f| odo.push(f.view()).unwrap()).collect());
    for &threads in threads {
        let pipeline = Pipeline::new(
            config.clone(),
            PipelineOptions {
                threads,
                keep_trajectory: true,
                geometry: Some(GeometryOptions::default()),
                ..PipelineOptions::default()
            },
        )
        .unwrap();
        for f in &frames {
            pipeline.push_view(f.view()).unwrap();
        }
        let summary = pipeline.finish().unwrap();
        assert_eq!(summary.trajectory.len(), expected.len());
        for (i, (r, e)) in summary.trajectory.iter().zip(&expected).enumerate() {
            assert_eq!(
                common::bits(&r.pose),
                common::bits(&e.pose),
                "{name} frame {i}, {threads} threads"
            );
        }
        assert_eq!(&summary.stats.counters, odo.tracker().counters());
    }
}

#[test]
fn real_tum_stream_matches_sequential_odometry() {
    tum_stream_matches_one_thread_odometry("tum_fr1_xyz_half", 40, &[2]);
}

/// At 640x480 ecvo-core splits MOTION and the filter between the pool's threads;
/// the poses must still be those of the one-thread sequential engine.
#[test]
fn full_resolution_tum_stream_matches_one_thread_odometry_at_1_2_and_4_threads() {
    tum_stream_matches_one_thread_odometry("tum_fr1_xyz_full300", 20, &[1, 2, 4]);
}

/// With gyroscope samples pushed beside the frames, and depth stamped 10 ms off the
/// intensity (after it on even frames, before it on odd ones: turned to the
/// intensity's time, `push_with_depth_time`), the pipeline's poses and counters are
/// still the sequential engine's, bit for bit, at 1 and 2 threads (the tracker stage
/// hands the tracker exactly the samples pushed before each frame; both turn the
/// depth from the samples pushed before the frame).
#[test]
fn offline_poses_with_an_imu_equal_sequential_odometry_bit_for_bit() {
    let (config, frames, imu) = common::pan_with_imu(30, 4);
    let offset = config.imu.time_offset;
    let mut odo = Odometry::new(config.clone()).unwrap();
    let mut next = 0;
    let expected: Vec<FrameOutput> = frames
        .iter()
        .enumerate()
        .map(|(i, f)| {
            odo.push_imu(common::imu_before(
                &imu,
                &mut next,
                f.timestamp + 0.01,
                offset,
            ))
            .unwrap();
            odo.push_with_depth_time(f.view(), depth_time(i, f.timestamp))
                .unwrap()
        })
        .collect();
    let c = odo.tracker().counters();
    assert_eq!((c.imu.priors, c.lost_frames), (29, 0), "{:?}", c.imu);
    assert_eq!(
        (c.imu.depth_turned, c.imu.depth_unturned),
        (30, 0),
        "{:?}",
        c.imu
    );
    for threads in [1, 2] {
        let pipeline = Pipeline::new(
            config.clone(),
            PipelineOptions {
                threads,
                keep_trajectory: true,
                ..PipelineOptions::default()
            },
        )
        .unwrap();
        let mut next = 0;
        for (i, f) in frames.iter().enumerate() {
            pipeline
                .push_imu(common::imu_before(
                    &imu,
                    &mut next,
                    f.timestamp + 0.01,
                    offset,
                ))
                .unwrap();
            pipeline
                .push_with_depth_time(f.timestamp, depth_time(i, f.timestamp), |a, b| {
                    a.copy_from_slice(&f.intensity);
                    b.copy_from_slice(&f.depth);
                })
                .unwrap();
        }
        let summary = pipeline.finish().unwrap();
        for (i, (r, e)) in summary.trajectory.iter().zip(&expected).enumerate() {
            assert_eq!(
                common::bits(&r.pose),
                common::bits(&e.pose),
                "frame {i}, {threads} threads"
            );
        }
        assert_eq!(&summary.stats.counters, odo.tracker().counters());
    }
}

/// Frame `i`'s depth time: 10 ms after its intensity's `t` on even frames, before it
/// on odd ones.
fn depth_time(i: usize, t: f64) -> f64 {
    if i % 2 == 0 { t + 0.01 } else { t - 0.01 }
}
