//! A warm pipeline allocates nothing per frame: a counting global allocator watches
//! frames 20..60 of an offline 320x180 run after a warm-up of 20 frames, then frames
//! 10..30 of a 640x480 run, where ecvo-core also splits MOTION and the filter between
//! the two compute threads (rayon's `join` keeps its jobs on the stack).
//!
//! The one allocation that remains is rayon's, not ours: handing a job to a
//! `rayon::ThreadPool` from outside it (`install`, as the stages do once per frame)
//! goes through the pool's injector queue, which allocates one fixed-size block per 63
//! jobs and frees it when they have run (about one 1.5 kB block every 25 frames). The
//! test checks that every allocation in the window is such a block, and that there are
//! no more of them than the jobs injected call for; everything else allocates nothing.
//!
//! Scope: `push` (copying into pooled raw buffers), the input, tracker and geometry
//! queues, the filter stage (`Preparer::prepare_into` into pooled frames), the
//! tracker stage (`Tracker::track`, latest pose, counters, statistics) and the
//! geometry stage with a voxel grid (its storage is reserved for `max_points` when
//! the pipeline starts), with 2 compute threads. Not in scope: the optional
//! trajectory and outputs channel (off here; they grow or queue per frame by
//! design), and `stats()` snapshots (they copy the counters).

#[path = "it/common/mod.rs"]
mod common;

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

use ecvo_pipeline::{GeometryOptions, Pipeline, PipelineOptions};

/// Size of a block of crossbeam-deque's `Injector<rayon_core::JobRef>`: 63 slots of a
/// two-pointer job reference and a state word, plus the link to the next block.
const INJECTOR_BLOCK: usize = 63 * 3 * std::mem::size_of::<usize>() + std::mem::size_of::<usize>();

struct Counting;

static COUNTING: AtomicBool = AtomicBool::new(false);
static ALLOCS: AtomicU64 = AtomicU64::new(0);
static SIZES: Mutex<[usize; 64]> = Mutex::new([0; 64]);

fn note(size: usize) {
    if COUNTING.load(Ordering::Relaxed) {
        let n = ALLOCS.fetch_add(1, Ordering::Relaxed) as usize;
        if n < 64
            && let Ok(mut s) = SIZES.try_lock()
        {
            s[n] = size;
        }
    }
}

// SAFETY: every method forwards its arguments unchanged to `System`, which upholds
// the `GlobalAlloc` contract; `note` only counts (atomics, and a `try_lock` that never
// blocks or allocates), so it cannot re-enter the allocator.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        note(layout.size());
        // SAFETY: the caller's `layout` contract is passed on to `System` as is.
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        note(layout.size());
        // SAFETY: as for `alloc`.
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        note(new_size);
        // SAFETY: `ptr` was allocated by `System` (every allocation goes through it)
        // with `layout`, as the caller guarantees.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: as for `realloc`.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn warm_pipeline_does_not_allocate_per_frame() {
    // One test, so that the two runs never count each other's allocations.
    let (config, frames) = common::synthetic(60, 7);
    check(config.clone(), &frames, 20);
    let (config_640, frames_640) = common::synthetic_640x480(30, 7);
    check(config_640, &frames_640, 10);
    // Keyframe tracking with frames prepared for lookup: the tracker finishes the
    // reference sides in place, without allocating (the same 320x180 frames).
    let mut config = config;
    config.keyframes = true;
    config.lookup_depth = ecvo_core::LookupDepth::Raw;
    check(config, &frames, 20);
    // With a gyroscope: its samples pushed before each frame, the tracker's ring
    // and the pipeline's inbox allocated during the warm-up, never again.
    let (config, frames, imu) = common::pan_with_imu(40, 7);
    check_with(config, &frames, 15, &imu);
}

/// Runs `frames` through a pipeline and counts the allocations after the first `warm`.
fn check(config: ecvo_core::Config, frames: &[common::Frame], warm: usize) {
    check_with(config, frames, warm, &[]);
}

/// [`check`] with gyro samples pushed before each frame.
fn check_with(
    config: ecvo_core::Config,
    frames: &[common::Frame],
    warm: usize,
    imu: &[ecvo_core::GyroSample],
) {
    let width = config.camera.width;
    let offset = config.imu.time_offset;
    let next = std::cell::Cell::new(0usize);
    let pipeline = Pipeline::new(
        config,
        PipelineOptions {
            threads: 2,
            geometry: Some(GeometryOptions {
                voxel_size_m: Some(0.01),
                max_points: 300_000,
                point_stride: 2,
            }),
            ..PipelineOptions::default()
        },
    )
    .unwrap();
    let push = |f: &common::Frame| {
        let mut n = next.get();
        pipeline
            .push_imu(common::imu_before(imu, &mut n, f.timestamp, offset))
            .unwrap();
        next.set(n);
        pipeline
            .push(f.timestamp, |i, d| {
                i.copy_from_slice(&f.intensity);
                d.copy_from_slice(&f.depth);
            })
            .unwrap();
    };
    for f in &frames[..warm] {
        push(f);
    }
    pipeline.flush().unwrap();

    let geometry_before = pipeline.stats().geometry.frames;
    ALLOCS.store(0, Ordering::SeqCst);
    COUNTING.store(true, Ordering::SeqCst);
    for f in &frames[warm..] {
        push(f);
    }
    pipeline.flush().unwrap();
    COUNTING.store(false, Ordering::SeqCst);

    let allocs = ALLOCS.load(Ordering::SeqCst);
    let sizes = *SIZES.lock().unwrap();
    let stats = pipeline.stats();
    // Jobs handed to the pool in the window: one per frame for the filter and for the
    // tracker, one per reference frame for the geometry stage. The injector needs a
    // new block every 63 jobs; two stage threads racing for the last slot of a block
    // may both allocate one (the loser frees its copy), hence at most two per 63.
    let counted = (frames.len() - warm) as u64;
    let jobs = 2 * counted + (stats.geometry.frames - geometry_before);
    let summary = pipeline.finish().unwrap();
    assert_eq!(summary.stats.tracked, frames.len() as u64);
    assert!(stats.counters.references.iter().sum::<u64>() > 0);
    assert!(stats.cloud_points > 0);
    if !imu.is_empty() {
        let c = &stats.counters.imu;
        assert_eq!(
            (c.priors, c.late, c.missing),
            (frames.len() as u64 - 1, 0, 0),
            "{c:?}"
        );
    }
    let seen = &sizes[..(allocs as usize).min(64)];
    assert!(
        seen.iter().all(|&s| s == INJECTOR_BLOCK) && allocs <= 2 * jobs.div_ceil(63),
        "width {width}: {allocs} allocations over frames {warm}..{} ({jobs} jobs injected), \
         sizes {seen:?}; only rayon injector blocks of {INJECTOR_BLOCK} bytes are expected",
        frames.len()
    );
    eprintln!(
        "width {width}, frames {warm}..{}: {allocs} allocations, all rayon injector blocks \
         ({jobs} jobs injected)",
        frames.len()
    );
}
