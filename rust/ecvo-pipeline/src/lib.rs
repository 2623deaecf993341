//! # ecvo-pipeline
//!
//! The engine every front end of ecvo uses (command line, JNI library, app): the
//! parallel pipeline of An et al., WACV 2018, section 4.1 and Figure 4.
//!
//! ```text
//!  push() ──▶ [input queue] ──▶ filter ──▶ [tracker queue] ──▶ tracker ──▶ [geometry queue] ──▶ geometry
//!  (caller's    raw frames      prepare     pooled prepared     track       reference frames    world cloud
//!   thread)     (pooled)        _into       frames (ref-counted) (Figure 1b) + their poses
//!                                                                │
//!                                                 latest(), outputs(), trajectory, stats()
//! ```
//!
//! - **Stages on their own threads**: the input stage is the caller's
//!   [`Pipeline::push`] (a decode thread, a camera callback); filter, tracker and
//!   geometry each run on a thread of their own and are connected by **bounded FIFO
//!   queues** ([`PipelineOptions::queue_capacity`]). While the tracker works on frame
//!   *n*, the filter prepares frame *n + 1*: their times overlap as in Table 2.
//! - **Compute threads**: the stages do their work inside the pipeline's own
//!   `rayon::ThreadPool` of [`PipelineOptions::threads`] threads (`pool.install`), so
//!   that number bounds all the computing the pipeline does, including any
//!   rayon-parallel loop inside ecvo-core. One thread runs the stages one at a time;
//!   two let filter and tracker overlap, and at 640x480 a free thread also takes
//!   chunks of the other stage's loops.
//! - **Load sharing**: when the tracker is behind (its queue is full, so the filter
//!   would wait anyway), the filter stage also computes the new frame's \[A\],
//!   `frame_to_frame(current, previous)`, which depends on the two frames alone; the
//!   tracker uses it when that previous frame is still its previous frame (not
//!   lost, not dropped) and computes it itself otherwise
//!   ([`PipelineStats::ahead_computed`], [`PipelineStats::ahead_used`]).
//! - **Frame pool**: raw input buffers and prepared frames are pooled and reused; a
//!   prepared frame is shared by reference counting ([`PooledFrame`], the handle the
//!   tracker keeps as previous and reference frame) and returns to the pool when the
//!   last holder drops it, so a reference frame lives exactly as long as it is one.
//!   Once warm, `push`, the queues and the filter, tracker and geometry stages
//!   allocate nothing per frame (`tests/alloc.rs`). The exceptions: the optional
//!   collections ([`PipelineOptions::keep_trajectory`], constant once its
//!   [`PipelineOptions::trajectory_window`] is full,
//!   [`PipelineOptions::output_queue`]), and rayon's own injector queue, which
//!   allocates (and later frees) one 1.5 kB block per 63 jobs handed to the pool from
//!   the stage threads, about one every 25 frames.
//! - **Admission** ([`Admission`]): offline is blocking and lossless; live drops the
//!   oldest waiting frame when the tracker falls behind, so latency stays bounded.
//! - **Determinism**: offline, the poses are bit-for-bit those of the sequential
//!   [`ecvo_core::Odometry`] on the same stream, whatever the number of threads:
//!   every frame is prepared and tracked exactly once, in order, by the same code
//!   (ecvo-core's parallel loops sum over fixed chunks in a fixed order, and an \[A\]
//!   computed ahead is the same computation on the same two frames).
//! - **Failure**: a panic in a stage is caught, closes every queue (so nothing
//!   waits for it) and is returned to the caller as [`Error::StagePanicked`] by the
//!   next `push`, `flush` or `finish`. Dropping a pipeline stops and joins every
//!   thread it started.
//!
//! ```no_run
//! # fn demo(config: ecvo_core::Config, frames: &[(f64, Vec<u8>, Vec<u16>)]) -> ecvo_pipeline::Result<()> {
//! use ecvo_pipeline::{Admission, Pipeline, PipelineOptions};
//! let pipeline = Pipeline::new(config, PipelineOptions {
//!     admission: Admission::Offline,
//!     keep_trajectory: true,
//!     ..PipelineOptions::default()
//! })?;
//! for (t, gray, depth) in frames {
//!     pipeline.push(*t, |i, d| {
//!         i.copy_from_slice(gray);
//!         d.copy_from_slice(depth);
//!     })?;
//! }
//! let summary = pipeline.finish()?;
//! println!("{} frames, {:.1} ms per frame", summary.stats.tracked, summary.stats.wall_ms_per_frame);
//! # Ok(()) }
//! ```

mod chain;
mod geometry;
mod imu;
mod pool;
mod poselog;
mod push;
mod queue;
mod reading;
mod shared;
mod stages;
mod stats;
mod types;

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Condvar, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use crossbeam_channel::{Receiver, SendTimeoutError, Sender, TrySendError};
use ecvo_core::{
    Camera, Config, Counters, FrameOutput, FrameView, MotionEstimator, Pose, Preparer, Tracker,
    TrackingState, frame_to_frame, tracker::working_motion,
};

pub use geometry::{CloudPoint, GeometryOptions};
pub use imu::IMU_INBOX_CAPACITY;
pub use pool::PooledFrame;
pub use stats::{PipelineStats, PoolStats, QueueStats, StageStats};
pub use types::*;

/// The 64-bit content hash [`Pipeline::push`] uses to tell a repeated frame, public
/// for its benchmark (`rust/ecvo-bench/benches/push.rs`).
#[doc(hidden)]
pub use shared::frame_hash;

use chain::{Chain, Published};
use geometry::{Cloud, stage_points};
use pool::{Ahead, FrameMeta, FramePool};
use poselog::PoseLog;
use queue::{Queue, lock};
use shared::*;
use stages::{filter_stage, geometry_stage, tracker_stage};
use stats::{Histogram, copy_counters};

/// The parallel tracking pipeline. `Send + Sync`: `push` from one thread (the
/// camera or decoder), `latest`, `stats` and `cloud_snapshot` from any other.
pub struct Pipeline {
    shared: Arc<Shared>,
    threads: Vec<JoinHandle<()>>,
    workers: Arc<WorkerCount>,
    outputs: Option<Receiver<TrackedFrame>>,
    config: Config,
    options: PipelineOptions,
}

fn panic_message(p: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = p.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = p.downcast_ref::<String>() {
        s.clone()
    } else {
        "non-string panic payload".to_string()
    }
}

fn validate(opts: &PipelineOptions) -> Result<()> {
    let bad = |field: &'static str, why: String| Err(Error::InvalidOptions { field, why });
    if !(1..=256).contains(&opts.threads) {
        return bad("threads", format!("{} is not in 1..=256", opts.threads));
    }
    if opts.trajectory_window == Some(0) {
        return bad(
            "trajectory_window",
            "0 keeps no pose; use None to keep them all".into(),
        );
    }
    if !(1..=1024).contains(&opts.queue_capacity) {
        return bad(
            "queue_capacity",
            format!("{} is not in 1..=1024", opts.queue_capacity),
        );
    }
    if let Some(n) = opts.output_queue
        && !(1..=1 << 20).contains(&n)
    {
        return bad("output_queue", format!("{n} is not in 1..=1048576"));
    }
    if let Some(g) = &opts.geometry {
        if let Some(v) = g.voxel_size_m
            && !(v.is_finite() && v > 0.0)
        {
            return bad("geometry.voxel_size_m", format!("{v} is not positive"));
        }
        if !(1..=100_000_000).contains(&g.max_points) {
            return bad(
                "geometry.max_points",
                format!("{} is not in 1..=100000000", g.max_points),
            );
        }
        if !(1..=64).contains(&g.point_stride) {
            return bad(
                "geometry.point_stride",
                format!("{} is not in 1..=64", g.point_stride),
            );
        }
    }
    Ok(())
}

/// Prepared frames the pool holds: the previous frame, one per level, the one being
/// tracked, the tracker queue, the one being prepared, the filter's previous frame
/// (kept to compute \[A\] ahead), the geometry queue and the one being added.
fn frame_pool_capacity(config: &Config, options: &PipelineOptions) -> usize {
    let q = options.queue_capacity;
    let geometry_frames = if options.geometry.is_some() { q + 1 } else { 0 };
    config.reference_levels.len() + 1 + 1 + q + 1 + 1 + geometry_frames
}

/// Raw input buffers the pool holds: the input queue, the one being filled and the
/// one being prepared, and one spare.
fn raw_pool_capacity(options: &PipelineOptions) -> usize {
    options.queue_capacity + 3
}

impl Pipeline {
    /// Starts the stage threads and the compute pool. Fails on an invalid
    /// configuration or option, on one that needs more memory than
    /// [`Config::memory_budget`] ([`Pipeline::memory_needed`]), or if a thread cannot
    /// be started.
    pub fn new(config: Config, options: PipelineOptions) -> Result<Pipeline> {
        validate(&options)?;
        config.validate()?;
        ecvo_core::memory::check_budget(
            Pipeline::memory_needed(&config, &options),
            config.memory_budget,
        )?;
        let mut tracker: Tracker<PooledFrame> = Tracker::new(config.clone())?;
        let mut preparer = Preparer::new(&config);
        // Only the geometry stage reads the normals (of frames prepared whole, or of
        // reference sides the tracker finishes).
        preparer.set_normals(options.geometry.is_some());
        tracker.set_normals(options.geometry.is_some());
        let levels = config.reference_levels.len();
        let q = options.queue_capacity;
        let pool_capacity = frame_pool_capacity(&config, &options);

        // Counted from the start, so that a pipeline dropped before its workers
        // have even started still waits for them.
        let workers = Arc::new(WorkerCount {
            alive: Mutex::new(options.threads),
            exited: Condvar::new(),
        });
        let w_exit = workers.clone();
        let compute = rayon::ThreadPoolBuilder::new()
            .num_threads(options.threads)
            .thread_name(|i| format!("ecvo-compute-{i}"))
            .exit_handler(move |_| {
                *lock(&w_exit.alive) -= 1;
                w_exit.exited.notify_all();
            })
            .build()
            .map_err(|e| Error::Spawn(e.to_string()))?;
        let compute = Arc::new(compute);

        let shared = Arc::new(Shared {
            camera: config.camera,
            levels,
            admission: options.admission,
            geometry: options.geometry,
            keep_trajectory: options.keep_trajectory,
            #[cfg(any(test, feature = "test-hooks"))]
            hooks: options.test_hooks.clone(),
            abort: AtomicBool::new(false),
            input_closed: AtomicBool::new(false),
            failure: Mutex::new(None),
            next_sequence: AtomicU64::new(0),
            last_input: Mutex::new(LastInput {
                camera: config.camera,
                timestamp: None,
                timestamp_ns: None,
                hash: None,
            }),
            // Raw buffers are created now too, for the same reason as the frame pool.
            raw: Mutex::new(RawPool::new(raw_pool_capacity(&options), config.camera)),
            raw_freed: Condvar::new(),
            input: Queue::new(q),
            prepared: Queue::new(q),
            to_geometry: Queue::new(q),
            frames: FramePool::new(pool_capacity, || {
                ecvo_core::PreparedFrame::for_config(&config)
            }),
            progress: Mutex::new(Progress::default()),
            progress_changed: Condvar::new(),
            velocity: Mutex::new(None),
            depth_noise: Mutex::new(working_motion(&config.motion).depth_noise),
            latest: Mutex::new(LatestPose {
                tracked: 0,
                sequence: 0,
                timestamp: 0.0,
                pose: Pose::identity(),
                state: TrackingState::Initialising,
                reference_levels: 0,
                registration: None,
                lost_reason: None,
                pushed_at: Instant::now(),
                tracked_at: Instant::now(),
            }),
            counters: Mutex::new(tracker.counters().clone()),
            imu: Mutex::new(imu::ImuInbox::new(config.imu)),
            poses: Mutex::new(PoseLog::new(options.trajectory_window)),
            cloud: options.geometry.map(|g| Mutex::new(Cloud::new(g))),
            timers: Timers::default(),
        });

        let (out_tx, out_rx) = match options.output_queue {
            Some(n) => {
                let (tx, rx) = crossbeam_channel::bounded(n);
                (Some(tx), Some(rx))
            }
            None => (None, None),
        };

        let mut pipeline = Pipeline {
            shared: shared.clone(),
            threads: Vec::new(),
            workers,
            outputs: out_rx,
            config,
            options,
        };
        let c = compute.clone();
        let filter_config = pipeline.config.clone();
        pipeline.spawn(Stage::Filter, move |s| {
            filter_stage(s, preparer, &filter_config, &c)
        })?;
        let c = compute.clone();
        pipeline.spawn(Stage::Tracker, move |s| {
            tracker_stage(s, tracker, &c, out_tx)
        })?;
        if pipeline.shared.geometry.is_some() {
            let c = compute.clone();
            pipeline.spawn(Stage::Geometry, move |s| geometry_stage(s, &c))?;
        }
        drop(compute);
        Ok(pipeline)
    }

    /// What a pipeline of `config` and `options` allocates, in bytes, computed
    /// without allocating: an upper bound of its pooled prepared frames (previous,
    /// references, the queues' and stages' frames), its raw input buffers, the
    /// preparer's and the two motion estimators' scratch ([`ecvo_core::memory`]), the
    /// tracker's gyro ring and the IMU inbox ([`IMU_INBOX_CAPACITY`]), the geometry
    /// stage's cloud, and the outputs channel and trajectory window when
    /// they are bounded. [`Pipeline::new`] refuses a configuration whose need exceeds
    /// [`Config::memory_budget`] ([`ecvo_core::Error::MemoryBudget`]) before it
    /// allocates anything.
    ///
    /// Not counted, because nothing bounds them: a trajectory kept without a window
    /// (about 100 bytes a frame), and in live mode the raw buffers allocated for
    /// pushers beyond the pool (more threads pushing at once than it holds).
    pub fn memory_needed(config: &Config, options: &PipelineOptions) -> usize {
        use ecvo_core::memory;
        let n = config.camera.pixels();
        let frames = frame_pool_capacity(config, options) * memory::prepared_frame_bytes(config);
        let raw = raw_pool_capacity(options) * (n * (size_of::<u8>() + size_of::<u16>()));
        let scratch = memory::preparer_bytes(config) + 2 * memory::estimator_bytes(config);
        // The tracker's gyro ring and the inbox in front of it (both allocated at the
        // first `push_imu`).
        let imu =
            memory::imu_bytes() + IMU_INBOX_CAPACITY * size_of::<ecvo_core::imu::GyroSample>();
        let geometry = options.geometry.map_or(0, |g| {
            let point = size_of::<CloudPoint>();
            let stride = g.point_stride.max(1);
            let staged = config.camera.width.div_ceil(stride)
                * config.camera.height.div_ceil(stride)
                * point;
            // hashbrown: buckets a power of two at least 8/7 of the capacity, each a
            // key and a control byte.
            let voxels = g.voxel_size_m.map_or(0, |_| {
                (g.max_points.saturating_mul(8) / 7 + 1).next_power_of_two()
                    * (size_of::<(i32, i32, i32)>() + 1)
            });
            g.max_points.saturating_mul(point) + voxels + staged
        });
        let outputs = options
            .output_queue
            .map_or(0, |q| q.saturating_mul(size_of::<TrackedFrame>()));
        // Each kept pose is a record in one of two double-ended queues that may double.
        let poses = match (options.keep_trajectory, options.trajectory_window) {
            (true, Some(w)) => w.saturating_mul(4 * size_of::<PoseRecord>()),
            _ => 0,
        };
        memory::with_margin(
            frames
                .saturating_add(raw)
                .saturating_add(scratch)
                .saturating_add(imu)
                .saturating_add(geometry)
                .saturating_add(outputs)
                .saturating_add(poses),
        )
    }

    fn spawn(&mut self, stage: Stage, body: impl FnOnce(&Shared) + Send + 'static) -> Result<()> {
        let shared = self.shared.clone();
        let handle = std::thread::Builder::new()
            .name(format!("ecvo-{stage}"))
            .spawn(move || {
                let result = catch_unwind(AssertUnwindSafe(|| body(&shared)));
                if let Err(p) = result {
                    shared.fail(stage, panic_message(p.as_ref()));
                }
                // Downstream stages see the end of their input.
                match stage {
                    Stage::Filter => shared.prepared.close(),
                    Stage::Tracker => shared.to_geometry.close(),
                    Stage::Geometry => {}
                }
                shared.update_progress(|_| {});
            })
            .map_err(|e| Error::Spawn(e.to_string()));
        match handle {
            Ok(h) => {
                self.threads.push(h);
                Ok(())
            }
            Err(e) => {
                // Drop stops and joins what already runs.
                Err(e)
            }
        }
    }

    /// The tracker's configuration.
    pub fn config(&self) -> &Config {
        &self.config
    }

    /// The options the pipeline runs with.
    pub fn options(&self) -> &PipelineOptions {
        &self.options
    }

    /// Waits until every frame pushed before the call is tracked (or dropped) and
    /// every reference frame sent to the geometry stage is in the cloud. Fails if a
    /// stage failed or the pipeline was stopped meanwhile.
    pub fn flush(&self) -> Result<()> {
        let s = &*self.shared;
        let mut p = lock(&s.progress);
        let target = p.pushed;
        loop {
            s.check_failure()?;
            if p.settled() >= target && p.geometry_done >= p.geometry_sent {
                return Ok(());
            }
            if s.aborted() || self.threads.iter().all(|t| t.is_finished()) {
                return Err(s.stopped_error());
            }
            p = s
                .progress_changed
                .wait_timeout(p, Duration::from_millis(100))
                .unwrap_or_else(|e| e.into_inner())
                .0;
        }
    }

    /// Closes the input, lets the stages finish every queued frame, joins every
    /// thread and returns the final statistics, trajectory and cloud; or the first
    /// stage failure. Offline, a caller holding an [`Pipeline::outputs`] receiver
    /// must keep consuming it (or drop it) for this to return.
    pub fn finish(mut self) -> Result<PipelineSummary> {
        self.close_input();
        self.outputs = None;
        self.join();
        self.shared.check_failure()?;
        let s = &*self.shared;
        let stats = self.stats();
        let (trajectory, references) = lock(&s.poses).take();
        Ok(PipelineSummary {
            stats,
            trajectory,
            references,
            cloud: s
                .cloud
                .as_ref()
                .map_or_else(Vec::new, |c| std::mem::take(&mut lock(c).points)),
        })
    }

    /// Joins the stage threads, then waits (a bounded time) for the compute workers,
    /// which exit once the last stage has dropped the pool.
    fn join(&mut self) {
        for t in self.threads.drain(..) {
            // A stage's panic is caught inside the thread; join cannot fail.
            let _ = t.join();
        }
        let deadline = Instant::now() + Duration::from_secs(5);
        let mut alive = lock(&self.workers.alive);
        while *alive > 0 {
            let left = deadline.saturating_duration_since(Instant::now());
            if left.is_zero() {
                log::warn!("ecvo-pipeline: {} compute threads still running", *alive);
                break;
            }
            alive = self
                .workers
                .exited
                .wait_timeout(alive, left)
                .unwrap_or_else(|e| e.into_inner())
                .0;
        }
    }
}

impl Drop for Pipeline {
    /// Stops the stages (queued frames are discarded) and joins every thread.
    fn drop(&mut self) {
        if !self.threads.is_empty() {
            self.shared.abort();
            self.outputs = None;
            self.join();
        }
    }
}

#[cfg(test)]
mod tests;
