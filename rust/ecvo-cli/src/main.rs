//! `ecvo`: track an RGB-D camera through a recorded sequence with the improved
//! frame-to-frame method of An et al. (WACV 2018), evaluate trajectories, reproduce
//! the paper's Table 1 and render synthetic test streams.
//!
//! Every error is printed as one message naming the file (and line) involved, and
//! the process exits with status 1 (2 for unusable command-line flags).
// The run summary is one `json!` literal, deeper than the default limit allows.
#![recursion_limit = "256"]
// The help texts are these doc comments, and they name the paper's motion
// estimations [A], [B], [C] as the paper does: not links.
#![allow(rustdoc::broken_intra_doc_links)]

/// `print!` for the command's results: a closed stdout (`ecvo eval GT EST | head -1`)
/// ends the process quietly with status 0, as in every Unix tool, instead of the
/// standard macro's panic; another write error is an error message and status 1.
macro_rules! out {
    ($($arg:tt)*) => {
        $crate::write_stdout(format_args!($($arg)*))
    };
}

/// `println!` through [`out!`].
macro_rules! outln {
    ($($arg:tt)*) => {
        $crate::write_stdout(format_args!("{}\n", format_args!($($arg)*)))
    };
}

mod engine;
mod imu;
mod outputs;
mod plot;
mod run;
mod settings;
mod stats;
mod synth;
mod table;
mod track_args;

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::Result;
use clap::{Parser, Subcommand};
use ecvo_core::Mode;
use ecvo_io::Trajectory;
use ecvo_io::files::shown_path;
use serde_json::json;

use crate::plot::Plane;
use crate::run::{Evaluation, RunOutputs};
use crate::settings::TrackSettings;
use crate::synth::{Motion, Noise, Size};
use crate::track_args::{LimitArgs, ModeArg, PresetArg, TrackArgs};

#[derive(Parser)]
#[command(
    name = "ecvo",
    version,
    about = "RGB-D camera tracking (An et al., WACV 2018)"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// More messages on stderr: -v for progress notes, -vv for debugging (RUST_LOG,
    /// e.g. `RUST_LOG=ecvo_io=debug`, overrides both flags).
    #[arg(short, long, action = clap::ArgAction::Count, global = true)]
    verbose: u8,
    /// Only errors on stderr (the frame account still appears when a frame was
    /// skipped or lost).
    #[arg(short, long, global = true, conflicts_with = "verbose")]
    quiet: bool,
}

/// Writes `args` to stdout and flushes it; see [`out!`].
fn write_stdout(args: std::fmt::Arguments<'_>) {
    use std::io::Write;
    let mut stdout = std::io::stdout().lock();
    if let Err(e) = stdout.write_fmt(args).and_then(|()| stdout.flush()) {
        if e.kind() == std::io::ErrorKind::BrokenPipe {
            std::process::exit(0);
        }
        eprintln!("error: writing to stdout: {e}");
        std::process::exit(1);
    }
}

/// Set by `-q`.
static QUIET: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Prints the one-line account of a run's frames on stderr: as a warning when a frame
/// was skipped or lost, else as a note (left out with -q).
pub(crate) fn report_account(line: &str, loss: bool) {
    if loss {
        eprintln!("warning: {}", printable(line));
    } else if !QUIET.load(std::sync::atomic::Ordering::Relaxed) {
        eprintln!("{}", printable(line));
    }
}

/// A message as stderr shows it: control characters escaped, at most 4,000
/// characters (paths inside are already shortened by ecvo-io).
fn printable(text: &str) -> String {
    const MAX: usize = 4000;
    let mut out = String::with_capacity(text.len().min(MAX + 16));
    for (n, c) in text.chars().enumerate() {
        if n == MAX {
            out.push_str("…[cut]");
            break;
        }
        if c.is_control() {
            out.extend(c.escape_default());
        } else {
            out.push(c);
        }
    }
    out
}

/// The logger: `warning: ...` lines on stderr, at warn level by default, info with
/// -v, debug with -vv, trace with -vvv, errors only with -q; `RUST_LOG` overrides.
fn init_logger(verbose: u8, quiet: bool) {
    use std::io::Write as _;
    let level = match (quiet, verbose) {
        (true, _) => log::LevelFilter::Error,
        (false, 0) => log::LevelFilter::Warn,
        (false, 1) => log::LevelFilter::Info,
        (false, 2) => log::LevelFilter::Debug,
        _ => log::LevelFilter::Trace,
    };
    let mut builder = env_logger::Builder::new();
    builder.filter_level(level);
    if let Ok(spec) = std::env::var("RUST_LOG") {
        builder.parse_filters(&spec);
    }
    builder.format(|buf, record| {
        let prefix = match record.level() {
            log::Level::Error => "error: ",
            log::Level::Warn => "warning: ",
            log::Level::Info => "",
            log::Level::Debug | log::Level::Trace => "debug: ",
        };
        writeln!(buf, "{prefix}{}", printable(&record.args().to_string()))
    });
    builder.target(env_logger::Target::Stderr);
    let logger = builder.build();
    log::set_max_level(logger.filter());
    let _ = log::set_boxed_logger(Box::new(SayOnce {
        inner: logger,
        said: std::sync::Mutex::new(std::collections::HashSet::new()),
    }));
}

/// The logger around env_logger that says each warning once: `ecvo table` opens a
/// sequence once per cell, and its reader's warnings (list entries without a partner)
/// are the same every time.
struct SayOnce {
    inner: env_logger::Logger,
    /// Hashes of the warnings said so far; at most [`SayOnce::MAX_REMEMBERED`].
    said: std::sync::Mutex<std::collections::HashSet<u64>>,
}

impl SayOnce {
    /// Beyond this many different warnings, new ones are all said (the memory stays
    /// bounded whatever the input).
    const MAX_REMEMBERED: usize = 4096;
}

impl log::Log for SayOnce {
    fn enabled(&self, metadata: &log::Metadata<'_>) -> bool {
        self.inner.enabled(metadata)
    }

    fn log(&self, record: &log::Record<'_>) {
        if !self.inner.matches(record) {
            return;
        }
        if record.level() == log::Level::Warn {
            use std::hash::{Hash, Hasher};
            let mut h = std::collections::hash_map::DefaultHasher::new();
            record.args().to_string().hash(&mut h);
            let key = h.finish();
            let mut said = self.said.lock().unwrap_or_else(|e| e.into_inner());
            if said.contains(&key) {
                return;
            }
            if said.len() < Self::MAX_REMEMBERED {
                said.insert(key);
            }
        }
        self.inner.log(record);
    }

    fn flush(&self) {
        self.inner.flush();
    }
}

#[derive(Subcommand)]
enum Command {
    /// Track a sequence and write trajectory.txt (TUM poses), states.txt (the
    /// tracker's word on each frame), references.txt, summary.json (settings,
    /// counters, errors, times, the frame account), cloud.ply and trajectory.svg
    /// into --out.
    Run {
        /// Sequence folder (TUM layout with camera.json, or ICL-NUIM).
        seq: PathBuf,
        #[command(flatten)]
        track: TrackArgs,
        /// Which error-correction levels run.
        #[arg(help_heading = "Method", display_order = 11, long, value_enum, default_value_t = ModeArg::L2)]
        mode: ModeArg,
        /// Reference levels overriding the preset's, e.g. "30mm:7deg,120mm:12deg".
        #[arg(
            help_heading = "Method",
            display_order = 12,
            long,
            allow_hyphen_values = true
        )]
        levels: Option<String>,
        /// Switch the bilateral depth filter off. With the phone preset keep the
        /// contour filter off too (--no-contour-filter): at its 20° it reads raw depth
        /// noise as depth edges and removes nearly every pixel.
        #[arg(help_heading = "Tuning", display_order = 34, long)]
        no_bilateral: bool,
        /// Switch the normal-based removal filter off.
        #[arg(help_heading = "Tuning", display_order = 35, long)]
        no_normal_filter: bool,
        /// Switch the contour-based removal filter off.
        #[arg(help_heading = "Tuning", display_order = 36, long)]
        no_contour_filter: bool,
        /// Output folder (created if needed; files in it are overwritten).
        #[arg(help_heading = "Output", display_order = 40, long)]
        out: PathBuf,
        /// Point cloud: take every Nth pixel in each direction.
        #[arg(help_heading = "Output", display_order = 42, long, default_value_t = 4)]
        cloud_stride: usize,
        /// Point cloud with --mode naive: take every Nth frame.
        #[arg(
            help_heading = "Output",
            display_order = 43,
            long,
            default_value_t = 15
        )]
        cloud_every: usize,
        /// Plane of the top view in trajectory.svg.
        #[arg(help_heading = "Output", display_order = 41, long, value_enum, default_value_t = Plane::Xz)]
        plot_plane: Plane,
        #[command(flatten)]
        limits: LimitArgs,
    },
    /// ATE and RPE of an estimated TUM trajectory against a ground-truth one.
    Eval {
        /// Ground-truth trajectory (TUM format).
        gt: PathBuf,
        /// Estimated trajectory (TUM format).
        est: PathBuf,
        /// Print a JSON object instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Print the paper's Table 1 (naive, L1, L2) for the given sequences as Markdown.
    Table {
        /// Sequence folders.
        #[arg(required = true)]
        seqs: Vec<PathBuf>,
        #[command(flatten)]
        track: TrackArgs,
        /// Frame steps to run each sequence at, e.g. 1,2,3,4 (overrides --frame-step;
        /// each 1 to 1000).
        #[arg(help_heading = "Input", display_order = 3, long, value_delimiter = ',', value_parser = clap::value_parser!(u32).range(1..=1000))]
        frame_steps: Vec<u32>,
        /// Also write every row as JSON lines to this file.
        #[arg(help_heading = "Output", display_order = 40, long)]
        json: Option<PathBuf>,
        #[command(flatten)]
        limits: LimitArgs,
    },
    /// Render a synthetic stream with exact ground truth: a 320x180 phone-like camera
    /// by default, or the TUM Kinect's 640x480 one (--size).
    Synth {
        /// Output folder (must not already hold a sequence).
        #[arg(long)]
        out: PathBuf,
        /// Number of frames (30 per second).
        #[arg(long, default_value_t = 90)]
        frames: usize,
        /// Seed of the scene, the camera path and the noise.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Sensor noise model.
        #[arg(long, value_enum, default_value_t = Noise::Phone)]
        noise: Noise,
        /// Timestamp of the first frame, seconds.
        #[arg(long, default_value_t = 1_700_000_000.0)]
        start_time: f64,
        /// Camera motion: the slow hand-held walk around the room, fast hand-held
        /// shaking and panning in front of a wall (see --depth, --max-rot-speed,
        /// --max-speed), or a far-depth hand-held orbit panning round a hall (see
        /// --depth, --max-rot-speed).
        #[arg(long, value_enum, default_value_t = Motion::Slow)]
        motion: Motion,
        /// Fast motion: distance from the camera to the wall it looks at, metres
        /// (0.4–4.5, default 2; the mean viewing depth is within about 10 % of it).
        /// Orbit: viewing distance of the hall's walls, metres (1–4.5, default 2.5;
        /// the mean viewing depth is within about 4 % of it).
        #[arg(long)]
        depth: Option<f64>,
        /// Texture contrast of every surface, (0, 1]: 1 is the standard room, 0.05 a
        /// room of nearly blank walls (the shading of each face still differs).
        #[arg(long, default_value_t = 1.0)]
        texture_contrast: f64,
        /// Fast motion and orbit: peak rotation rate between frames, degrees per
        /// second (default 90 for fast, 45 for orbit: 1.5° a frame at 30 Hz).
        #[arg(long)]
        max_rot_speed: Option<f64>,
        /// Fast motion: peak speed between frames, metres per second.
        #[arg(long)]
        max_speed: Option<f64>,
        /// Image size and camera: the phone-like 320x180 one, or the TUM Kinect's
        /// 640x480 (fx = fy = 525, depth in 1/5000 m) seeing the same scene and path.
        #[arg(long, value_enum, default_value_t = Size::Phone320x180)]
        size: Size,
        /// Do not write imu.txt (a simulated phone IMU riding on the camera: gyro and
        /// accelerometer at 200-400 Hz with datasheet noise and bias, its rotation
        /// and time offset in camera.json).
        #[arg(long)]
        no_imu: bool,
        /// Take each depth image this many milliseconds after its intensity image
        /// (before it if negative; |delay| < 20, the readers pair images at most 20 ms
        /// apart), stamped so in depth.txt, as a Kinect's two streams are: 0 by
        /// default.
        #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
        depth_delay_ms: f64,
    },
    /// Make a SIMULATED imu.txt for a real sequence from its groundtruth.txt: a smooth
    /// spline through the poses, its derivatives, then a phone IMU's noise, bias,
    /// camera-IMU rotation and time offset. Writes imu.txt and a camera.json with
    /// the calibration into --out (outside the sequence folder); track with `ecvo run
    /// SEQ --imu OUT/imu.txt`.
    ImuFromGroundtruth {
        /// Sequence folder with groundtruth.txt and camera.json.
        seq: PathBuf,
        /// Output folder (not inside the sequence folder).
        #[arg(long)]
        out: PathBuf,
        /// Seed of the IMU's rate, rotation, offset, bias and noise.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Spacing of the spline's control poses, seconds.
        #[arg(long, default_value_t = imu::GROUNDTRUTH_KNOT_S)]
        knot: f64,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    init_logger(cli.verbose, cli.quiet);
    QUIET.store(cli.quiet, std::sync::atomic::Ordering::Relaxed);
    match dispatch(cli.command) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", printable(&message(&e)));
            ExitCode::FAILURE
        }
    }
}

/// The error and its causes on one line, leaving out a cause that the message before
/// it already quotes (ecvo-io's errors include their I/O source in their text).
fn message(e: &anyhow::Error) -> String {
    let mut parts: Vec<String> = Vec::new();
    for cause in e.chain() {
        let text = cause.to_string();
        if parts.last().is_some_and(|prev| prev.contains(&text)) {
            continue;
        }
        parts.push(text);
    }
    parts.join(": ")
}

fn dispatch(command: Command) -> Result<()> {
    match command {
        Command::Run {
            seq,
            track,
            mode,
            levels,
            no_bilateral,
            no_normal_filter,
            no_contour_filter,
            out,
            cloud_stride,
            cloud_every,
            plot_plane,
            limits,
        } => {
            let mode = match mode {
                ModeArg::Naive => Mode::Naive,
                ModeArg::L1 => Mode::L1,
                ModeArg::L2 => Mode::L2,
            };
            if no_bilateral && !no_contour_filter && matches!(track.preset, PresetArg::Phone) {
                log::warn!(
                    "--no-bilateral with the phone preset's contour filter (20°): on \
                     raw depth the contour test reads the noise as depth edges and removes nearly \
                     every pixel (frames lost as failed_toofewpixels); add --no-contour-filter"
                );
            }
            let settings = TrackSettings {
                levels,
                bilateral: !no_bilateral,
                normal_filter: !no_normal_filter,
                contour_filter: !no_contour_filter,
                ..track.settings(mode, &limits)
            };
            let outs = RunOutputs {
                out,
                cloud_stride,
                cloud_every,
                plane: plot_plane,
            };
            run::run_command(&seq, &settings, &outs)
        }
        Command::Eval { gt, est, json } => eval_command(&gt, &est, json),
        Command::Table {
            seqs,
            track,
            frame_steps,
            json,
            limits,
        } => {
            let steps: Vec<usize> = if frame_steps.is_empty() {
                vec![track.frame_step as usize]
            } else {
                frame_steps.iter().map(|&s| s as usize).collect()
            };
            table::table_command(
                &seqs,
                &track.settings(Mode::L2, &limits),
                &steps,
                json.as_deref(),
            )
        }
        Command::Synth {
            out,
            frames,
            seed,
            noise,
            start_time,
            motion,
            depth,
            max_rot_speed,
            max_speed,
            texture_contrast,
            size,
            no_imu,
            depth_delay_ms,
        } => synth::synth_command(
            &out,
            frames,
            seed,
            noise,
            start_time,
            &synth::MotionArgs {
                motion,
                depth,
                max_rot_speed_deg: max_rot_speed,
                max_speed,
                texture_contrast,
                size,
            },
            !no_imu,
            depth_delay_ms / 1e3,
        ),
        Command::ImuFromGroundtruth {
            seq,
            out,
            seed,
            knot,
        } => imu::from_groundtruth(&seq, &out, seed, knot),
    }
}

/// `ecvo eval`.
fn eval_command(gt_path: &Path, est_path: &Path, as_json: bool) -> Result<()> {
    let gt = Trajectory::read_tum(gt_path)?;
    let est = Trajectory::read_tum(est_path)?;
    // ATE is what eval is for: its failure (no overlap in time, values too large
    // to score) is an error.
    let ate = ecvo_io::eval::ate(&gt, &est).map_err(|e| {
        anyhow::anyhow!(
            "{} against {}: {e}",
            shown_path(est_path),
            shown_path(gt_path)
        )
    })?;
    let mut eval = Evaluation::new(&gt, &est);
    eval.ate = Some(ate.clone());
    let a = &ate;
    if as_json {
        let v = json!({
            "groundtruth": gt_path.to_string_lossy(),
            "estimate": est_path.to_string_lossy(),
            "ate_rmse_m": a.rmse,
            "ate": eval.ate_json(),
            "rpe": eval.rpe_json(),
        });
        outln!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        outln!(
            "ATE RMSE (absolute trajectory error after rigid alignment): {:.4} m (mean {:.4}, median {:.4}, max {:.4}); {} poses",
            a.rmse,
            a.mean,
            a.median,
            a.max,
            a.count
        );
        match &eval.rpe_s {
            Some(r) => outln!(
                "RPE over 1 s (drift), RMSE: {:.4} m/s, {:.3} deg/s; {} pairs",
                r.trans.rmse,
                r.rot_deg.rmse,
                r.trans.count
            ),
            None => outln!("RPE over 1 s: n/a (no pair of poses 1 s apart could be scored)"),
        }
        match &eval.rpe_frame {
            Some(r) => outln!(
                "RPE per frame (consecutive poses), RMSE: {:.5} m, {:.4} deg; {} pairs",
                r.trans.rmse,
                r.rot_deg.rmse,
                r.trans.count
            ),
            None => outln!("RPE per frame: n/a (no consecutive poses could be scored)"),
        }
    }
    Ok(())
}
