//! `ecvo table`: the paper's Table 1 (naive, L1, L2) for a set of sequences, at one
//! or more frame steps (every Nth frame: the robustness suite for fast motion). With
//! keyframe tracking (the default) the level-1 references are the keyframes, and the
//! motion estimations count each frame's registration, the fusion of each new
//! keyframe with the chain and the fall-backs to the previous frame, which get their
//! own column.

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use ecvo_core::Mode;
use serde_json::json;

use crate::engine::CloudFrames;
use crate::run::{StageStats, track};
use crate::settings::TrackSettings;

/// Tracks every sequence at every frame step in the three modes and prints one
/// Markdown table per sequence; with `json`, also one JSON line per row.
pub fn table_command(
    seqs: &[PathBuf],
    base: &TrackSettings,
    steps: &[usize],
    json_path: Option<&Path>,
) -> Result<()> {
    let mut json_out = match json_path {
        Some(p) => {
            Some(std::fs::File::create(p).with_context(|| format!("creating {}", p.display()))?)
        }
        None => None,
    };
    for (k, seq) in seqs.iter().enumerate() {
        let mut rows = Vec::new();
        let mut engine = String::new();
        for &step in steps {
            for (mode, name) in [(Mode::Naive, "naive"), (Mode::L1, "L1"), (Mode::L2, "L2")] {
                let settings = TrackSettings {
                    mode,
                    frame_step: step,
                    ..base.clone()
                };
                let t = track(seq, &settings, CloudFrames::None, 1)?;
                engine = settings.engine.describe(&t.config);
                let c = &t.run.counters;
                let refs = match c.references.as_slice() {
                    [] => "-".to_string(),
                    [a] => format!("{a}/-"),
                    r => r
                        .iter()
                        .map(|n| n.to_string())
                        .collect::<Vec<_>>()
                        .join("/"),
                };
                let ate = t.eval.ate.as_ref().map(|a| a.rmse);
                let s = StageStats::of(&t.run);
                let lost = if c.lost_frames > 0 {
                    format!(" ({} lost)", c.lost_frames)
                } else {
                    String::new()
                };
                // Keyframe tracking needs a reference level: the naive rows (and
                // `--tracking chain`) register against the previous frame.
                let keyframes = t.config.keyframes && !t.config.reference_levels.is_empty();
                let kf = if keyframes {
                    format!("{}/{}", c.keyframe_fusions, c.keyframe_fallbacks)
                } else {
                    "-".to_string()
                };
                rows.push(format!(
                    "| {step} | {} | {name} | {} | {}{lost} | {refs} | {kf} | {:.2} |",
                    c.frames,
                    ate.map_or("n/a".to_string(), |a| format!("{a:.4}")),
                    c.motion_estimations,
                    s.total.mean
                ));
                if let Some(f) = &mut json_out {
                    let row = json!({
                        "sequence": seq.display().to_string(),
                        "frame_step": step,
                        "frames": c.frames,
                        "mode": name,
                        "ate_rmse_m": ate,
                        "motion_estimations": c.motion_estimations,
                        "references": c.references,
                        "lost_frames": c.lost_frames,
                        "recovered_frames": c.recovered_frames,
                        "failed_corrections": c.failed_corrections,
                        "rejected_corrections": c.rejected_corrections,
                        "keyframes": keyframes,
                        "keyframe_fusions": c.keyframe_fusions,
                        "keyframe_fallbacks": c.keyframe_fallbacks,
                        "overlap_keyframes": c.overlap_keyframes,
                        "keyframe_spread_refusals": c.keyframe_spread_refusals,
                        "ms_per_frame": s.total.mean,
                        "filter_ms": s.filter.mean,
                        "tracker_ms": s.tracker.mean,
                        "engine": engine,
                    });
                    writeln!(f, "{row}").context("writing the JSON rows")?;
                }
            }
        }
        let mut out = String::new();
        if k > 0 {
            out.push('\n');
        }
        let _ = writeln!(
            out,
            "### {} (preset {}; {engine})\n",
            seq.display(),
            crate::settings::preset_name(base.preset)
        );
        let _ = writeln!(
            out,
            "| frame step | frames | method | ATE RMSE (m) | motion estimations | references L1/L2 | keyframe fusions/fallbacks | ms per frame |"
        );
        let _ = writeln!(out, "|---|---|---|---|---|---|---|---|");
        for r in rows {
            let _ = writeln!(out, "{r}");
        }
        out!("{out}");
    }
    Ok(())
}
