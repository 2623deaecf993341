//! `Pipeline::memory_needed` is an upper bound of what a pipeline really allocates: a
//! counting global allocator records the peak of the bytes outstanding from
//! `Pipeline::new` to `finish`, at 320x180 and 640x480, with and without the geometry
//! stage, offline and live, and the figure must cover it. A pipeline over its budget
//! is refused before it allocates, with the need and the budget; and once it is
//! finished or dropped the bytes outstanding are back at the baseline.

#[path = "it/common/mod.rs"]
mod common;

use std::sync::Mutex;
use std::sync::atomic::Ordering;

use ecvo_core::memory::{self, MB};
use ecvo_pipeline::{Admission, Error, GeometryOptions, Pipeline, PipelineOptions};

#[path = "../../ecvo-core/tests/support/counting_alloc.rs"]
mod counting_alloc;

use counting_alloc::{CURRENT, Counting, PEAK};

#[global_allocator]
static GLOBAL: Counting = Counting;

/// One process-wide counter: one test at a time.
static SERIAL: Mutex<()> = Mutex::new(());

fn run(config: &ecvo_core::Config, options: PipelineOptions, frames: &[common::Frame]) {
    let pipeline = Pipeline::new(config.clone(), options).expect("within the budget");
    for f in frames {
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
