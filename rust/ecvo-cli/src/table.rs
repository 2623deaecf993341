//! `ecvo table`: the paper's Table 1 (naive, L1, L2) for a set of sequences.

use std::fmt::Write as _;
use std::path::PathBuf;

use anyhow::Result;
use ecvo_core::Mode;

use crate::engine::CloudFrames;
use crate::run::{StageStats, TrackSettings, track};

/// Tracks every sequence in the three modes and prints one Markdown table per
/// sequence.
pub fn table_command(seqs: &[PathBuf], base: &TrackSettings) -> Result<()> {
    for (k, seq) in seqs.iter().enumerate() {
        let mut rows = Vec::new();
        let mut frames = 0;
        for (mode, name) in [(Mode::Naive, "naive"), (Mode::L1, "L1"), (Mode::L2, "L2")] {
            let settings = TrackSettings {
                mode,
                ..base.clone()
            };
            let t = track(seq, &settings, CloudFrames::None, 1)?;
            let c = &t.run.counters;
            frames = c.frames;
            let refs = match c.references.as_slice() {
                [] => "-".to_string(),
                [a] => format!("{a}/-"),
                r => r
                    .iter()
                    .map(|n| n.to_string())
                    .collect::<Vec<_>>()
                    .join("/"),
            };
            let ate = t
                .eval
                .ate
                .as_ref()
                .map_or("n/a".to_string(), |a| format!("{:.4}", a.rmse));
            let s = StageStats::of(&t.run);
            let lost = if c.lost_frames > 0 {
                format!(" ({} lost)", c.lost_frames)
            } else {
                String::new()
            };
            rows.push(format!(
                "| {name} | {ate} | {}{lost} | {refs} | {:.2} |",
                c.motion_estimations, s.total.mean
            ));
        }
        let mut out = String::new();
        if k > 0 {
            out.push('\n');
        }
        let _ = writeln!(
            out,
            "### {} ({frames} frames, preset {})\n",
            seq.display(),
            crate::run::preset_name(base.preset)
        );
        let _ = writeln!(
            out,
            "| method | ATE RMSE (m) | motion estimations | references L1/L2 | ms per frame |"
        );
        let _ = writeln!(out, "|---|---|---|---|---|");
        for r in rows {
            let _ = writeln!(out, "{r}");
        }
        print!("{out}");
    }
    Ok(())
}
