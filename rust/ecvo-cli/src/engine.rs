//! Driving the tracking engine over a recorded sequence.
//!
//! Everything the commands need from a tracking run goes through
//! [`track_sequence`], so that the sequential loop here (a [`Preparer`] and a
//! [`Tracker`] on the calling thread, frames decoded ahead by the sequence reader)
//! can be swapped for the multithreaded pipeline without touching the commands.

use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context, Result};
use ecvo_core::{Config, Counters, FrameOutput, PreparedFrame, Preparer, Tracker};
use ecvo_io::Sequence;
use indicatif::{ProgressBar, ProgressStyle};

/// Decoded frames the reader thread may keep waiting ahead of the tracker.
const PREFETCH: usize = 4;

/// Which frames contribute their points to the point cloud.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CloudFrames {
    /// No point cloud.
    None,
    /// The first frame and every frame that became a reference frame (any level).
    References,
    /// Frames `0, n, 2n, ...` (naive tracking has no reference frames).
    EveryNth(usize),
}

impl CloudFrames {
    fn wants(self, out: &FrameOutput) -> bool {
        match self {
            CloudFrames::None => false,
            CloudFrames::References => out.index == 0 || out.reference_levels > 0,
            CloudFrames::EveryNth(n) => out.index % n.max(1) as u64 == 0,
        }
    }
}

/// How to run the engine over a sequence.
#[derive(Clone, Debug)]
pub struct EngineOptions {
    /// Track only the first this many frames (all if `None`).
    pub max_frames: Option<usize>,
    /// Worker threads (recorded; the sequential engine uses one thread plus the
    /// frame reader).
    pub threads: usize,
    /// Show a progress bar on stderr.
    pub progress: bool,
    /// Frames whose points are collected.
    pub cloud: CloudFrames,
    /// Take every `cloud_stride`-th pixel in each direction for the cloud.
    pub cloud_stride: usize,
}

/// Points of one frame in its camera's coordinates, as [`PreparedFrame::for_each_point`]
/// gives them.
#[derive(Clone, Debug, Default)]
pub struct FramePoints {
    /// Position of the frame in the stream.
    pub index: u64,
    /// Points in camera coordinates (metres).
    pub points: Vec<[f32; 3]>,
    /// Unit normals in camera coordinates (NaN where unknown).
    pub normals: Vec<[f32; 3]>,
    /// Intensity 0..=255.
    pub intensity: Vec<u8>,
}

/// Wall-clock time of each stage for one frame, in milliseconds.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StageTimes {
    /// The filter stage: preparing the frame (filters, pyramid, templates).
    pub filter_ms: f64,
    /// The tracker stage: motion estimation and error correction.
    pub tracker_ms: f64,
}

impl StageTimes {
    /// Filter plus tracker time (frame decoding runs ahead on its own thread and is
    /// not included).
    pub fn total_ms(&self) -> f64 {
        self.filter_ms + self.tracker_ms
    }
}

/// The result of tracking a sequence.
#[derive(Clone, Debug)]
pub struct TrackRun {
    /// What the tracker said about every frame, in stream order.
    pub outputs: Vec<FrameOutput>,
    /// The tracker's counters at the end.
    pub counters: Counters,
    /// Per-frame stage times, in stream order.
    pub times: Vec<StageTimes>,
    /// Points of the frames selected by [`EngineOptions::cloud`], in stream order.
    pub clouds: Vec<FramePoints>,
    /// Wall-clock time of the whole run, seconds (decoding included).
    pub wall_s: f64,
    /// Threads the run was asked to use.
    pub threads: usize,
}

/// Tracks `sequence` with `config`: every frame is decoded (ahead, on the reader's
/// thread), prepared and tracked, and both stages are timed.
///
/// Fails on an invalid configuration and on the first frame that cannot be decoded
/// (the error names the file).
pub fn track_sequence(
    sequence: &Sequence,
    config: &Config,
    opts: &EngineOptions,
) -> Result<TrackRun> {
    let mut tracker: Tracker<Arc<PreparedFrame>> =
        Tracker::new(config.clone()).context("invalid tracker configuration")?;
    let mut preparer = Preparer::new(tracker.config());
    let n = opts
        .max_frames
        .map_or(sequence.len(), |m| m.min(sequence.len()));

    let bar = if opts.progress {
        let bar = ProgressBar::new(n as u64);
        if let Ok(style) = ProgressStyle::with_template(
            "{spinner} tracking [{bar:40}] {pos}/{len} frames, {per_sec}, eta {eta}",
        ) {
            bar.set_style(style.progress_chars("=> "));
        }
        bar
    } else {
        ProgressBar::hidden()
    };

    let start = Instant::now();
    let mut outputs = Vec::with_capacity(n);
    let mut times = Vec::with_capacity(n);
    let mut clouds = Vec::new();
    // Prepared frames the tracker no longer holds are reused, so memory stays flat.
    let mut pool: Vec<Arc<PreparedFrame>> = Vec::new();
    let mut reader = sequence.reader(Some(n), PREFETCH);
    // Not a `for` loop: the reader is also used inside to recycle frames.
    #[allow(clippy::while_let_on_iterator)]
    while let Some(item) = reader.next() {
        let frame = item.with_context(|| format!("reading {}", sequence.dir().display()))?;
        let slot = pool.iter().position(|f| Arc::strong_count(f) == 1);
        let mut prepared = match slot {
            Some(i) => pool.swap_remove(i),
            None => Arc::new(PreparedFrame::default()),
        };

        let t0 = Instant::now();
        let target = Arc::get_mut(&mut prepared).context("a pooled frame is still shared")?;
        preparer
            .prepare_into(frame.view(), target)
            .with_context(|| format!("frame {} (timestamp {})", frame.index, frame.timestamp))?;
        let t1 = Instant::now();
        let out = tracker.track(prepared.clone());
        let t2 = Instant::now();

        times.push(StageTimes {
            filter_ms: (t1 - t0).as_secs_f64() * 1e3,
            tracker_ms: (t2 - t1).as_secs_f64() * 1e3,
        });
        if opts.cloud.wants(&out) {
            clouds.push(frame_points(&prepared, out.index, opts.cloud_stride));
        }
        outputs.push(out);
        pool.push(prepared);
        bar.inc(1);
        reader.recycle(frame);
    }
    bar.finish_and_clear();
    Ok(TrackRun {
        outputs,
        counters: tracker.counters().clone(),
        times,
        clouds,
        wall_s: start.elapsed().as_secs_f64(),
        threads: opts.threads,
    })
}

/// Copies the points of a prepared frame (every `stride`-th pixel).
fn frame_points(frame: &PreparedFrame, index: u64, stride: usize) -> FramePoints {
    let mut fp = FramePoints {
        index,
        ..FramePoints::default()
    };
    frame.for_each_point(stride, |p, n, i| {
        fp.points.push(p);
        fp.normals.push(n);
        fp.intensity.push(i);
    });
    fp
}
