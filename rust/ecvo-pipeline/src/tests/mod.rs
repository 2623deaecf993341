//! Unit tests of the pipeline. This file: the fault-injection hooks (panics in each
//! stage, a slow tracker in live mode, dropping without `finish`) and the shared helpers.

use std::sync::mpsc;
use std::time::Duration;

use ecvo_core::{Camera, Config, Mode, Preset};
use ecvo_synth::SynthSequence;

use super::*;

mod ahead;
mod input;

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
