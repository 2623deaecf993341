//! Pipelines created, fed and dropped (or finished) in a loop give back everything:
//! their threads (counted in `/proc/self/task`) and their memory (the bytes live in
//! a counting global allocator). This is what `ecvo-jni`'s close and re-init do, many
//! times a second in `scripts/jni-drivers.sh stress`, whose RSS grows by hundreds of
//! megabytes under glibc (its per-thread arenas and its dynamic mmap threshold keep
//! freed pages); this test shows that nothing is leaked by ecvo itself.

#[path = "it/common/mod.rs"]
mod common;

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicI64, Ordering};

use ecvo_pipeline::{Admission, GeometryOptions, Pipeline, PipelineOptions};

struct Live;

static LIVE_BYTES: AtomicI64 = AtomicI64::new(0);

// SAFETY: every method forwards its arguments unchanged to `System`, which upholds
// the `GlobalAlloc` contract; the counter is an atomic, so it cannot re-enter the
// allocator.
unsafe impl GlobalAlloc for Live {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // SAFETY: the caller's `layout` contract is passed on to `System` as is.
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            LIVE_BYTES.fetch_add(layout.size() as i64, Ordering::Relaxed);
        }
        p
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        // SAFETY: as for `alloc`.
        let p = unsafe { System.alloc_zeroed(layout) };
        if !p.is_null() {
            LIVE_BYTES.fetch_add(layout.size() as i64, Ordering::Relaxed);
        }
        p
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // SAFETY: `ptr` was allocated by `System` (every allocation goes through it)
        // with `layout`, as the caller guarantees.
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            LIVE_BYTES.fetch_add(new_size as i64 - layout.size() as i64, Ordering::Relaxed);
        }
        p
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: as for `realloc`.
        unsafe { System.dealloc(ptr, layout) };
        LIVE_BYTES.fetch_sub(layout.size() as i64, Ordering::Relaxed);
    }
}

#[global_allocator]
static GLOBAL: Live = Live;

fn threads() -> usize {
    std::fs::read_dir("/proc/self/task")
        .map(|d| d.count())
        .unwrap_or(0)
}

/// The threads once they have settled: a compute worker is counted out by rayon's
/// exit handler (which `Pipeline`'s drop waits for) a moment before its thread ends.
fn threads_settled(want: usize) -> usize {
    for _ in 0..200 {
        if threads() == want {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    threads()
}

/// One tracker's life as the JNI library lives it: created, fed, then dropped with
/// frames still queued (close) or finished.
fn one_life(cycle: usize, config: &ecvo_core::Config, frames: &[common::Frame]) {
    let live = cycle % 2 == 0;
    let pipeline = Pipeline::new(
        config.clone(),
        PipelineOptions {
            threads: 1 + cycle % 2,
            admission: if live {
                Admission::Live
            } else {
                Admission::Offline
            },
            geometry: (cycle % 3 != 0).then(|| GeometryOptions {
                max_points: 50_000,
                ..GeometryOptions::default()
            }),
            keep_trajectory: true,
            // Live, outputs that do not fit are discarded (offline the tracker would
            // wait for a reader).
            output_queue: (cycle % 4 == 0).then_some(4),
            ..PipelineOptions::default()
        },
    )
    .unwrap();
    for f in frames {
        pipeline
            .push(f.timestamp, |i, d| {
                i.copy_from_slice(&f.intensity);
                d.copy_from_slice(&f.depth);
            })
            .unwrap();
    }
    let _ = (pipeline.latest(), pipeline.stats(), pipeline.trajectory());
    let _ = pipeline.cloud_snapshot();
    if cycle % 3 == 2 {
        pipeline.finish().unwrap();
    } else {
        drop(pipeline);
    }
}

#[test]
fn dropped_pipelines_release_threads_and_memory() {
    // One test in this binary, so that nothing else allocates or spawns meanwhile.
    let (config, frames) = common::synthetic(12, 3);
    let threads_before = threads();
    // The first lives warm up what stays for the process (rayon's and std's statics).
    for cycle in 0..2 {
        one_life(cycle, &config, &frames);
    }
    let base = LIVE_BYTES.load(Ordering::SeqCst);
    let mut worst = 0i64;
    for cycle in 2..26 {
        one_life(cycle, &config, &frames);
        assert_eq!(
            threads_settled(threads_before),
            threads_before,
            "threads left running after pipeline {cycle}"
        );
        let grown = LIVE_BYTES.load(Ordering::SeqCst) - base;
        worst = worst.max(grown);
        // A pipeline at 320x180 holds about 30 MB; a leaked frame, pool or thread
        // stack is well over this bound.
        assert!(
            grown < 16 * 1024,
            "{grown} bytes still allocated after pipeline {cycle}"
        );
    }
    eprintln!("24 pipelines: at most {worst} bytes more than after the first two");
}
