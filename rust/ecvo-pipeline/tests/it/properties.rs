//! Property tests (proptest) of the pipeline's pool and queue invariants under random
//! sequences of push, flush and poll, ended by finish, in both admission modes.

use std::sync::OnceLock;

use ecvo_core::{Camera, Config, Mode, Odometry, Preset, se3};
use ecvo_pipeline::{Admission, GeometryOptions, Pipeline, PipelineOptions, PushStatus};
use ecvo_synth::{SynthCamera, SynthSequence};
use proptest::prelude::*;

struct Frame {
    timestamp: f64,
    intensity: Vec<u8>,
    depth: Vec<u16>,
}

const FRAMES: usize = 40;

/// A small (160x90) synthetic stream, rendered once.
fn stream() -> &'static (Config, Vec<Frame>) {
    static S: OnceLock<(Config, Vec<Frame>)> = OnceLock::new();
    S.get_or_init(|| {
        let mut seq = SynthSequence::phone_320x180(FRAMES, 7);
        seq.camera = SynthCamera {
            width: 160,
            height: 90,
            fx: 125.0,
            fy: 125.0,
            cx: 79.5,
            cy: 44.5,
            depth_scale: 1000.0,
        };
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
        let mut config = Config::new(camera, Preset::Phone, Mode::L2);
        config.motion.min_valid_pixels = 50;
        let frames = seq
            .iter()
            .map(|f| Frame {
                timestamp: f.timestamp,
                intensity: f.intensity,
                depth: f.depth,
            })
            .collect();
        (config, frames)
    })
}

#[derive(Clone, Debug)]
enum Op {
    Push(usize),
    Flush,
    Poll,
}

fn op() -> impl Strategy<Value = Op> {
    prop_oneof![
        4 => (1usize..6).prop_map(Op::Push),
        1 => Just(Op::Flush),
        1 => Just(Op::Poll),
    ]
}

fn check_bounds(p: &Pipeline, capacity: &mut Option<usize>) -> Result<(), TestCaseError> {
    let s = p.stats();
    let pool = s.frame_pool;
    prop_assert!(pool.in_use <= pool.capacity, "{pool:?}");
    prop_assert!(pool.max_in_use <= pool.capacity, "{pool:?}");
    prop_assert!(pool.allocated <= pool.capacity, "{pool:?}");
    // Everything is allocated at start-up: the pool never grows.
    let c = *capacity.get_or_insert(pool.allocated);
    prop_assert_eq!(pool.allocated, c);
    for q in [s.input_queue, s.tracker_queue, s.geometry_queue] {
        prop_assert!(q.depth <= q.capacity && q.max_depth <= q.capacity, "{q:?}");
    }
    prop_assert!(
        s.tracked + s.dropped + s.failed_preparations <= s.pushed,
        "{s:?}"
    );
    prop_assert_eq!(s.dropped, s.dropped_at_input + s.dropped_at_tracker);
    prop_assert!(s.ahead_used <= s.ahead_computed);
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn pool_and_queues_hold_under_random_use(
        ops in prop::collection::vec(op(), 1..14),
        live in any::<bool>(),
        queue_capacity in 1usize..4,
        threads in 1usize..3,
        geometry in any::<bool>(),
    ) {
        let (config, frames) = stream();
        let admission = if live { Admission::Live } else { Admission::Offline };
        let p = Pipeline::new(config.clone(), PipelineOptions {
            threads,
            admission,
            queue_capacity,
            geometry: geometry.then(GeometryOptions::default),
            keep_trajectory: true,
            ..PipelineOptions::default()
        }).expect("valid options");
        let mut capacity = None;
        let mut pushed = 0usize;
        for op in &ops {
            match *op {
                Op::Push(n) => {
                    for _ in 0..n {
                        let f = &frames[pushed % FRAMES];
                        // Past the stream, the timestamps go on increasing.
                        let t = f.timestamp + (pushed / FRAMES) as f64 * 10.0;
                        let st = p.push(t, |i, d| {
                            i.copy_from_slice(&f.intensity);
                            d.copy_from_slice(&f.depth);
                        }).expect("push");
                        prop_assert!(live || st == PushStatus::Accepted);
                        pushed += 1;
                    }
                }
                Op::Flush => {
                    p.flush().expect("flush");
                    let s = p.stats();
                    // After a flush every pushed frame is accounted for.
                    prop_assert_eq!(s.pushed, pushed as u64);
                    prop_assert_eq!(s.tracked + s.dropped + s.failed_preparations, s.pushed, "{:?}", s);
                    prop_assert_eq!(p.latest().tracked, s.tracked);
                    prop_assert_eq!(p.trajectory().len() as u64, s.tracked);
                    if !live {
                        prop_assert_eq!(s.dropped, 0);
                    }
                }
                Op::Poll => {
                    let l = p.latest();
                    prop_assert!(l.tracked <= pushed as u64);
                    if l.tracked > 0 {
                        prop_assert!(se3::is_finite(&l.pose));
                    }
                }
            }
            check_bounds(&p, &mut capacity)?;
        }
        let summary = p.finish().expect("finish");
        let s = &summary.stats;
        prop_assert_eq!(s.pushed, pushed as u64);
        prop_assert_eq!(s.tracked + s.dropped + s.failed_preparations, s.pushed);
        prop_assert_eq!(summary.trajectory.len() as u64, s.tracked);
        for w in summary.trajectory.windows(2) {
            prop_assert!(w[0].sequence < w[1].sequence);
            prop_assert!(w[0].timestamp < w[1].timestamp);
            prop_assert_eq!(w[0].index + 1, w[1].index);
        }
        prop_assert!(summary.trajectory.iter().all(|r| se3::is_finite(&r.pose)));
        prop_assert!(s.frame_pool.max_in_use <= s.frame_pool.capacity);
        if !live {
            // Offline is lossless and equal to the sequential engine bit for bit.
            prop_assert_eq!(s.dropped, 0);
            let mut odo = Odometry::new(config.clone()).expect("valid");
            for (k, r) in summary.trajectory.iter().enumerate() {
                let f = &frames[k % FRAMES];
                let out = odo.push(ecvo_core::FrameView {
                    timestamp: f.timestamp + (k / FRAMES) as f64 * 10.0,
                    intensity: &f.intensity,
                    depth: &f.depth,
                }).expect("push");
                prop_assert_eq!(out.pose, r.pose, "frame {}", k);
                prop_assert_eq!(out.state, r.state);
            }
        }
    }
}
