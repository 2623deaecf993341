//! What `ecvo run` writes besides the trajectory: `summary.json`, the summary it prints,
//! `states.txt`, `references.txt` and `cloud.ply`.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::{Context, Result};
use ecvo_core::motion::Status;
use ecvo_core::{Mode, TrackingState};
use serde_json::json;

use crate::run::{RunOutputs, StageStats, Tracked, account};
use crate::settings::{TrackSettings, levels_string, mode_name, preset_name};

pub(crate) fn summary_json(
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
    if let Some(s) = &t.imu {
        summary["imu"] = crate::imu::report(s, &c.imu).1;
    }
    summary["depth_noise_in_use"] = depth_noise_json(t.run.stats.depth_noise);
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
pub(crate) fn pipeline_json(st: &ecvo_pipeline::PipelineStats) -> serde_json::Value {
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
pub(crate) fn human_summary(seq: &Path, t: &Tracked, s: &StageStats, out: &Path) -> String {
    let c = &t.run.counters;
    let mut r = String::new();
    let _ = writeln!(
        r,
        "{}: {} frames, levels {}",
        seq.display(),
        c.frames,
        levels_string(&t.config.reference_levels)
    );
    if let Some(s) = &t.imu {
        let _ = writeln!(r, "{}", crate::imu::report(s, &c.imu).0);
    }
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
pub(crate) fn write_states(path: &Path, t: &Tracked) -> Result<()> {
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
pub(crate) fn write_references(path: &Path, t: &Tracked) -> Result<()> {
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
pub(crate) fn write_cloud(path: &Path, t: &Tracked) -> Result<usize> {
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

/// `depth_noise_in_use` in `summary.json`: the depth-noise model as a name and its
/// parameters, `{"model": "quadratic"}`, `{"model": "constant"}` or
/// `{"model": "mixed", "half_log2_alpha": 2, "alpha": 2.0}` (σ_Z(z)² ∝ α + z⁴ with
/// α = 2^(half_log2_alpha / 2)); `{"model": "fitted"}` only before a first fit.
pub(crate) fn depth_noise_json(model: ecvo_core::DepthNoiseModel) -> serde_json::Value {
    use ecvo_core::DepthNoiseModel as M;
    match model {
        M::Constant => json!({ "model": "constant" }),
        M::Quadratic => json!({ "model": "quadratic" }),
        M::Fitted => json!({ "model": "fitted" }),
        M::Mixed { half_log2_alpha } => json!({
            "model": "mixed",
            "half_log2_alpha": half_log2_alpha,
            "alpha": (f64::from(half_log2_alpha) / 2.0).exp2(),
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::depth_noise_json;
    use ecvo_core::DepthNoiseModel;
    use serde_json::json;

    #[test]
    fn depth_noise_is_a_name_and_its_parameters() {
        assert_eq!(
            depth_noise_json(DepthNoiseModel::Mixed { half_log2_alpha: 2 }),
            json!({"model": "mixed", "half_log2_alpha": 2, "alpha": 2.0})
        );
        assert_eq!(
            depth_noise_json(DepthNoiseModel::Mixed {
                half_log2_alpha: -7
            })["alpha"],
            json!(2f64.powf(-3.5))
        );
        assert_eq!(
            depth_noise_json(DepthNoiseModel::Quadratic),
            json!({"model": "quadratic"})
        );
        assert_eq!(
            depth_noise_json(DepthNoiseModel::Constant),
            json!({"model": "constant"})
        );
    }
}
