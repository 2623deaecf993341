//! `Pipeline::memory_needed` is an upper bound of what a pipeline really allocates: a
//! counting global allocator records the peak of the bytes outstanding from
//! `Pipeline::new` to `finish`, at 320x180 and 640x480, with and without the geometry
//! stage, offline and live, with a 400 Hz gyro stream, and the figure must cover it;
//! the IMU inbox allocates once, what the need counts for it. A pipeline over its budget
//! is refused before it allocates, with the need and the budget; and once it is
//! finished or dropped the bytes outstanding are back at the baseline.

#[path = "it/common/mod.rs"]
mod common;

use std::sync::Mutex;
use std::sync::atomic::Ordering;

use ecvo_core::imu::GyroSample;
use ecvo_core::memory::{self, MB};
use ecvo_pipeline::{
    Admission, Error, GeometryOptions, IMU_INBOX_CAPACITY, Pipeline, PipelineOptions,
};

#[path = "../../ecvo-core/tests/support/counting_alloc.rs"]
mod counting_alloc;

use counting_alloc::{CURRENT, Counting, PEAK};

#[global_allocator]
static GLOBAL: Counting = Counting;

/// One process-wide counter: one test at a time.
static SERIAL: Mutex<()> = Mutex::new(());

/// Gyro samples at 400 Hz over `[t0, t1)`.
fn gyro(t0: f64, t1: f64) -> Vec<GyroSample> {
    let (first, last) = ((t0 * 400.0).ceil() as i64, (t1 * 400.0).ceil() as i64);
    (first..last)
        .map(|i| GyroSample {
            t: i as f64 / 400.0,
            w: [0.0, 0.01, 0.0],
        })
        .collect()
}

fn run(config: &ecvo_core::Config, options: PipelineOptions, frames: &[common::Frame]) {
    let pipeline = Pipeline::new(config.clone(), options).expect("within the budget");
    let mut last = frames.first().map_or(0.0, |f| f.timestamp - 0.1);
    for f in frames {
        // A 400 Hz gyro up to the frame: the inbox and the tracker's ring fill.
        pipeline
            .push_imu(&gyro(last, f.timestamp + 0.001))
            .expect("finite samples");
        last = f.timestamp + 0.001;
        pipeline
            .push(f.timestamp, |i, d| {
                i.copy_from_slice(&f.intensity);
                d.copy_from_slice(&f.depth);
            })
            .expect("a valid frame");
    }
    let summary = pipeline.finish().expect("no stage failure");
    assert!(summary.stats.tracked > 0);
}

#[test]
fn memory_needed_bounds_the_peak_and_everything_is_given_back() {
    let _serial = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let small = common::synthetic(25, 3);
    let vga = common::synthetic_640x480(12, 3);
    let geometry = Some(GeometryOptions {
        voxel_size_m: Some(0.01),
        max_points: 200_000,
        point_stride: 2,
    });
    for (config, frames) in [&small, &vga] {
        for (admission, geometry, queue) in [
            (Admission::Offline, None, 2),
            (Admission::Offline, geometry, 4),
            (Admission::Live, None, 1),
        ] {
            let options = PipelineOptions {
                admission,
                geometry,
                queue_capacity: queue,
                ..PipelineOptions::default()
            };
            let need = Pipeline::memory_needed(config, &options);
            let base = CURRENT.load(Ordering::Relaxed);
            PEAK.store(base, Ordering::Relaxed);
            run(config, options, frames);
            let peak = PEAK.load(Ordering::Relaxed) - base;
            let after = CURRENT.load(Ordering::Relaxed) as isize - base as isize;
            let w = config.camera.width;
            println!(
                "{w}: {admission:?} q{queue} geometry {}: need {}, peak {}, left {after} bytes",
                geometry.is_some(),
                memory::format_mb(need),
                memory::format_mb(peak)
            );
            assert!(peak <= need, "{w} {admission:?}: peak {peak} above {need}");
            assert!(
                need <= 2 * peak + MB,
                "{w} {admission:?}: {need} far above {peak}"
            );
            // Given back: rayon's global registry is not touched; what stays is
            // at most the logger's and thread-locals' odd bytes.
            assert!(
                after.unsigned_abs() < 64 << 10,
                "{w}: {after} bytes not given back"
            );
        }
    }
}

#[test]
fn the_imu_inbox_is_counted_and_allocated_once() {
    let _serial = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let (config, _) = common::synthetic(1, 3);
    // The inbox and the depth clock beside it (`Pipeline::push_with_depth_time`).
    let inbox = (IMU_INBOX_CAPACITY + ecvo_core::imu::depth_time::DEPTH_CLOCK_CAPACITY)
        * size_of::<GyroSample>();
    let pipeline = Pipeline::new(config, PipelineOptions::default()).expect("valid");
    let samples = gyro(0.0, 60.0);
    let base = CURRENT.load(Ordering::Relaxed);
    pipeline.push_imu(&samples[..10]).unwrap();
    let first = CURRENT.load(Ordering::Relaxed) - base;
    // 24,000 samples wrap the inbox: nothing more (no frame, so the tracker reads none).
    pipeline.push_imu(&samples[10..]).unwrap();
    let all = CURRENT.load(Ordering::Relaxed) - base;
    println!(
        "IMU inbox: {first} bytes at the first push, {all} after {}; counted {inbox}",
        samples.len()
    );
    assert!(
        first > 0 && all == first,
        "allocated once: {first} then {all}"
    );
    assert!(
        first <= inbox && 2 * first > inbox,
        "{first} against {inbox}"
    );
    drop(pipeline);
}

#[test]
fn a_pipeline_over_its_budget_is_refused_before_allocating() {
    let _serial = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let (mut config, _) = common::synthetic_640x480(1, 3);
    let options = PipelineOptions::default();
    let need = Pipeline::memory_needed(&config, &options);
    config.memory_budget = need - 1;
    let before = CURRENT.load(Ordering::Relaxed);
    PEAK.store(before, Ordering::Relaxed);
    match Pipeline::new(config.clone(), options.clone()) {
        Err(Error::Core(e @ ecvo_core::Error::MemoryBudget { .. })) => {
            assert_eq!(
                e,
                ecvo_core::Error::MemoryBudget {
                    need,
                    budget: need - 1
                }
            );
            assert!(e.to_string().contains(&memory::format_mb(need)), "{e}");
        }
        other => panic!("expected a memory budget error, got {:?}", other.err()),
    }
    assert!(
        PEAK.load(Ordering::Relaxed) - before < MB,
        "allocated before refusing"
    );
    config.memory_budget = need;
    assert!(Pipeline::new(config, options).is_ok());
}
