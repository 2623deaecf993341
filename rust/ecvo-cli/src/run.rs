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
use crate::plot::{Plane, write_trajectory_svg};
use crate::settings::{TrackSettings, levels_string, mode_name, preset_name};
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
    let config = settings.config(*sequence.camera())?;
    let opts = EngineOptions {
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

    print!("{}", human_summary(seq, &t, &stages, out));
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

fn summary_json(
    seq: &Path,
    settings: &TrackSettings,
    t: &Tracked,
    stages: &StageStats,
    outs: &RunOutputs,
    cloud_points: usize,
) -> serde_json::Value {
    let c = &t.run.counters;
    let cam = t.sequence.camera();
    let f = &t.config.filter;
    let mut summary = json!({
        "ecvo_version": env!("CARGO_PKG_VERSION"),
        "sequence": seq.display().to_string(),
        "mode": mode_name(settings.mode),
        "preset": preset_name(settings.preset),
        "levels": t.config.reference_levels.iter().map(|l| json!({
            "max_distance_m": l.max_distance_m, "max_angle_deg": l.max_angle_deg,
        })).collect::<Vec<_>>(),
        "levels_text": levels_string(&t.config.reference_levels),
        "filters": {
            "bilateral": f.bilateral.is_some(),
            "normal_max_angle_deg": f.normal_max_angle_deg,
            "contour_angle_deg": f.contour_angle_deg,
        },
        "camera": {
            "width": cam.width, "height": cam.height, "fx": cam.fx, "fy": cam.fy,
            "cx": cam.cx, "cy": cam.cy, "depth_scale": cam.depth_scale,
        },
        "camera_file": settings.camera.as_ref().map(|p| p.display().to_string()),
        "threads": t.run.threads,
        "max_frames": settings.max_frames,
        "frames": c.frames,
        "motion_estimations": c.motion_estimations,
        "references": c.references,
        "lost_frames": c.lost_frames,
        "lost_frame_indices": t.run.outputs.iter()
            .filter(|o| o.state == TrackingState::Lost)
            .map(|o| o.index)
            .collect::<Vec<_>>(),
        "recovered_frames": c.recovered_frames,
        "failed_corrections": c.failed_corrections,
        "rejected_corrections": c.rejected_corrections,
        "stale_references": c.stale_references,
        "predicted_starts": c.predicted_starts,
        "reanchors": c.reanchors,
        "implausible_motions": c.implausible_motions,
        "spread_jumps": c.spread_jumps,
        "keyframe_fallbacks": c.keyframe_fallbacks,
        "overlap_keyframes": c.overlap_keyframes,
        "keyframe_spread_refusals": c.keyframe_spread_refusals,
        "keyframe_fusions": c.keyframe_fusions,
        "frame_step": settings.frame_step,
        "engine": settings.engine.describe(&t.config),
        "ground_truth": t.eval.ate.is_some(),
        "ate_rmse_m": t.eval.ate.as_ref().map(|a| a.rmse),
        "ate": t.eval.ate_json(),
        "rpe": t.eval.rpe_json(),
        "ms_per_frame": stages,
        "wall_ms_per_frame": t.run.stats.wall_ms_per_frame,
        "latency_ms": { "median": t.run.stats.latency.median_ms, "mean": t.run.stats.latency.mean_ms },
        "wall_time_s": t.run.wall_s,
        "pipeline": pipeline_json(&t.run.stats),
        "dropped_frames": t.run.stats.dropped,
        "cloud": {
            "points": cloud_points,
            "frames": t.run.clouds.len(),
            "pixel_stride": outs.cloud_stride,
            "every_nth_frame": (settings.mode == Mode::Naive).then_some(outs.cloud_every),
        },
    });
    // Which kernel copies ran (same poses on every path): what the times measured, and
    // the refinements between corrections. Set here because the `json!` above is at
    // the macro's recursion limit.
    summary["simd"] = json!(ecvo_core::simd_path());
    summary["refinements"] = json!(c.refinements);
    summary["refused_refinements"] = json!(c.refused_refinements);
    summary["noise_refits"] = json!(c.noise_refits);
    summary["depth_noise_in_use"] = json!(format!("{:?}", t.run.stats.depth_noise));
    summary["frames_account"] = account(t, settings).1;
    // `ground_truth` means an ATE was computed; these say whether the sequence had a
    // ground-truth file and, if no ATE, why.
    summary["ground_truth_file"] = json!(t.sequence.groundtruth().is_some());
    summary["ate_missing"] = json!(t.eval.ate_missing);
    summary["allow_outside"] = json!(settings.allow_outside);
    summary["strict"] = json!(settings.strict);
    summary
}

/// The `pipeline` object of summary.json: what the pipeline did besides tracking.
fn pipeline_json(st: &ecvo_pipeline::PipelineStats) -> serde_json::Value {
    let queue = |q: &ecvo_pipeline::QueueStats| json!({ "capacity": q.capacity, "max_depth": q.max_depth, "mean_depth": q.mean_depth });
    let stage = |s: &ecvo_pipeline::StageStats| {
        json!({
            "frames": s.frames, "median_ms": s.median_ms, "mean_ms": s.mean_ms,
            "p95_ms": s.p95_ms, "max_ms": s.max_ms,
        })
    };
    json!({
        "admission": "offline",
        "pushed": st.pushed,
        "tracked": st.tracked,
        "dropped": st.dropped,
        "failed_preparations": st.failed_preparations,
        "frame_to_frame_ahead": { "computed": st.ahead_computed, "used": st.ahead_used },
        "stages": {
            "filter": stage(&st.filter),
            "tracker": stage(&st.tracker),
            "work": stage(&st.work),
            "work_cpu": stage(&st.work_cpu),
            "latency": stage(&st.latency),
        },
        "queues": {
            "input": queue(&st.input_queue),
            "tracker": queue(&st.tracker_queue),
        },
        "frame_pool": {
            "capacity": st.frame_pool.capacity,
            "allocated": st.frame_pool.allocated,
            "max_in_use": st.frame_pool.max_in_use,
        },
    })
}

/// The short report printed after a run.
fn human_summary(seq: &Path, t: &Tracked, s: &StageStats, out: &Path) -> String {
    let c = &t.run.counters;
    let mut r = String::new();
    let _ = writeln!(
        r,
        "{}: {} frames, levels {}",
        seq.display(),
        c.frames,
        levels_string(&t.config.reference_levels)
    );
    match &t.eval.ate {
        Some(a) => {
            let _ = writeln!(
                r,
                "ATE RMSE (absolute trajectory error after rigid alignment): {:.4} m over {} poses",
                a.rmse, a.count
            );
        }
        None => {
            let why = t.eval.ate_missing.as_deref().unwrap_or("not computed");
            let _ = writeln!(r, "ATE RMSE: n/a ({why})");
        }
    }
    if let Some(p) = &t.eval.rpe_s {
        let _ = writeln!(
            r,
            "RPE RMSE over 1 s (drift): {:.4} m/s, {:.3} deg/s",
            p.trans.rmse, p.rot_deg.rmse
        );
    }
    let refs: Vec<String> = c.references.iter().map(|n| n.to_string()).collect();
    let levels: Vec<String> = (1..=refs.len()).map(|k| format!("L{k}")).collect();
    let _ = writeln!(
        r,
        "motion estimations (MOTION calls): {}, reference frames chosen per level ({}): {}, lost frames: {}",
        c.motion_estimations,
        if levels.is_empty() {
            "none".to_string()
        } else {
            levels.join("/")
        },
        if refs.is_empty() {
            "-".to_string()
        } else {
            refs.join("/")
        },
        c.lost_frames
    );
    let ahead = if t.run.stats.ahead_computed > 0 {
        format!(
            " (the filter stage's thread computed [A] ahead for {} of {} frames; that time \
             is booked to the tracker)",
            t.run.stats.ahead_computed, t.run.stats.tracked
        )
    } else {
        String::new()
    };
    let _ = writeln!(
        r,
        "stage time, ms per frame (median/mean/p95): filter {:.2}/{:.2}/{:.2}, tracker {:.2}/{:.2}/{:.2}, per frame {:.2}/{:.2}/{:.2} (CPU {:.2}/{:.2}/{:.2}){ahead}",
        s.filter.median,
        s.filter.mean,
        s.filter.p95,
        s.tracker.median,
        s.tracker.mean,
        s.tracker.p95,
        s.total.median,
        s.total.mean,
        s.total.p95,
        s.cpu.median,
        s.cpu.mean,
        s.cpu.p95
    );
    let _ = writeln!(
        r,
        "wall time: {:.2} ms per frame with {} thread(s) ({:.1} frames/s)",
        t.run.stats.wall_ms_per_frame,
        t.run.threads,
        if t.run.stats.wall_ms_per_frame > 0.0 {
            1e3 / t.run.stats.wall_ms_per_frame
        } else {
            0.0
        }
    );
    let _ = writeln!(r, "wrote {}", out.display());
    r
}

/// `states.txt`: one line per frame, in the order of `trajectory.txt`, with what the
/// tracker said about it (the TUM trajectory itself stays standard).
fn write_states(path: &Path, t: &Tracked) -> Result<()> {
    let mut text = String::from(concat!(
        "# per-frame tracking state, one line per line of trajectory.txt\n",
        "# timestamp frame_index state reference_levels motion_estimations recovered reanchored",
        " refused_corrections f2f_status f2f_sigma_i f2f_sigma_z\n",
        "# state: tracking | lost (a lost frame's pose is the last good one)\n",
        "# f2f_status: [A]'s outcome (converged, max_iterations or failed_<why>; - for the first frame)\n",
        "# f2f_sigma_i, f2f_sigma_z: robust scale of its photometric and gain-scaled depth residuals\n",
    ));
    let sigma = |x: f64| {
        if x.is_finite() {
            format!("{:.5}", x.sqrt())
        } else {
            "nan".into()
        }
    };
    for o in &t.run.outputs {
        let state = match o.state {
            TrackingState::Lost => "lost",
            _ => "tracking",
        };
        let (status, si, sz) = match &o.frame_to_frame {
            None => ("-".to_string(), "nan".to_string(), "nan".to_string()),
            Some(r) => (
                match r.status {
                    Status::Converged => "converged".to_string(),
                    Status::MaxIterations => "max_iterations".to_string(),
                    Status::Failed(f) => format!("failed_{f:?}").to_lowercase(),
                },
                r.scale.map_or("nan".into(), |s| sigma(s.ii)),
                r.scale.map_or("nan".into(), |s| sigma(s.zz)),
            ),
        };
        let _ = writeln!(
            text,
            "{:.6} {} {state} {} {} {} {} {} {status} {si} {sz}",
            o.timestamp,
            o.index,
            o.reference_levels,
            o.motion_estimations,
            u8::from(o.recovered),
            u8::from(o.reanchored),
            o.refused_corrections
        );
    }
    std::fs::write(path, text).with_context(|| format!("writing {}", path.display()))
}

/// `references.txt`: one line per frame that became a reference frame.
fn write_references(path: &Path, t: &Tracked) -> Result<()> {
    let mut text = String::from(
        "# reference frames chosen by the tracker (the first frame, which anchors every level, is not listed)\n\
         # timestamp tx ty tz qx qy qz qw level frame_index\n\
         # level: highest level the frame became the reference of (a level-2 reference is also level 1)\n",
    );
    for o in t.run.outputs.iter().filter(|o| o.reference_levels > 0) {
        let tr = &o.pose.translation.vector;
        let q = o.pose.rotation.quaternion();
        let _ = writeln!(
            text,
            "{} {} {} {} {} {} {} {} {} {}",
            o.timestamp, tr.x, tr.y, tr.z, q.i, q.j, q.k, q.w, o.reference_levels, o.index
        );
    }
    std::fs::write(path, text).with_context(|| format!("writing {}", path.display()))
}

/// `cloud.ply`: the selected frames' points in world coordinates; returns the number
/// of points.
fn write_cloud(path: &Path, t: &Tracked) -> Result<usize> {
    let total: usize = t.run.clouds.iter().map(|c| c.points.len()).sum();
    let mut points = Vec::with_capacity(total);
    let mut normals = Vec::with_capacity(total);
    let mut intensity = Vec::with_capacity(total);
    for c in &t.run.clouds {
        let Some(o) = t.run.outputs.get(c.index as usize) else {
            continue;
        };
        if o.state == TrackingState::Lost {
            continue;
        }
        let pose = o.pose.cast::<f32>();
        for ((p, n), i) in c.points.iter().zip(&c.normals).zip(&c.intensity) {
            let w = pose * ecvo_core::nalgebra::Point3::from(*p);
            let nw = pose.rotation * ecvo_core::nalgebra::Vector3::from(*n);
            points.push([w.x, w.y, w.z]);
            normals.push([nw.x, nw.y, nw.z]);
            intensity.push(*i);
        }
    }
    ecvo_io::write_ply(path, &points, Some(&normals), Some(&intensity))?;
    Ok(points.len())
}
