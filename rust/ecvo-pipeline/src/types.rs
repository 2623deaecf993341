//! The pipeline's public types: errors, options, push status and the poses it reports.

use super::*;

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
    /// [`crate::Pipeline::push_ns`]: the frame's timestamp is not greater than the
    /// last accepted frame's, compared as integer nanoseconds. As
    /// [`Error::TimestampNotIncreasing`] otherwise.
    #[error("timestamp {timestamp_ns} ns is not after the previous frame's ({previous_ns} ns)")]
    TimestampNsNotIncreasing {
        /// The last accepted frame's timestamp (nanoseconds).
        previous_ns: i64,
        /// The rejected frame's timestamp (nanoseconds).
        timestamp_ns: i64,
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
    /// lists grow with the stream (about 100 bytes per frame) unless
    /// `trajectory_window` bounds them.
    pub keep_trajectory: bool,
    /// With `keep_trajectory`: keep only the latest this many poses (and the reference
    /// records among them), so that memory stays constant over a session of any
    /// length; the older ones are discarded ([`Pipeline::trajectory_start`],
    /// [`PipelineStats::poses_discarded`]). `None` keeps every pose. At least 1.
    ///
    /// [`Pipeline::trajectory_start`]: crate::Pipeline::trajectory_start
    pub trajectory_window: Option<usize>,
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
            trajectory_window: None,
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

/// The latest tracked pose, for a user interface (not `PartialEq`: its
/// `registration` is a [`ecvo_core::MotionResult`]).
#[derive(Clone, Copy, Debug)]
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
    /// The registration the pose came from, as [`ecvo_core::FrameOutput::registration`]:
    /// its `information`, `scale` and `valid_pixels / template_points` are the frame's
    /// quality (None for the first frame, a re-anchored one and a lost one).
    pub registration: Option<ecvo_core::MotionResult>,
    /// Why the frame was lost, as [`ecvo_core::FrameOutput::lost_reason`].
    pub lost_reason: Option<ecvo_core::LostReason>,
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
    /// Every tracked frame's pose (empty unless `keep_trajectory`; only the latest
    /// ones with a `trajectory_window`).
    pub trajectory: Vec<PoseRecord>,
    /// Every reference frame's pose, in order (empty unless `keep_trajectory`; only
    /// those among the kept poses with a `trajectory_window`).
    pub references: Vec<PoseRecord>,
    /// The accumulated cloud (empty without geometry).
    pub cloud: Vec<CloudPoint>,
}
