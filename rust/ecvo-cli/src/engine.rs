//! Driving the tracking engine over a recorded sequence.
//!
//! Everything the commands need from a tracking run goes through
//! [`track_sequence`], which runs the multithreaded [`ecvo_pipeline::Pipeline`] in
//! offline (lossless) admission: the sequence reader decodes frames ahead on its own
//! thread, the calling thread is the pipeline's input stage (it pushes every frame
//! and collects the outputs, in order), and the filter and tracker stages run on the
//! pipeline's threads. Offline, the poses are bit for bit those of the sequential
//! engine whatever the number of threads.
//!
//! The point cloud is gathered here rather than by the pipeline's geometry stage:
//! that stage takes only reference frames (naive tracking has none but the first),
//! reserves its whole capacity up front and thins or caps the cloud, while
//! `cloud.ply` wants every selected frame's points, unthinned. A decoded frame is
//! kept only until its output comes back (a few frames, the pipeline's depth); if
//! the output says the frame is wanted, the calling thread prepares it again (the
//! same deterministic code as the filter stage) and copies its points.

use std::collections::VecDeque;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use ecvo_core::{Config, Counters, FrameOutput, PreparedFrame, Preparer};
use ecvo_io::{Frame, Sequence};
use ecvo_pipeline::{
    Admission, Pipeline, PipelineOptions, PipelineStats, PushStatus, TrackedFrame,
};
use indicatif::{ProgressBar, ProgressStyle};

/// Decoded frames the reader thread may keep waiting ahead of the pipeline.
const PREFETCH: usize = 4;

/// Capacity of the pipeline's output channel. The calling thread drains it after
/// every push, so it never holds more than the frames in flight inside the pipeline
/// (a dozen or so); the margin keeps the tracker from ever waiting on it.
const OUTPUT_QUEUE: usize = 1024;

const MIB: usize = 1 << 20;

/// The pipeline as the CLI runs it.
fn pipeline_options(threads: usize) -> PipelineOptions {
    PipelineOptions {
        threads,
        admission: Admission::Offline,
        geometry: None,
        keep_trajectory: false,
        output_queue: Some(OUTPUT_QUEUE),
        ..PipelineOptions::default()
    }
}

/// What the reader allocates: the decoded frames waiting (`PREFETCH`, one being
/// decoded, one pushed, one kept for the cloud per frame in flight, counted as two)
/// at 3 bytes a pixel, and the decoder's scratch (8 bytes a pixel at most, 16-bit
/// RGBA) on the reader thread.
fn reader_bytes(config: &Config) -> usize {
    let n = config.camera.pixels();
    (PREFETCH + 4) * 3 * n + 8 * n
}

/// Bytes a run of `config` with `threads` allocates for frames: the pipeline's
/// estimate ([`Pipeline::memory_needed`]) plus the reader's ([`reader_bytes`]). Not
/// counted: the poses and outputs kept (about 200 bytes a frame) and the point
/// cloud (the cloud frames' points, 28 bytes each).
pub fn memory_needed(config: &Config, threads: usize) -> usize {
    Pipeline::memory_needed(config, &pipeline_options(threads)) + reader_bytes(config)
}

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
            CloudFrames::EveryNth(n) => out.index.is_multiple_of(n.max(1) as u64),
        }
    }
}

/// How to run the engine over a sequence.
#[derive(Clone, Debug)]
pub struct EngineOptions {
    /// Gyroscope samples pushed beside the frames ([`crate::imu::ImuFeed`]).
    pub imu: Option<crate::imu::ImuStream>,
    /// Track only the first this many frames (all if `None`).
    pub max_frames: Option<usize>,
    /// Compute threads of the pipeline (1..=256).
    pub threads: usize,
    /// Show a progress bar on stderr.
    pub progress: bool,
    /// Frames whose points are collected.
    pub cloud: CloudFrames,
    /// Take every `cloud_stride`-th pixel in each direction for the cloud.
    pub cloud_stride: usize,
    /// Make a skipped frame (repeated, or its timestamp not after the previous one)
    /// an error instead of a warning.
    pub strict: bool,
}

/// Frames of the stream that were read but not tracked, or tracked without depth.
#[derive(Clone, Debug, Default)]
pub struct Skips {
    /// Frames bit-identical to the previous one (positions in the stream).
    pub repeated: Vec<usize>,
    /// Frames whose timestamp was not after the previous frame's.
    pub timestamp_not_increasing: Vec<usize>,
    /// Frames with no depth pixel in the filter's range (tracked, but lost unless
    /// the tracker can register them on intensity alone, which it does not).
    pub no_valid_depth: Vec<usize>,
}

/// The stream frames checked for valid depth with an immediate warning.
const EARLY_DEPTH_FRAMES: usize = 5;

/// Raw depth values that the filter stage keeps: non-zero and within the filter's
/// depth range at the camera's depth scale.
fn valid_raw_depth(config: &Config) -> (u16, u16) {
    let s = config.camera.depth_scale;
    let lo = (config.filter.min_depth_m * s).ceil().max(1.0);
    let hi = (config.filter.max_depth_m * s)
        .floor()
        .min(f64::from(u16::MAX));
    if !(lo <= hi) {
        return (1, 0);
    }
    (lo as u16, hi as u16)
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

/// The result of tracking a sequence.
#[derive(Clone, Debug)]
pub struct TrackRun {
    /// What the tracker said about every frame, in stream order.
    pub outputs: Vec<FrameOutput>,
    /// The tracker's counters at the end.
    pub counters: Counters,
    /// The pipeline's statistics at the end (stage times, wall time per frame, queue
    /// depths, drops).
    pub stats: PipelineStats,
    /// Milliseconds the calling thread spent gathering each cloud frame's points
    /// (preparing it again and copying them), in stream order.
    pub cloud_ms: Vec<f64>,
    /// Points of the frames selected by [`EngineOptions::cloud`], in stream order.
    pub clouds: Vec<FramePoints>,
    /// Wall-clock time of the whole run, seconds (decoding, the pipeline's start and
    /// stop and the cloud included).
    pub wall_s: f64,
    /// Compute threads the pipeline used.
    pub threads: usize,
    /// Frames not tracked, or tracked without depth.
    pub skips: Skips,
}

/// The calling thread's side of a run: frames waiting for their output, and what
/// has come back.
struct Collector<'a> {
    cloud: CloudFrames,
    cloud_stride: usize,
    preparer: Option<Preparer>,
    scratch: PreparedFrame,
    pending: VecDeque<Frame>,
    outputs: Vec<FrameOutput>,
    clouds: Vec<FramePoints>,
    cloud_ms: Vec<f64>,
    bar: &'a ProgressBar,
}

impl Collector<'_> {
    /// Takes one tracked frame: matches it with its decoded frame (returned for
    /// recycling, if it was kept), and gathers its points if the cloud wants it.
    fn take(&mut self, t: TrackedFrame) -> Result<Option<Frame>> {
        let expected = self.outputs.len() as u64;
        if t.sequence != expected || t.output.index != expected {
            // Offline admission drops nothing, so a gap is a frame the filter stage
            // could not prepare.
            let what = self
                .pending
                .front()
                .map(|f| format!("frame {} (timestamp {})", f.index, f.timestamp))
                .unwrap_or_else(|| format!("frame {expected}"));
            bail!("{what} could not be prepared (see the log)");
        }
        let mut done = None;
        if let Some(preparer) = &mut self.preparer {
            let frame = self
                .pending
                .pop_front()
                .context("an output came back for a frame that was not pushed")?;
            if self.cloud.wants(&t.output) {
                let t0 = Instant::now();
                preparer
                    .prepare_into(frame.view(), &mut self.scratch)
                    .with_context(|| {
                        format!("frame {} (timestamp {})", frame.index, frame.timestamp)
                    })?;
                self.clouds.push(frame_points(
                    &self.scratch,
                    t.output.index,
                    self.cloud_stride,
                ));
                self.cloud_ms.push(t0.elapsed().as_secs_f64() * 1e3);
            }
            done = Some(frame);
        }
        self.outputs.push(t.output);
        self.bar.inc(1);
        Ok(done)
    }
}

/// Tracks `sequence` with `config` through the pipeline (offline, `opts.threads`
/// compute threads): every frame is decoded (ahead, on the reader's thread), pushed,
/// prepared and tracked exactly once, in order.
///
/// Fails on an invalid configuration and on the first frame that cannot be decoded
/// or prepared (the error names it).
pub fn track_sequence(
    sequence: &Sequence,
    config: &Config,
    opts: &EngineOptions,
) -> Result<TrackRun> {
    let options = pipeline_options(opts.threads);
    let need = memory_needed(config, opts.threads);
    if need > config.memory_budget {
        let c = &config.camera;
        bail!(
            "{}x{} frames need {} MiB (the tracking pipeline {} MiB, frames decoded ahead {} \
             MiB), more than the memory budget of {} MiB (--max-memory)",
            c.width,
            c.height,
            need.div_ceil(MIB),
            Pipeline::memory_needed(config, &options).div_ceil(MIB),
            reader_bytes(config).div_ceil(MIB),
            config.memory_budget / MIB
        );
    }
    let pipeline =
        Pipeline::new(config.clone(), options).context("invalid tracker configuration")?;
    let rx = pipeline
        .outputs()
        .context("the pipeline has no output channel")?;
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
    let mut c = Collector {
        cloud: opts.cloud,
        cloud_stride: opts.cloud_stride,
        preparer: (opts.cloud != CloudFrames::None).then(|| Preparer::whole(config)),
        scratch: PreparedFrame::default(),
        pending: VecDeque::new(),
        outputs: Vec::with_capacity(n),
        clouds: Vec::new(),
        cloud_ms: Vec::new(),
        bar: &bar,
    };
    let mut skips = Skips::default();
    let (lo, hi) = valid_raw_depth(config);
    let mut warned_depth = false;
    let mut reader = sequence.reader(Some(n), PREFETCH);
    let mut imu = opts
        .imu
        .as_ref()
        .map(|s| ecvo_io::imu::ImuFeed::new(s.samples.to_vec(), s.calibration.time_offset));
    // Not a `for` loop: the reader is also used inside to recycle frames.
    #[allow(clippy::while_let_on_iterator)]
    while let Some(item) = reader.next() {
        let frame = item.with_context(|| format!("reading {}", sequence.dir().display()))?;
        let what = || format!("frame {} (timestamp {})", frame.index, frame.timestamp);
        if !frame.depth.iter().any(|&d| d >= lo && d <= hi) {
            skips.no_valid_depth.push(frame.index);
            if frame.index < EARLY_DEPTH_FRAMES && !warned_depth {
                warned_depth = true;
                let c = &config.camera;
                log::warn!(
                    "{}: no valid depth pixel (every raw value is 0 or outside {}..={}, which \
                     is {} to {} m at depth_scale {}); without depth the frames are lost: is \
                     depth_scale right?",
                    what(),
                    lo,
                    hi,
                    config.filter.min_depth_m,
                    config.filter.max_depth_m,
                    c.depth_scale
                );
            }
        }
        if let Some(f) = &mut imu {
            pipeline
                .push_imu(f.before_frame(&frame))
                .context("pushing IMU samples")?;
        }
        // With the depth's own time: turned to the intensity's by the gyro, if any.
        match pipeline.push_view_with_depth_time(frame.view(), frame.depth_timestamp) {
            Ok(PushStatus::Repeated) => {
                // Bit-identical to the previous frame: not tracked (counted in the
                // pipeline's statistics).
                if opts.strict {
                    bail!("{}: identical to the previous frame (--strict)", what());
                }
                log::warn!("{}: identical to the previous frame, skipped", what());
                skips.repeated.push(frame.index);
                reader.recycle(frame);
                continue;
            }
            Ok(_) => {}
            Err(e @ ecvo_pipeline::Error::TimestampNotIncreasing { .. }) => {
                if opts.strict {
                    bail!("{}: {e} (--strict)", what());
                }
                log::warn!("{}: {e}; skipped", what());
                skips.timestamp_not_increasing.push(frame.index);
                reader.recycle(frame);
                continue;
            }
            Err(e) => return Err(e).with_context(what),
        }
        if c.preparer.is_some() {
            c.pending.push_back(frame);
        } else {
            reader.recycle(frame);
        }
        while let Ok(t) = rx.try_recv() {
            if let Some(f) = c.take(t)? {
                reader.recycle(f);
            }
        }
    }
    // No more input: the stages drain their queues and stop, and the channel closes
    // once the tracker has sent its last output.
    pipeline.close_input();
    for t in rx.iter() {
        if let Some(f) = c.take(t)? {
            reader.recycle(f);
        }
    }
    drop(rx);
    let summary = pipeline.finish().context("the tracking pipeline failed")?;
    bar.finish_and_clear();
    let skipped = summary.stats.repeated_frames + summary.stats.timestamps_rejected;
    if c.outputs.len() as u64 + skipped != n as u64 {
        let what = c
            .pending
            .front()
            .map(|f| format!("frame {} (timestamp {})", f.index, f.timestamp))
            .unwrap_or_else(|| format!("frame {}", c.outputs.len()));
        bail!("{what} could not be prepared (see the log)");
    }
    Ok(TrackRun {
        outputs: c.outputs,
        counters: summary.stats.counters.clone(),
        stats: summary.stats,
        cloud_ms: c.cloud_ms,
        clouds: c.clouds,
        wall_s: start.elapsed().as_secs_f64(),
        threads: opts.threads,
        skips,
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

#[cfg(test)]
mod tests {
    use super::*;
    use ecvo_core::{Camera, Mode, Preset};

    fn config(width: usize, height: usize) -> Config {
        let camera = Camera {
            width,
            height,
            fx: 0.8 * width as f64,
            fy: 0.8 * width as f64,
            cx: (width as f64 - 1.0) / 2.0,
            cy: (height as f64 - 1.0) / 2.0,
            depth_scale: 5000.0,
        };
        Config::new(camera, Preset::Pc, Mode::L2)
    }

    /// The largest frame of the aspect `w:h` (a multiple of it) within the default
    /// budget with `threads`.
    fn largest(w: usize, h: usize, threads: usize) -> (usize, usize) {
        let mut k = 1;
        while {
            let c = config(w * (k + 1), h * (k + 1));
            c.camera.width <= 8192 && memory_needed(&c, threads) <= c.memory_budget
        } {
            k += 1;
        }
        (w * k, h * k)
    }

    #[test]
    fn default_budget_fits_vga_and_refuses_the_largest_camera() {
        for threads in [1, 2] {
            let vga = config(640, 480);
            let need = memory_needed(&vga, threads);
            println!("{threads} thread(s): 640x480 needs {} MiB", need >> 20);
            assert!(need < vga.memory_budget / 2, "{need}");
            let big = config(8192, 8192);
            assert!(memory_needed(&big, threads) > big.memory_budget);
            // The reader's share is counted on top of the pipeline's.
            assert!(
                memory_needed(&vga, threads)
                    > Pipeline::memory_needed(&vga, &pipeline_options(threads))
            );
            let (w, h) = largest(16, 9, threads);
            let (w4, h4) = largest(4, 3, threads);
            // Printed for the README (`cargo test -p ecvo-cli -- --nocapture budget`).
            println!(
                "{threads} thread(s): largest 16:9 frame {w}x{h}, 4:3 {w4}x{h4} within {} MiB",
                vga.memory_budget >> 20
            );
            assert!((1024..8192).contains(&w), "{w}x{h}");
        }
    }
}
