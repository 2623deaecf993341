//! Memory soak: pushes many synthetic 320x180 frames through a live pipeline (no
//! point cloud, no trajectory kept) and samples the process's resident set size
//! (`VmRSS` in `/proc/self/status`) every `--every` frames. With `--imu-hz N`, a
//! gyroscope stream of N samples a second (the replayed motion's angular velocity
//! plus a constant bias) is pushed before each frame (`Pipeline::push_imu`).
//!
//! It prints the RSS curve and checks that, after `--warmup` frames, RSS stays
//! within 1 MB of its first post-warm-up sample and below 32 MB, and that the engine
//! made no allocation after the warm-up but the blocks of rayon's injector queue
//! (see `tests/alloc.rs`; at most one per 25 frames) (exit status 1 if not). The
//! allocations are counted by a global allocator on every thread, except the main
//! thread's own bookkeeping (statistics, printing, `/proc`). Linux only (it reads
//! `/proc`). Not part of the test run: 100,000 frames take several minutes.
//!
//! ```text
//! cargo run --release -p ecvo-pipeline --example soak
//! cargo run --release -p ecvo-pipeline --example soak -- --frames 20000 --every 1000
//! cargo run --release -p ecvo-pipeline --example soak -- --imu-hz 400 --threads 1
//! ```
//!
//! The frames: 16 frames of ecvo-synth's phone sequence, rendered once (2.8 MB, part
//! of the RSS measured), played forwards then backwards so that the motion stays
//! continuous, with timestamps 1/30 s apart. Frames are pushed as soon as the
//! tracker has nearly caught up (live admission never waits, so pushing without a
//! pause would only measure the drop path).

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::{Duration, Instant};

use ecvo_core::imu::GyroSample;
use ecvo_core::{Camera, Config, Mode, Preset};
use ecvo_pipeline::{Admission, Pipeline, PipelineOptions};
use ecvo_synth::{SynthFrame, SynthSequence};

/// Counts allocations while `COUNTING`, except on a thread inside [`bookkeeping`].
struct Counting;

static COUNTING: AtomicBool = AtomicBool::new(false);
static ALLOCS: AtomicU64 = AtomicU64::new(0);
/// Of them, blocks of rayon's injector queue (by size, as `tests/alloc.rs`).
static INJECTOR_ALLOCS: AtomicU64 = AtomicU64::new(0);
/// The size of the last other allocation.
static OTHER_SIZE: AtomicU64 = AtomicU64::new(0);

/// Size of a block of crossbeam-deque's `Injector<rayon_core::JobRef>`.
const INJECTOR_BLOCK: usize = 63 * 3 * size_of::<usize>() + size_of::<usize>();

thread_local! {
    static PAUSED: Cell<bool> = const { Cell::new(false) };
}

fn note(size: usize) {
    if COUNTING.load(Ordering::Relaxed) && !PAUSED.with(Cell::get) {
        ALLOCS.fetch_add(1, Ordering::Relaxed);
        if size == INJECTOR_BLOCK {
            INJECTOR_ALLOCS.fetch_add(1, Ordering::Relaxed);
        } else {
            OTHER_SIZE.store(size as u64, Ordering::Relaxed);
        }
    }
}

// SAFETY: every method forwards its arguments unchanged to `System`, which upholds
// the `GlobalAlloc` contract; `note` only touches atomics and a const-initialised
// thread-local `Cell`, so it cannot re-enter the allocator.
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
        // SAFETY: `ptr` was allocated by `System` with `layout`, as the caller
        // guarantees.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: as for `realloc`.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Runs `f` with this thread's allocations not counted (the soak's own
/// bookkeeping, not the engine's).
fn bookkeeping<T>(f: impl FnOnce() -> T) -> T {
    PAUSED.with(|p| p.set(true));
    let out = f();
    PAUSED.with(|p| p.set(false));
    out
}

/// Frames rendered once and replayed.
const RENDERED: usize = 16;
/// Flatness allowed after warm-up, and the ceiling, in kB.
const FLAT_KB: u64 = 1024;
const MAX_KB: u64 = 32 * 1024;

fn rss_kb() -> u64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmRSS:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
        .unwrap_or(0)
}

fn arg(name: &str, default: usize) -> usize {
    let args: Vec<String> = std::env::args().collect();
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1))
        .map(|v| v.parse().expect("a number"))
        .unwrap_or(default)
}

fn main() -> ExitCode {
    let frames = arg("--frames", 100_000);
    let every = arg("--every", 2_000).max(1);
    let warmup = arg("--warmup", 10_000);
    let threads = arg("--threads", 2);
    let imu_hz = arg("--imu-hz", 0);

    let seq = SynthSequence::phone_320x180(RENDERED, 11);
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
    let rendered: Vec<SynthFrame> = seq.iter().collect();
    // One period of the replayed motion (forwards then backwards, 2 (RENDERED - 1)
    // frames) at `imu_hz`: the path's angular velocity (IMU aligned with the camera,
    // on its clock), reversed on the way back, plus a constant bias.
    let period_s = (2 * (RENDERED - 1)) as f64 / seq.fps;
    let per_period = (period_s * imu_hz as f64).round() as usize;
    let bias = [0.01, -0.02, 0.015];
    let gyro_table: Vec<[f64; 3]> = (0..per_period)
        .map(|j| {
            let u = j as f64 / imu_hz as f64 * seq.fps;
            let half = (RENDERED - 1) as f64;
            let (at, dir) = if u <= half {
                (u, 1.0)
            } else {
                (2.0 * half - u, -1.0)
            };
            let (w, _) = ecvo_synth::imu::derivatives(&|t| seq.path.pose_at(t), at / seq.fps);
            std::array::from_fn(|i| dir * w[i] + bias[i])
        })
        .collect();
    let mut gyro_next = 0usize;
    let mut gyro_batch: Vec<GyroSample> = Vec::with_capacity(64);
    let config = Config::new(camera, Preset::Phone, Mode::L2);
    let options = PipelineOptions {
        threads,
        admission: Admission::Live,
        geometry: None,
        keep_trajectory: false,
        output_queue: None,
        ..PipelineOptions::default()
    };
    let pipeline = Pipeline::new(config, options).expect("a valid configuration");
    println!(
        "soak: {frames} frames of {}x{}, live, no point cloud, {threads} threads, gyro {}; RSS at start {} kB",
        c.width,
        c.height,
        if imu_hz > 0 {
            format!("{imu_hz} Hz")
        } else {
            "none".into()
        },
        rss_kb()
    );
    println!(
        "{:>8} {:>9} {:>9} {:>8} {:>6} {:>8}",
        "frame", "RSS kB", "tracked", "dropped", "lost", "s"
    );

    let start = Instant::now();
    let mut curve: Vec<(usize, u64)> = Vec::new();
    for k in 0..frames {
        // 0, 1, .., 15, 14, .., 1, 0, 1, ...: continuous motion.
        let period = 2 * (RENDERED - 1);
        let i = k % period;
        let f = &rendered[if i < RENDERED { i } else { period - i }];
        let t = k as f64 / 30.0;
        if imu_hz > 0 {
            // The samples up to the frame (a reused buffer: nothing allocated).
            gyro_batch.clear();
            while (gyro_next as f64 / imu_hz as f64) <= t + 1e-9 {
                gyro_batch.push(GyroSample {
                    t: gyro_next as f64 / imu_hz as f64,
                    w: gyro_table[gyro_next % per_period],
                });
                gyro_next += 1;
            }
            pipeline.push_imu(&gyro_batch).expect("finite samples");
        }
        if k == warmup {
            COUNTING.store(true, Ordering::Relaxed);
        }
        pipeline
            .push(t, |int, depth| {
                int.copy_from_slice(&f.intensity);
                depth.copy_from_slice(&f.depth);
            })
            .expect("push");
        // Let the tracker nearly catch up (a bounded wait: live admission may drop).
        let waited = Instant::now();
        while bookkeeping(|| pipeline.latest().tracked + pipeline_dropped(&pipeline) + 2)
            < k as u64 + 1
            && waited.elapsed() < Duration::from_millis(200)
        {
            std::thread::sleep(Duration::from_micros(200));
        }
        if (k + 1) % every == 0 {
            bookkeeping(|| {
                let s = pipeline.stats();
                let rss = rss_kb();
                curve.push((k + 1, rss));
                println!(
                    "{:>8} {:>9} {:>9} {:>8} {:>6} {:>8.1}",
                    k + 1,
                    rss,
                    s.tracked,
                    s.dropped,
                    s.counters.lost_frames,
                    start.elapsed().as_secs_f64()
                );
            });
        }
    }
    COUNTING.store(false, Ordering::Relaxed);
    let allocs = ALLOCS.load(Ordering::Relaxed);
    let injector = INJECTOR_ALLOCS.load(Ordering::Relaxed);
    let summary = pipeline.finish().expect("the pipeline finishes");
    let s = &summary.stats;
    println!(
        "done: {} pushed, {} tracked, {} dropped, {} lost, filter {:.2} ms, tracker {:.2} ms (medians), {:.0} s",
        s.pushed,
        s.tracked,
        s.dropped,
        s.counters.lost_frames,
        s.filter.median_ms,
        s.tracker.median_ms,
        start.elapsed().as_secs_f64()
    );
    let imu = &s.counters.imu;
    if imu_hz > 0 {
        println!(
            "gyro: {} samples taken, {} refused, {} dropped; {} frames with a gyro prior, {} late, {} missing; bias updates {} ({} outliers)",
            imu.samples,
            imu.refused,
            imu.dropped,
            imu.priors,
            imu.late,
            imu.missing,
            imu.bias_updates,
            imu.bias_outliers
        );
    }
    let counted = frames.saturating_sub(warmup);
    let others = allocs - injector;
    println!(
        "allocations after the warm-up, over {counted} frames: {allocs} ({injector} rayon injector blocks of {INJECTOR_BLOCK} bytes, {others} others{})",
        if others > 0 {
            format!(", the last of {} bytes", OTHER_SIZE.load(Ordering::Relaxed))
        } else {
            String::new()
        }
    );
    let allocs_ok = others == 0 && injector <= (counted as u64).div_ceil(25);

    let after: Vec<u64> = curve
        .iter()
        .filter(|(k, _)| *k > warmup)
        .map(|&(_, r)| r)
        .collect();
    let Some(&first) = after.first() else {
        println!("no sample after the warm-up of {warmup} frames");
        return ExitCode::FAILURE;
    };
    let (lo, hi) = (
        *after.iter().min().expect("samples"),
        *after.iter().max().expect("samples"),
    );
    let spread = hi - lo;
    println!(
        "after {warmup} frames: RSS {first} kB first, {lo}..{hi} kB, spread {spread} kB \
         (allowed {FLAT_KB}), max {hi} kB (allowed {MAX_KB})"
    );
    if spread <= FLAT_KB && hi < MAX_KB && allocs_ok {
        println!("PASS");
        ExitCode::SUCCESS
    } else {
        println!("FAIL");
        ExitCode::FAILURE
    }
}

fn pipeline_dropped(p: &Pipeline) -> u64 {
    p.stats().dropped
}
