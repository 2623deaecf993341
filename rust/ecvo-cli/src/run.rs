//! `ecvo run`: track a sequence and write the trajectory, the reference frames, a
//! summary, a point cloud and a plot.

use std::fmt::Write as _;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use ecvo_core::motion::Status;
use ecvo_core::{Config, Mode, TrackingState};
use ecvo_io::eval::{AteResult, RpeResult};
use ecvo_io::{Sequence, Trajectory};
use serde::Serialize;
use serde_json::json;

use crate::engine::{CloudFrames, EngineOptions, TrackRun, track_sequence};
use crate::outputs::{human_summary, summary_json, write_cloud, write_references, write_states};
use crate::plot::{Plane, write_trajectory_svg};
use crate::settings::TrackSettings;
use crate::stats::MedianMean;

/// Ground-truth comparison of a run.
#[derive(Clone, Debug, Default)]
pub struct Evaluation {
    /// Absolute trajectory error.
    pub ate: Option<AteResult>,
    /// Relative pose error over 1 s.
    pub rpe_s: Option<RpeResult>,
    /// Relative pose error between consecutive frames.
    pub rpe_frame: Option<RpeResult>,
    /// Why there is no ATE (no ground truth, or what the evaluation refused).
    pub ate_missing: Option<String>,
}

impl Evaluation {
    /// Compares `est` with `gt`; an error (too few associated poses) leaves a field
    /// empty and is logged.
    pub fn new(gt: &Trajectory, est: &Trajectory) -> Evaluation {
        // A missing ATE is a warning (the run has ground truth); a missing RPE only a
        // note (short runs have no pair of poses 1 s apart).
        fn keep<T>(what: &str, r: ecvo_io::Result<T>, level: log::Level) -> Option<T> {
            match r {
                Ok(v) => Some(v),
                Err(e) => {
                    log::log!(level, "{what}: {e}");
                    None
                }
            }
        }
        let ate = ecvo_io::eval::ate(gt, est);
        let ate_missing = ate.as_ref().err().map(|e| e.to_string());
        Evaluation {
            ate: keep("ATE against the ground truth", ate, log::Level::Warn),
            rpe_s: keep(
                "RPE over 1 s",
                ecvo_io::eval::rpe(gt, est, 1.0),
                log::Level::Info,
            ),
            rpe_frame: keep(
                "RPE per frame",
                ecvo_io::eval::rpe_per_frame(gt, est),
                log::Level::Info,
            ),
            ate_missing,
        }
    }

    /// No ground truth to compare with.
    pub fn without_ground_truth() -> Evaluation {
        Evaluation {
            ate_missing: Some("the sequence has no ground truth".into()),
            ..Evaluation::default()
        }
    }

    /// The `ate` object of the JSON outputs.
    pub fn ate_json(&self) -> serde_json::Value {
        match &self.ate {
            Some(a) => json!({
                "rmse_m": a.rmse, "mean_m": a.mean, "median_m": a.median, "std_m": a.std,
                "min_m": a.min, "max_m": a.max, "pairs": a.count,
            }),
            None => serde_json::Value::Null,
        }
    }

    /// The `rpe` object of the JSON outputs.
    pub fn rpe_json(&self) -> serde_json::Value {
        if self.rpe_s.is_none() && self.rpe_frame.is_none() {
            return serde_json::Value::Null;
        }
        let per_second = self.rpe_s.as_ref().map(|r| {
            json!({
                "trans_m_per_s": r.trans.rmse, "rot_deg_per_s": r.rot_deg.rmse,
                "trans_mean_m_per_s": r.trans.mean, "rot_mean_deg_per_s": r.rot_deg.mean,
                "pairs": r.trans.count,
            })
        });
        let per_frame = self.rpe_frame.as_ref().map(|r| {
            json!({
                "trans_m": r.trans.rmse, "rot_deg": r.rot_deg.rmse,
                "trans_mean_m": r.trans.mean, "rot_mean_deg": r.rot_deg.mean,
                "pairs": r.trans.count,
            })
        });
        json!({
            "trans_m_per_s": self.rpe_s.as_ref().map(|r| r.trans.rmse),
            "rot_deg_per_s": self.rpe_s.as_ref().map(|r| r.rot_deg.rmse),
            "per_second": per_second,
            "per_frame": per_frame,
        })
    }
}

/// Per-stage milliseconds per frame.
///
/// `filter` and `tracker` come from the pipeline's per-stage histograms: the mean is
/// exact, the median is the centre of its histogram bin (within about 2 %).
/// `total` is the per-frame sum of the two (each frame's preparation plus its
/// tracking, from the pipeline's `work` histogram): the work one frame needs, which
/// the stages overlap when the pipeline has two threads or more. Each has its median,
/// mean and 95th percentile.
/// `geometry` is the CLI's point gathering per cloud frame (the frame prepared again
/// and its points copied, on the input thread; 0 when no frame was gathered).
#[derive(Clone, Copy, Debug, Serialize)]
pub struct StageStats {
    /// The filter stage (frame preparation).
    pub filter: MedianMean,
    /// The tracker stage (motion estimation and correction).
    pub tracker: MedianMean,
    /// Filter plus tracker.
    pub total: MedianMean,
    /// The same per-frame work as CPU time of the compute thread (the pipeline's
    /// `work_cpu`): with `--threads 1` a frame's whole cost on one core, which time
    /// spent descheduled on a loaded machine does not inflate.
    pub cpu: MedianMean,
    /// Gathering the points of a cloud frame, per cloud frame.
    pub geometry: MedianMean,
}

impl StageStats {
    /// The statistics of a run.
    pub fn of(run: &TrackRun) -> Self {
        let mm = |s: &ecvo_pipeline::StageStats| MedianMean {
            median: s.median_ms,
            mean: s.mean_ms,
            p95: s.p95_ms,
        };
        StageStats {
            filter: mm(&run.stats.filter),
            tracker: mm(&run.stats.tracker),
            total: mm(&run.stats.work),
            cpu: mm(&run.stats.work_cpu),
            geometry: MedianMean::of(run.cloud_ms.iter().copied()),
        }
    }
}

/// A tracked and evaluated sequence.
pub struct Tracked {
    /// The opened sequence.
    pub sequence: Sequence,
    /// The configuration used.
    pub config: Config,
    /// The engine's results.
    pub run: TrackRun,
    /// The IMU stream used, if any.
    pub imu: Option<crate::imu::ImuStream>,
    /// The estimated trajectory (every frame).
    pub trajectory: Trajectory,
    /// Comparison with the ground truth, if the sequence has one.
    pub eval: Evaluation,
}

/// Opens, tracks and evaluates `seq`.
pub fn track(
    seq: &Path,
    settings: &TrackSettings,
    cloud: CloudFrames,
    cloud_stride: usize,
) -> Result<Tracked> {
    let sequence = settings.open_sequence(seq)?;
    let mut config = settings.config(*sequence.camera())?;
    let imu = crate::imu::load_stream(seq, &settings.imu)?;
    if let Some(s) = &imu {
        config.imu = s.calibration;
    }
    let opts = EngineOptions {
        imu: imu.clone(),
        max_frames: settings.max_frames,
        threads: settings.threads,
        progress: std::io::stderr().is_terminal(),
        cloud,
        cloud_stride,
        strict: settings.strict,
    };
    let run = track_sequence(&sequence, &config, &opts)?;
    if run.outputs.is_empty() {
        bail!("{}: no frame was tracked", seq.display());
    }
    let mut trajectory = Trajectory::with_capacity(run.outputs.len());
    for o in &run.outputs {
        trajectory.push(o.timestamp, o.pose);
    }
    let eval = match sequence.groundtruth() {
        Some(gt) => Evaluation::new(gt, &trajectory),
        None => Evaluation::without_ground_truth(),
    };
    Ok(Tracked {
        sequence,
        config,
        run,
        imu,
        trajectory,
        eval,
    })
}

/// Options of `ecvo run` beyond the tracking settings.
#[derive(Clone, Debug)]
pub struct RunOutputs {
    /// Output folder.
    pub out: PathBuf,
    /// Pixel stride of the point cloud.
    pub cloud_stride: usize,
    /// With naive tracking, every how many frames the cloud takes a frame.
    pub cloud_every: usize,
    /// Plane of the top view.
    pub plane: Plane,
}

/// `ecvo run`.
pub fn run_command(seq: &Path, settings: &TrackSettings, outs: &RunOutputs) -> Result<()> {
    if outs.cloud_stride == 0 || outs.cloud_every == 0 {
        bail!("--cloud-stride and --cloud-every must be at least 1");
    }
    let cloud = if settings.mode == Mode::Naive {
        CloudFrames::EveryNth(outs.cloud_every)
    } else {
        CloudFrames::References
    };
    // Open and check everything before the (long) run, so that a bad output folder
    // fails at once.
    std::fs::create_dir_all(&outs.out)
        .with_context(|| format!("cannot create the output folder {}", outs.out.display()))?;
    let t = track(seq, settings, cloud, outs.cloud_stride)?;
    let out = &outs.out;

    t.trajectory.write_tum(out.join("trajectory.txt"))?;
    write_references(&out.join("references.txt"), &t)?;
    write_states(&out.join("states.txt"), &t)?;
    let cloud_points = write_cloud(&out.join("cloud.ply"), &t)?;
    let svg = out.join("trajectory.svg");
    write_trajectory_svg(
        &svg,
        &t.trajectory,
        t.sequence.groundtruth(),
        t.eval.ate.as_ref(),
        outs.plane,
        &seq.display().to_string(),
    )
    .with_context(|| format!("writing {}", svg.display()))?;

    let (line, _) = account(&t, settings);
    crate::report_account(&line, account_has_loss(&t));
    let stages = StageStats::of(&t.run);
    let summary = summary_json(seq, settings, &t, &stages, outs, cloud_points);
    let summary_path = out.join("summary.json");
    let text = serde_json::to_string_pretty(&summary)? + "\n";
    std::fs::write(&summary_path, text)
        .with_context(|| format!("writing {}", summary_path.display()))?;

    out!("{}", human_summary(seq, &t, &stages, out));
    Ok(())
}

/// Why a frame was lost, as `states.txt` spells [A]'s outcome.
fn lost_reason(o: &ecvo_core::FrameOutput) -> String {
    match &o.frame_to_frame {
        None => "no frame-to-frame estimate".into(),
        Some(r) => match r.status {
            Status::Failed(f) => format!("failed_{f:?}").to_lowercase(),
            _ => "registration not believed (implausible motion or spread jump)".into(),
        },
    }
}

/// What became of the frames the lists held: one line for stderr and the
/// `frames_account` object of summary.json.
pub fn account(t: &Tracked, settings: &TrackSettings) -> (String, serde_json::Value) {
    let l = t.sequence.listing();
    let skips = &t.run.skips;
    let read = t.run.outputs.len() + skips.repeated.len() + skips.timestamp_not_increasing.len();
    let not_read = t.sequence.len().saturating_sub(read);
    let mut lost: std::collections::BTreeMap<String, usize> = Default::default();
    for o in t
        .run
        .outputs
        .iter()
        .filter(|o| o.state == TrackingState::Lost)
    {
        *lost.entry(lost_reason(o)).or_default() += 1;
    }
    let lost_total: usize = lost.values().sum();
    let listed = match t.sequence.layout() {
        ecvo_io::Layout::Tum => format!(
            "listed {} colour + {} depth, paired {}",
            l.rgb_listed, l.depth_listed, l.paired
        ),
        ecvo_io::Layout::IclNuim => format!("listed {} in associations.txt", l.paired),
    };
    let mut line = format!("frames: {listed}");
    if l.unpaired_rgb + l.unpaired_depth > 0 {
        let _ = write!(
            line,
            " (skipped unpaired: {} colour, {} depth)",
            l.unpaired_rgb, l.unpaired_depth
        );
    }
    if l.stepped_over > 0 {
        let _ = write!(
            line,
            ", {} left out by --frame-step {}",
            l.stepped_over, settings.frame_step
        );
    }
    if not_read > 0 {
        let _ = write!(line, ", {not_read} not read (--max-frames)");
    }
    let skipped = skips.repeated.len() + skips.timestamp_not_increasing.len();
    let _ = write!(line, ", read {read}, skipped {skipped}");
    if skipped > 0 {
        let _ = write!(
            line,
            " ({} identical to the previous frame, {} with a timestamp not after the previous one)",
            skips.repeated.len(),
            skips.timestamp_not_increasing.len()
        );
    }
    let _ = write!(line, ", tracked {}, lost {lost_total}", t.run.outputs.len());
    if lost_total > 0 {
        let reasons: Vec<String> = lost.iter().map(|(r, n)| format!("{n} {r}")).collect();
        let _ = write!(line, " ({})", reasons.join(", "));
    }
    if !skips.no_valid_depth.is_empty() {
        let _ = write!(
            line,
            ", {} without a valid depth pixel",
            skips.no_valid_depth.len()
        );
    }
    let json = json!({
        "rgb_listed": l.rgb_listed,
        "depth_listed": l.depth_listed,
        "paired": l.paired,
        "unpaired_rgb_skipped": l.unpaired_rgb,
        "unpaired_depth_skipped": l.unpaired_depth,
        "left_out_by_frame_step": l.stepped_over,
        "not_read_max_frames": not_read,
        "read": read,
        "skipped_repeated": skips.repeated,
        "skipped_timestamp_not_increasing": skips.timestamp_not_increasing,
        "tracked": t.run.outputs.len(),
        "lost": lost_total,
        "lost_reasons": lost,
        "no_valid_depth": skips.no_valid_depth,
    });
    (line, json)
}

/// Whether anything was skipped or lost (then the account is printed even with -q).
pub fn account_has_loss(t: &Tracked) -> bool {
    let l = t.sequence.listing();
    let s = &t.run.skips;
    l.unpaired_rgb + l.unpaired_depth > 0
        || !s.repeated.is_empty()
        || !s.timestamp_not_increasing.is_empty()
        || !s.no_valid_depth.is_empty()
        || t.run.counters.lost_frames > 0
}
