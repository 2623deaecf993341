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
//!   would wait anyway), the filter stage also computes the new frame's [A],
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
//!   collections ([`PipelineOptions::keep_trajectory`],
//!   [`PipelineOptions::output_queue`]), and rayon's own injector queue, which
//!   allocates (and later frees) one 1.5 kB block per 63 jobs handed to the pool from
//!   the stage threads, about one every 25 frames.
//! - **Admission** ([`Admission`]): offline is blocking and lossless; live drops the
//!   oldest waiting frame when the tracker falls behind, so latency stays bounded.
//! - **Determinism**: offline, the poses are bit-for-bit those of the sequential
//!   [`ecvo_core::Odometry`] on the same stream, whatever the number of threads:
//!   every frame is prepared and tracked exactly once, in order, by the same code
//!   (ecvo-core's parallel loops sum over fixed chunks in a fixed order, and an [A]
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
mod pool;
mod queue;
mod stats;

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Condvar, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use crossbeam_channel::{Receiver, SendTimeoutError, Sender, TrySendError};
use ecvo_core::{
    Camera, Config, Counters, FrameOutput, FrameView, MotionEstimator, Pose, Preparer, Tracker,
    TrackingState, frame_to_frame,
};

pub use geometry::{CloudPoint, GeometryOptions};
pub use pool::PooledFrame;
pub use stats::{PipelineStats, PoolStats, QueueStats, StageStats};

use chain::{Chain, Published};
use geometry::{Cloud, stage_points};
use pool::{Ahead, FrameMeta, FramePool};
use queue::{Queue, lock};
use stats::{Histogram, copy_counters};

/// What can go wrong in the pipeline.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum Error {
    /// A bad configuration or a frame that does not match the camera.
    #[error(transparent)]
    Core(#[from] ecvo_core::Error),
    /// A pipeline option is out of range; `field` names it.
    #[error("invalid pipeline option `{field}`: {why}")]
    InvalidOptions {
        /// The offending option.
        field: &'static str,
        /// Why it is rejected.
        why: String,
    },
    /// A stage panicked; the pipeline has stopped.
    #[error("the {stage} stage panicked: {message}")]
    StagePanicked {
        /// The stage that panicked.
        stage: Stage,
        /// The panic message.
        message: String,
    },
    /// The input was closed ([`Pipeline::close_input`]) or the pipeline stopped.
    #[error("the pipeline no longer accepts frames")]
    Closed,
    /// A thread could not be started.
    #[error("could not start the pipeline's threads: {0}")]
    Spawn(String),
    /// The frame's timestamp is not greater than the last frame's accepted by `push`
    /// (a duplicated or backwards timestamp). The frame is not queued; the pipeline
    /// goes on, and frames with later timestamps are accepted.
    #[error("timestamp {timestamp} is not after the previous frame's ({previous})")]
    TimestampNotIncreasing {
        /// The last accepted frame's timestamp (seconds).
        previous: f64,
        /// The rejected frame's timestamp (seconds).
        timestamp: f64,
    },
}

/// Result with the pipeline's error.
pub type Result<T> = std::result::Result<T, Error>;

/// The stages that run on threads of their own.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Stage {
    /// Frame preparation (bilateral, normal and contour filters, pyramid, templates).
    Filter,
    /// Motion estimation with adaptive error correction.
    Tracker,
    /// The point cloud of the reference frames.
    Geometry,
}

impl std::fmt::Display for Stage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Stage::Filter => "filter",
            Stage::Tracker => "tracker",
            Stage::Geometry => "geometry",
        })
    }
}

/// What happens when frames arrive faster than they are tracked.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Admission {
    /// Blocking and lossless: `push` waits for room, every frame is tracked, and the
    /// poses equal the sequential engine's bit for bit. For files.
    Offline,
    /// Never waits for the tracker: when a queue is full its oldest frame is dropped
    /// (and counted) to make room, so the latency stays bounded. For cameras.
    Live,
}

/// Settings of the pipeline (the tracker's own are in [`ecvo_core::Config`]).
#[derive(Clone, Debug)]
pub struct PipelineOptions {
    /// Compute threads of the pipeline's rayon pool, which all stages share (1..=256).
    /// 2 lets the filter and the tracker overlap; more help only where ecvo-core
    /// splits its loops (images of 640x480 and up). On big.LITTLE phones, count the
    /// big cores.
    pub threads: usize,
    /// Offline (lossless) or live (bounded latency).
    pub admission: Admission,
    /// Capacity of each of the three queues (1..=1024).
    pub queue_capacity: usize,
    /// Accumulate the reference frames' points; `None` runs no geometry stage.
    pub geometry: Option<GeometryOptions>,
    /// Keep every frame's pose and every reference frame's pose for
    /// [`Pipeline::trajectory`], [`Pipeline::references`] and the summary. These
    /// lists grow with the stream (about 100 bytes per frame).
    pub keep_trajectory: bool,
    /// Send each frame's output to a bounded channel of this capacity
    /// ([`Pipeline::outputs`]); `None` sends nothing. Offline, the tracker waits while
    /// the channel is full, so consume it (or drop every receiver); live, an output
    /// that does not fit is discarded and counted.
    pub output_queue: Option<usize>,
    /// Fault injection for tests; absent from production builds.
    #[cfg(any(test, feature = "test-hooks"))]
    pub test_hooks: TestHooks,
}

impl Default for PipelineOptions {
    /// Two threads, offline, queues of 2, no geometry, no trajectory, no outputs
    /// channel.
    fn default() -> Self {
        PipelineOptions {
            threads: 2,
            admission: Admission::Offline,
            queue_capacity: 2,
            geometry: None,
            keep_trajectory: false,
            output_queue: None,
            #[cfg(any(test, feature = "test-hooks"))]
            test_hooks: TestHooks::default(),
        }
    }
}

/// Test-only fault injection (feature `test-hooks`).
#[cfg(any(test, feature = "test-hooks"))]
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TestHooks {
    /// Panic in this stage when it handles the frame with this push sequence number.
    pub panic_at: Option<(Stage, u64)>,
    /// Sleep this long in this stage for every frame.
    pub delay: Option<(Stage, Duration)>,
}

/// What `push` did with a frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PushStatus {
    /// The frame was queued.
    Accepted,
    /// Live mode: the frame was queued, and the oldest waiting frame was dropped to
    /// make room for it.
    DroppedOldest,
    /// The frame is bit-identical (depth and intensity) to the previous frame given
    /// to `push`: a frozen camera delivering the same image again. It is not queued
    /// (it carries no new information, and tracked it would read as a still camera);
    /// counted in [`PipelineStats::repeated_frames`]. Its timestamp counts as the
    /// last one, and the next new frame is registered against the last tracked one.
    /// Frames without any valid depth are never `Repeated`: they are tracked, and
    /// flagged lost.
    Repeated,
}

/// A tracked frame as sent to [`Pipeline::outputs`].
#[derive(Clone, Copy, Debug)]
pub struct TrackedFrame {
    /// Position of the frame among the frames pushed, from 0 (differs from
    /// `output.index`, the position among the frames tracked, once frames are
    /// dropped).
    pub sequence: u64,
    /// The tracker's output.
    pub output: FrameOutput,
}

/// The pose of one frame, as kept in the trajectory and the reference list.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PoseRecord {
    /// Position among the frames pushed.
    pub sequence: u64,
    /// Position among the frames tracked.
    pub index: u64,
    /// Capture time, seconds.
    pub timestamp: f64,
    /// Camera-to-world pose.
    pub pose: Pose,
    /// Tracking or lost.
    pub state: TrackingState,
    /// The frame became the reference at levels `1..=reference_levels` (the first
    /// frame and a re-anchored frame are references at every level).
    pub reference_levels: u8,
}

/// The latest tracked pose, for a user interface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LatestPose {
    /// Frames tracked so far (0: the fields below are not meaningful yet).
    pub tracked: u64,
    /// Push sequence number of the frame.
    pub sequence: u64,
    /// Capture time, seconds.
    pub timestamp: f64,
    /// Camera-to-world pose.
    pub pose: Pose,
    /// The tracker's state after the frame.
    pub state: TrackingState,
    /// The frame became the reference at levels `1..=reference_levels`.
    pub reference_levels: u8,
    /// When the frame was pushed.
    pub pushed_at: Instant,
    /// When its pose was published.
    pub tracked_at: Instant,
}

/// What [`Pipeline::finish`] returns.
#[derive(Clone, Debug)]
pub struct PipelineSummary {
    /// Final statistics.
    pub stats: PipelineStats,
    /// Every tracked frame's pose (empty unless `keep_trajectory`).
    pub trajectory: Vec<PoseRecord>,
    /// Every reference frame's pose, in order (empty unless `keep_trajectory`).
    pub references: Vec<PoseRecord>,
    /// The accumulated cloud (empty without geometry).
    pub cloud: Vec<CloudPoint>,
}

/// One raw input frame in the input pool.
struct RawFrame {
    sequence: u64,
    timestamp: f64,
    pushed_at: Instant,
    intensity: Vec<u8>,
    depth: Vec<u16>,
}

struct RawPool {
    free: Vec<RawFrame>,
}

/// A reference frame on its way to the geometry stage.
struct GeometryItem {
    frame: PooledFrame,
    pose: Pose,
}

#[derive(Default)]
struct Progress {
    pushed: u64,
    tracked: u64,
    dropped_at_input: u64,
    dropped_at_tracker: u64,
    failed_preparations: u64,
    geometry_sent: u64,
    geometry_done: u64,
    geometry_skipped: u64,
    outputs_discarded: u64,
    ahead_computed: u64,
    ahead_used: u64,
    timestamps_rejected: u64,
    repeated_frames: u64,
    first_push: Option<Instant>,
    last_tracked: Option<Instant>,
}

impl Progress {
    /// Frames that need nothing more from the filter and tracker.
    fn settled(&self) -> u64 {
        self.tracked + self.dropped_at_input + self.dropped_at_tracker + self.failed_preparations
    }
}

#[derive(Default)]
struct Timers {
    filter: Mutex<Histogram>,
    tracker: Mutex<Histogram>,
    geometry: Mutex<Histogram>,
    latency: Mutex<Histogram>,
}

/// State shared by the caller and the stage threads.
struct Shared {
    camera: Camera,
    levels: usize,
    admission: Admission,
    geometry: Option<GeometryOptions>,
    keep_trajectory: bool,
    #[cfg(any(test, feature = "test-hooks"))]
    hooks: TestHooks,

    abort: AtomicBool,
    input_closed: AtomicBool,
    failure: Mutex<Option<Error>>,
    next_sequence: AtomicU64,
    /// The last frame accepted by `push`: its timestamp and content hash.
    last_input: Mutex<LastInput>,

    raw: Mutex<RawPool>,
    raw_freed: Condvar,
    input: Queue<RawFrame>,
    prepared: Queue<PooledFrame>,
    to_geometry: Queue<GeometryItem>,
    frames: Arc<FramePool>,

    progress: Mutex<Progress>,
    progress_changed: Condvar,
    latest: Mutex<LatestPose>,
    /// The tracker's velocity after its last frame: that frame's sequence and [A]
    /// (motion and interval) when it registered frame to frame. The filter stage
    /// restarts its [A]-ahead chain from it.
    velocity: Mutex<Published>,
    counters: Mutex<Counters>,
    trajectory: Mutex<Vec<PoseRecord>>,
    references: Mutex<Vec<PoseRecord>>,
    cloud: Option<Mutex<Cloud>>,
    timers: Timers,
}

/// What `push` remembers of the last frame it accepted (queued or repeated).
#[derive(Default)]
struct LastInput {
    timestamp: Option<f64>,
    hash: Option<u64>,
}

/// A 64-bit hash of a frame's intensity and depth, to tell a frame bit-identical to
/// the previous one (two different frames collide with probability about 2^-64). Four
/// independent lanes of multiply-rotate over 8-byte words.
fn frame_hash(intensity: &[u8], depth: &[u16]) -> u64 {
    const K: u64 = 0x9E37_79B9_7F4A_7C15;
    let mut lanes = [K, K ^ 1, K ^ 2, K ^ 3];
    let mut mix = |i: usize, w: u64| {
        lanes[i & 3] = (lanes[i & 3] ^ w).wrapping_mul(K).rotate_left(29);
    };
    let words = intensity.chunks_exact(8);
    let tail = words.remainder();
    let mut n = 0;
    for w in words {
        mix(
            n,
            u64::from_le_bytes([w[0], w[1], w[2], w[3], w[4], w[5], w[6], w[7]]),
        );
        n += 1;
    }
    for &b in tail {
        mix(n, u64::from(b) | 1 << 63);
        n += 1;
    }
    let words = depth.chunks_exact(4);
    let tail = words.remainder();
    for w in words {
        mix(
            n,
            u64::from(w[0]) | u64::from(w[1]) << 16 | u64::from(w[2]) << 32 | u64::from(w[3]) << 48,
        );
        n += 1;
    }
    for &d in tail {
        mix(n, u64::from(d) | 1 << 62);
        n += 1;
    }
    let h = lanes.iter().fold(
        intensity.len() as u64 ^ (depth.len() as u64) << 32,
        |h, &l| (h ^ l).wrapping_mul(K).rotate_left(31),
    );
    h ^ h >> 32
}

impl Shared {
    /// Fails (and counts) if `timestamp` is not after the last accepted frame's.
    fn check_timestamp(&self, last: &LastInput, timestamp: f64) -> Result<()> {
        match last.timestamp {
            Some(previous) if timestamp <= previous => {
                self.update_progress(|p| p.timestamps_rejected += 1);
                Err(Error::TimestampNotIncreasing {
                    previous,
                    timestamp,
                })
            }
            _ => Ok(()),
        }
    }

    fn aborted(&self) -> bool {
        self.abort.load(Ordering::Acquire)
    }

    /// The error to report once the pipeline no longer takes frames.
    fn stopped_error(&self) -> Error {
        lock(&self.failure).clone().unwrap_or(Error::Closed)
    }

    fn check_failure(&self) -> Result<()> {
        match &*lock(&self.failure) {
            Some(e) => Err(e.clone()),
            None => Ok(()),
        }
    }

    fn update_progress(&self, f: impl FnOnce(&mut Progress)) {
        f(&mut lock(&self.progress));
        self.progress_changed.notify_all();
    }

    /// Stops everything: no stage waits for another once this returns.
    fn abort(&self) {
        self.abort.store(true, Ordering::Release);
        self.input.close();
        self.prepared.close();
        self.to_geometry.close();
        self.frames.wake_all();
        {
            let _g = lock(&self.raw);
            self.raw_freed.notify_all();
        }
        self.update_progress(|_| {});
    }

    fn fail(&self, stage: Stage, message: String) {
        log::error!("ecvo-pipeline: the {stage} stage panicked: {message}");
        lock(&self.failure).get_or_insert(Error::StagePanicked { stage, message });
        self.abort();
    }

    /// A free raw frame; in live mode, when none is free, the oldest queued one is
    /// taken back (and counted as dropped). Returns whether one was dropped.
    fn take_raw(&self) -> Result<(RawFrame, bool)> {
        let mut g = lock(&self.raw);
        loop {
            if self.aborted() || self.input_closed.load(Ordering::Acquire) {
                return Err(self.stopped_error());
            }
            if let Some(r) = g.free.pop() {
                return Ok((r, false));
            }
            if self.admission == Admission::Live {
                drop(g);
                if let Some(old) = self.input.try_pop() {
                    self.update_progress(|p| p.dropped_at_input += 1);
                    return Ok((old, true));
                }
                g = lock(&self.raw);
                continue;
            }
            g = self
                .raw_freed
                .wait_timeout(g, Duration::from_millis(50))
                .unwrap_or_else(|e| e.into_inner())
                .0;
        }
    }

    fn give_raw(&self, raw: RawFrame) {
        lock(&self.raw).free.push(raw);
        self.raw_freed.notify_one();
    }

    #[cfg(any(test, feature = "test-hooks"))]
    fn hook(&self, stage: Stage, sequence: u64) {
        if let Some((s, d)) = self.hooks.delay
            && s == stage
        {
            std::thread::sleep(d);
        }
        if self.hooks.panic_at == Some((stage, sequence)) {
            panic!("injected panic in the {stage} stage at frame {sequence}");
        }
    }

    #[cfg(not(any(test, feature = "test-hooks")))]
    #[inline(always)]
    fn hook(&self, _stage: Stage, _sequence: u64) {}
}

/// Returns raw frames to the pool if `fill` panics.
struct RawGuard<'a> {
    shared: &'a Shared,
    raw: Option<RawFrame>,
}

impl Drop for RawGuard<'_> {
    fn drop(&mut self) {
        if let Some(r) = self.raw.take() {
            self.shared.give_raw(r);
        }
    }
}

/// Counts the rayon workers still alive, so that dropping the pipeline can wait
/// for them (a dropped `rayon::ThreadPool` does not join its threads).
struct WorkerCount {
    alive: Mutex<usize>,
    exited: Condvar,
}

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

impl Pipeline {
    /// Starts the stage threads and the compute pool. Fails on an invalid
    /// configuration or option, or if a thread cannot be started.
    pub fn new(config: Config, options: PipelineOptions) -> Result<Pipeline> {
        validate(&options)?;
        let tracker: Tracker<PooledFrame> = Tracker::new(config.clone())?;
        let preparer = Preparer::new(&config);
        let levels = config.reference_levels.len();
        let q = options.queue_capacity;
        let geometry_frames = if options.geometry.is_some() { q + 1 } else { 0 };
        // Previous + one per level + the one being tracked + the tracker queue + the
        // one being prepared + the filter's previous frame (kept to compute [A] ahead)
        // + the geometry queue and the one being added.
        let pool_capacity = levels + 1 + 1 + q + 1 + 1 + geometry_frames;

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
            last_input: Mutex::new(LastInput::default()),
            // Raw buffers are created now too, for the same reason as the frame pool.
            raw: Mutex::new(RawPool {
                free: (0..q + 3)
                    .map(|_| RawFrame {
                        sequence: 0,
                        timestamp: 0.0,
                        pushed_at: Instant::now(),
                        intensity: vec![0; config.camera.pixels()],
                        depth: vec![0; config.camera.pixels()],
                    })
                    .collect(),
            }),
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
            latest: Mutex::new(LatestPose {
                tracked: 0,
                sequence: 0,
                timestamp: 0.0,
                pose: Pose::identity(),
                state: TrackingState::Initialising,
                reference_levels: 0,
                pushed_at: Instant::now(),
                tracked_at: Instant::now(),
            }),
            counters: Mutex::new(tracker.counters().clone()),
            trajectory: Mutex::new(Vec::new()),
            references: Mutex::new(Vec::new()),
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

    /// Queues one frame: `fill` writes its intensity and raw depth (each `width *
    /// height`, row-major) into a pooled buffer, which it must overwrite entirely
    /// (the buffer holds an older frame). Offline, waits while the input queue is
    /// full; live, returns at once, dropping the oldest waiting frame if need be.
    ///
    /// Push from one thread at a time for frames to be tracked in push order. Fails
    /// on a non-finite timestamp, on one not greater than the last accepted frame's
    /// ([`Error::TimestampNotIncreasing`]; the frame is not queued, the pipeline goes
    /// on), after [`Pipeline::close_input`], or once a stage has failed (with that
    /// failure). A frame bit-identical to the previous one is not queued:
    /// [`PushStatus::Repeated`].
    pub fn push(
        &self,
        timestamp: f64,
        fill: impl FnOnce(&mut [u8], &mut [u16]),
    ) -> Result<PushStatus> {
        let pushed_at = Instant::now();
        let s = &*self.shared;
        if !timestamp.is_finite() {
            return Err(
                ecvo_core::Error::BadFrame(format!("timestamp {timestamp} is not finite")).into(),
            );
        }
        // A closed or failed pipeline says so before anything else.
        if s.aborted() || s.input_closed.load(Ordering::Acquire) {
            return Err(s.stopped_error());
        }
        s.check_timestamp(&lock(&s.last_input), timestamp)?;
        let (raw, mut dropped) = s.take_raw()?;
        let mut guard = RawGuard {
            shared: s,
            raw: Some(raw),
        };
        let (hash, blank) = {
            let r = guard.raw.as_mut().expect("the guard holds the frame");
            fill(&mut r.intensity, &mut r.depth);
            (
                frame_hash(&r.intensity, &r.depth),
                r.depth.iter().all(|&d| d == 0),
            )
        };
        {
            // Checked again: another thread may have pushed meanwhile.
            let mut last = lock(&s.last_input);
            s.check_timestamp(&last, timestamp)?;
            // A frame without any depth (a covered lens) goes to the tracker, which
            // flags it lost, however often it comes.
            let repeated = !blank && last.hash == Some(hash);
            last.timestamp = Some(timestamp);
            last.hash = Some(hash);
            if repeated {
                drop(last);
                s.update_progress(|p| p.repeated_frames += 1);
                return Ok(PushStatus::Repeated);
            }
        }
        let mut raw = guard.raw.take().expect("the guard holds the frame");
        raw.timestamp = timestamp;
        raw.pushed_at = pushed_at;
        raw.sequence = s.next_sequence.fetch_add(1, Ordering::Relaxed);
        {
            let mut p = lock(&s.progress);
            p.pushed += 1;
            p.first_push.get_or_insert(pushed_at);
        }
        let queued = match s.admission {
            Admission::Offline => s.input.push_blocking(raw).map(|()| None),
            Admission::Live => s.input.push_evicting(raw),
        };
        match queued {
            Ok(None) => {}
            Ok(Some(old)) => {
                s.give_raw(old);
                s.update_progress(|p| p.dropped_at_input += 1);
                dropped = true;
            }
            Err(raw) => {
                s.give_raw(raw);
                s.update_progress(|p| p.pushed -= 1);
                return Err(s.stopped_error());
            }
        }
        Ok(if dropped {
            PushStatus::DroppedOldest
        } else {
            PushStatus::Accepted
        })
    }

    /// Queues a copy of `view` (checked against the camera); see [`Pipeline::push`].
    pub fn push_view(&self, view: FrameView<'_>) -> Result<PushStatus> {
        view.validate(&self.config.camera)?;
        self.push(view.timestamp, |i, d| {
            i.copy_from_slice(view.intensity);
            d.copy_from_slice(view.depth);
        })
    }

    /// Declares the end of the stream: further pushes fail with [`Error::Closed`],
    /// the stages finish the frames already queued, and the outputs channel closes
    /// after the last one.
    pub fn close_input(&self) {
        self.shared.input_closed.store(true, Ordering::Release);
        self.shared.input.close();
        let _g = lock(&self.shared.raw);
        self.shared.raw_freed.notify_all();
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

    /// A receiver of every tracked frame's output, in order (`None` unless
    /// [`PipelineOptions::output_queue`] is set). It disconnects after the last
    /// frame once the input is closed.
    pub fn outputs(&self) -> Option<Receiver<TrackedFrame>> {
        self.outputs.clone()
    }

    /// The latest tracked pose, its timestamp and the tracking state. Copies a small
    /// struct under a mutex that the tracker holds only to overwrite it once per
    /// frame, so it never blocks the tracker for more than that copy.
    pub fn latest(&self) -> LatestPose {
        *lock(&self.shared.latest)
    }

    /// Every tracked frame's pose so far (empty unless `keep_trajectory`).
    pub fn trajectory(&self) -> Vec<PoseRecord> {
        lock(&self.shared.trajectory).clone()
    }

    /// Every reference frame's pose so far, in order, the first frame included
    /// (empty unless `keep_trajectory`).
    pub fn references(&self) -> Vec<PoseRecord> {
        lock(&self.shared.references).clone()
    }

    /// A consistent copy of the cloud (empty without geometry). The geometry thread
    /// owns the cloud and adds a reference frame's points under a short lock; the
    /// copy is taken under the same lock, so it never stops the tracker.
    pub fn cloud_snapshot(&self) -> Vec<CloudPoint> {
        let mut v = Vec::new();
        self.cloud_snapshot_into(0, &mut v);
        v
    }

    /// Appends the cloud's points from position `from` on to `out` and returns the
    /// cloud's size. The cloud only grows at its end, so a renderer can pass the size
    /// it got last time and copy only the new points.
    pub fn cloud_snapshot_into(&self, from: usize, out: &mut Vec<CloudPoint>) -> usize {
        match &self.shared.cloud {
            Some(c) => {
                let c = lock(c);
                if from < c.points.len() {
                    out.extend_from_slice(&c.points[from..]);
                }
                c.points.len()
            }
            None => 0,
        }
    }

    /// A snapshot of the statistics, callable at any time.
    pub fn stats(&self) -> PipelineStats {
        let s = &*self.shared;
        let (progress, wall) = {
            let p = lock(&s.progress);
            let wall = match (p.first_push, p.last_tracked) {
                (Some(a), Some(b)) if p.tracked > 0 => {
                    b.saturating_duration_since(a).as_secs_f64() * 1e3 / p.tracked as f64
                }
                _ => 0.0,
            };
            (
                [
                    p.pushed,
                    p.tracked,
                    p.dropped_at_input,
                    p.dropped_at_tracker,
                    p.failed_preparations,
                    p.geometry_skipped,
                    p.outputs_discarded,
                    p.ahead_computed,
                    p.ahead_used,
                    p.timestamps_rejected,
                    p.repeated_frames,
                ],
                wall,
            )
        };
        let [
            pushed,
            tracked,
            dropped_at_input,
            dropped_at_tracker,
            failed_preparations,
            geometry_skipped,
            outputs_discarded,
            ahead_computed,
            ahead_used,
            timestamps_rejected,
            repeated_frames,
        ] = progress;
        PipelineStats {
            filter: lock(&s.timers.filter).summary(),
            tracker: lock(&s.timers.tracker).summary(),
            geometry: lock(&s.timers.geometry).summary(),
            latency: lock(&s.timers.latency).summary(),
            wall_ms_per_frame: wall,
            pushed,
            tracked,
            dropped: dropped_at_input + dropped_at_tracker,
            dropped_at_input,
            dropped_at_tracker,
            failed_preparations,
            geometry_skipped,
            outputs_discarded,
            ahead_computed,
            ahead_used,
            timestamps_rejected,
            repeated_frames,
            input_queue: s.input.stats(),
            tracker_queue: s.prepared.stats(),
            geometry_queue: s.to_geometry.stats(),
            frame_pool: s.frames.stats(),
            counters: lock(&s.counters).clone(),
            cloud_points: s.cloud.as_ref().map_or(0, |c| lock(c).points.len()),
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
        Ok(PipelineSummary {
            stats: self.stats(),
            trajectory: std::mem::take(&mut *lock(&s.trajectory)),
            references: std::mem::take(&mut *lock(&s.references)),
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

/// The filter stage: prepares each frame. While the tracker is behind (its queue is
/// not empty), it also computes the frame's [A] against the frame it prepared just
/// before, which is the tracker's previous frame unless that one is lost: the
/// tracker then only corrects against its references, and the two stages share the
/// work more evenly. [A] depends on the two frames alone, so the poses are the same.
fn filter_stage(s: &Shared, mut preparer: Preparer, config: &Config, compute: &rayon::ThreadPool) {
    let mut estimator =
        MotionEstimator::with_capacity(ecvo_core::prepare::max_template_points(config));
    // The frame prepared last, while the next one may still follow at once.
    let mut last: Option<PooledFrame> = None;
    // What the tracker's prediction for the next frame will be, as far as this stage
    // knows it: the [A] it computed ahead for the frame `last` (or that frame being
    // the first, with nothing to predict from).
    let mut chain = Chain::default();
    loop {
        let raw = match s.input.try_pop() {
            Some(raw) => raw,
            None => {
                // Nothing waiting: let the last frame go (only the tracker keeps frames
                // while the pipeline is idle), then wait.
                last = None;
                match s.input.pop() {
                    Some(raw) => raw,
                    None => break,
                }
            }
        };
        if s.aborted() {
            break;
        }
        let Some(mut slot) = s.frames.acquire(&s.abort) else {
            break;
        };
        s.hook(Stage::Filter, raw.sequence);
        let slot_mut = Arc::get_mut(&mut slot).expect("an acquired slot is exclusive");
        let view = FrameView {
            timestamp: raw.timestamp,
            intensity: &raw.intensity,
            depth: &raw.depth,
        };
        let prepared = &mut slot_mut.frame;
        // Timed inside the pool: a stage's time is its work, not its wait for a thread.
        let (result, ahead, filtered_in) = compute.install(|| {
            let t0 = Instant::now();
            let r = preparer.prepare_into(view, prepared);
            // The tracker is behind when its queue is full: this frame would wait.
            let behind = s.prepared.len() >= s.prepared.capacity();
            let ahead = match (&r, &last) {
                (Ok(()), Some(prev)) => {
                    let published = *lock(&s.velocity);
                    let offline = s.admission == Admission::Offline;
                    let known =
                        chain.prior(config, prev, prepared.timestamp, behind, offline, published);
                    known.map(|prior| Ahead {
                        against: prev.sequence(),
                        prior,
                        result: frame_to_frame(
                            &mut estimator,
                            prepared,
                            prev,
                            prior.as_ref(),
                            config,
                        ),
                    })
                }
                _ => None,
            };
            if r.is_ok() {
                chain.prepared(raw.sequence, prepared.timestamp, ahead.as_ref());
            }
            (r, ahead, t0.elapsed())
        });
        slot_mut.meta = FrameMeta {
            sequence: raw.sequence,
            pushed_at: raw.pushed_at,
            ahead,
        };
        lock(&s.timers.filter).record(filtered_in);
        s.give_raw(raw);
        if let Err(e) = result {
            log::warn!("ecvo-pipeline: frame not prepared: {e}");
            s.frames.give_back(slot);
            s.update_progress(|p| p.failed_preparations += 1);
            continue;
        }
        if ahead.is_some() {
            s.update_progress(|p| p.ahead_computed += 1);
        }
        let frame = s.frames.share(slot);
        last = Some(frame.clone());
        match s.admission {
            Admission::Offline => {
                if s.prepared.push_blocking(frame).is_err() {
                    break;
                }
            }
            Admission::Live => match s.prepared.push_evicting(frame) {
                Ok(None) => {}
                Ok(Some(old)) => {
                    drop(old);
                    s.update_progress(|p| p.dropped_at_tracker += 1);
                }
                Err(_) => break,
            },
        }
    }
}

fn tracker_stage(
    s: &Shared,
    mut tracker: Tracker<PooledFrame>,
    compute: &rayon::ThreadPool,
    outputs: Option<Sender<TrackedFrame>>,
) {
    let all_levels = s.levels.min(u8::MAX as usize) as u8;
    while let Some(frame) = s.prepared.pop() {
        if s.aborted() {
            break;
        }
        let meta = frame.meta();
        s.hook(Stage::Tracker, meta.sequence);
        let for_geometry = s.geometry.is_some().then(|| frame.clone());
        let mut used_ahead = false;
        let (out, tracked_in) = compute.install(|| {
            let t0 = Instant::now();
            let out = tracker.track_with(frame, |prev, prior| {
                let a = meta
                    .ahead
                    .filter(|a| a.against == prev.sequence() && a.prior.as_ref() == prior)?;
                used_ahead = true;
                Some(a.result)
            });
            (out, t0.elapsed())
        });
        if used_ahead {
            s.update_progress(|p| p.ahead_used += 1);
        }
        *lock(&s.velocity) = Some((
            meta.sequence,
            tracker
                .velocity()
                .filter(|v| v.index == out.index)
                .map(|v| (v.motion, v.dt)),
        ));

        let anchored = out.index == 0 || out.reanchored;
        let reference_levels = if anchored {
            all_levels
        } else {
            out.reference_levels
        };
        let is_reference = anchored || out.reference_levels > 0;
        if let Some(frame) = for_geometry
            && is_reference
        {
            let item = GeometryItem {
                frame,
                pose: out.pose,
            };
            match s.admission {
                Admission::Offline => {
                    s.update_progress(|p| p.geometry_sent += 1);
                    if s.to_geometry.push_blocking(item).is_err() {
                        s.update_progress(|p| p.geometry_sent -= 1);
                    }
                }
                Admission::Live => {
                    s.update_progress(|p| p.geometry_sent += 1);
                    if s.to_geometry.try_push(item).is_err() {
                        s.update_progress(|p| {
                            p.geometry_sent -= 1;
                            p.geometry_skipped += 1;
                        });
                    }
                }
            }
        }

        let now = Instant::now();
        *lock(&s.latest) = LatestPose {
            tracked: out.index + 1,
            sequence: meta.sequence,
            timestamp: out.timestamp,
            pose: out.pose,
            state: out.state,
            reference_levels,
            pushed_at: meta.pushed_at,
            tracked_at: now,
        };
        copy_counters(&mut lock(&s.counters), tracker.counters());
        if s.keep_trajectory {
            let record = PoseRecord {
                sequence: meta.sequence,
                index: out.index,
                timestamp: out.timestamp,
                pose: out.pose,
                state: out.state,
                reference_levels,
            };
            lock(&s.trajectory).push(record);
            if is_reference {
                lock(&s.references).push(record);
            }
        }
        if let Some(tx) = &outputs {
            let mut msg = TrackedFrame {
                sequence: meta.sequence,
                output: out,
            };
            match s.admission {
                Admission::Offline => loop {
                    match tx.send_timeout(msg, Duration::from_millis(50)) {
                        Ok(()) | Err(SendTimeoutError::Disconnected(_)) => break,
                        Err(SendTimeoutError::Timeout(m)) => {
                            if s.aborted() {
                                break;
                            }
                            msg = m;
                        }
                    }
                },
                Admission::Live => {
                    if let Err(TrySendError::Full(_)) = tx.try_send(msg) {
                        s.update_progress(|p| p.outputs_discarded += 1);
                    }
                }
            }
        }
        lock(&s.timers.tracker).record(tracked_in);
        lock(&s.timers.latency).record(now.saturating_duration_since(meta.pushed_at));
        s.update_progress(|p| {
            p.tracked += 1;
            p.last_tracked = Some(now);
        });
    }
}

fn geometry_stage(s: &Shared, compute: &rayon::ThreadPool) {
    let (Some(opts), Some(cloud)) = (s.geometry, &s.cloud) else {
        return;
    };
    let stride = opts.point_stride.max(1);
    let per_frame = s.camera.width.div_ceil(stride) * s.camera.height.div_ceil(stride);
    let mut staged = Vec::with_capacity(per_frame);
    while let Some(item) = s.to_geometry.pop() {
        if s.aborted() {
            break;
        }
        s.hook(Stage::Geometry, item.frame.sequence());
        let t0 = Instant::now();
        compute.install(|| stage_points(&item.frame, &item.pose, stride, &mut staged));
        drop(item);
        lock(cloud).extend(&staged);
        lock(&s.timers.geometry).record(t0.elapsed());
        s.update_progress(|p| p.geometry_done += 1);
    }
}

#[cfg(test)]
mod tests;
