//! How a sequence is tracked: the preset, mode, frame step and engine choices of
//! `ecvo run` and `ecvo table`, and how they become a [`Config`].

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use ecvo_core::{Camera, Config, Mode, Preset, ReferenceLevel, Schedule};
use ecvo_io::files::shown_path;
use ecvo_io::{OpenOptions, Sequence};
use ecvo_settings::{Settings, SettingsError};

/// Everything that decides how a sequence is tracked.
#[derive(Clone, Debug)]
pub struct TrackSettings {
    /// Which error-correction levels run.
    pub mode: Mode,
    /// Which thresholds and filter angles to start from.
    pub preset: Preset,
    /// Reference levels overriding the preset's, as given on the command line.
    pub levels: Option<String>,
    /// Bilateral filter on depth.
    pub bilateral: bool,
    /// Normal-based removal filter.
    pub normal_filter: bool,
    /// Contour-based removal filter.
    pub contour_filter: bool,
    /// A camera.json overriding the sequence's.
    pub camera: Option<PathBuf>,
    /// Track only the first this many frames.
    pub max_frames: Option<usize>,
    /// Worker threads.
    pub threads: usize,
    /// Track every this-many-th frame.
    pub frame_step: usize,
    /// Which engine settings, beyond the preset's thresholds.
    pub engine: EngineChoice,
    /// Any skipped frame (unpaired list entry, repeated frame, timestamp not after
    /// the previous one) is an error.
    pub strict: bool,
    /// Read list entries that lead outside the sequence folder.
    pub allow_outside: bool,
    /// The memory budget in bytes (`None`: the engine's default).
    pub max_memory: Option<usize>,
    /// Which IMU stream to use.
    pub imu: crate::imu::ImuSource,
}

/// The engine's method: ecvo's defaults, or the paper's as written, with single
/// parts overridden.
#[derive(Clone, Debug, Default)]
pub struct EngineChoice {
    /// Start from [`Config::paper`] instead of [`Config::new`].
    pub paper: bool,
    /// Coarse-to-fine schedule by name.
    pub schedule: Option<String>,
    /// Template point budgets, `LEVEL=POINTS,...`.
    pub point_budget: Option<String>,
    /// Residual weighting, and the finest step's if different.
    pub weighting: Option<(ecvo_core::Weighting, Option<ecvo_core::Weighting>)>,
    /// Depth noise model.
    pub depth_noise: Option<ecvo_core::DepthNoiseModel>,
    /// What [A] starts from.
    pub prior: Option<ecvo_core::MotionPrior>,
    /// Correction gate.
    pub max_correction_distance: Option<f64>,
    /// Cap on the depth residual's weight at the finest step.
    pub max_fine_depth_weight: Option<f64>,
    /// Fuse corrections with the chain (true) or replace it (false).
    pub fuse_corrections: Option<bool>,
    /// A level's Gauss-Newton stops below this predicted relative decrease.
    pub min_predicted_decrease: Option<f64>,
    /// A level's Gauss-Newton stops after an update below this many pixels of flow.
    pub min_update_px: Option<f64>,
    /// Scale fit passes after an accepted update.
    pub scale_passes: Option<usize>,
    /// Register every Nth frame after the level-1 reference against it (0: off).
    pub refine_every: Option<u32>,
    /// Register against the keyframe (true) or the previous frame (false).
    pub keyframes: Option<bool>,
    /// Overlap below which a frame becomes the new keyframe.
    pub keyframe_min_overlap: Option<f64>,
    /// Spread growth above which a keyframe registration is refused.
    pub keyframe_max_spread_growth: Option<f64>,
    /// The depth of a frame's lookup levels under keyframe tracking.
    pub lookup_depth: Option<ecvo_core::LookupDepth>,
    /// Fuse every Nth frame after the keyframe with the chain (0: off).
    pub keyframe_fuse_every: Option<u32>,
    /// Fuse the gyro's rotation into each registration (`Config::imu_fusion`).
    pub imu_fusion: Option<bool>,
    /// The gyro's rotation as a prior term in `MOTION` (`Config::imu_prior_term`).
    pub imu_prior_term: Option<bool>,
    /// Turn a frame's depth to its intensity's time (`Config::imu_depth_time`).
    pub imu_depth_time: Option<bool>,
}

impl EngineChoice {
    /// A short description for tables and summaries.
    pub fn describe(&self, config: &Config) -> String {
        let m = &config.motion;
        // The default first: on a large image the two pyramid schedules can give the
        // same steps (`Schedule::levels_for`).
        let schedule = [
            Schedule::PyramidStride2,
            Schedule::PaperSampling,
            Schedule::Pyramid,
        ]
        .into_iter()
        .find(|s| s.levels_for(&config.camera) == m.levels)
        .map_or_else(
            || {
                m.levels
                    .iter()
                    .map(|l| match l.max_points {
                        None => format!("{}/{}/{}", l.pyramid_level, l.stride, l.max_iterations),
                        Some(n) => {
                            format!("{}/{}/{}/{n}", l.pyramid_level, l.stride, l.max_iterations)
                        }
                    })
                    .collect::<Vec<_>>()
                    .join(",")
            },
            |s| s.name().to_string(),
        );
        format!(
            "schedule {schedule}, {} weighting, {:?} depth noise, {:?} prior, correction gate {}, corrections {}{}, stop below a predicted decrease of {} or an update of {} px, {} scale pass(es) per update",
            match m.fine_weighting {
                Some(f) if f != m.weighting =>
                    format!("{:?} then {:?} at the finest step", m.weighting, f),
                _ if m.weighting == ecvo_core::Weighting::Bivariate
                    && m.max_fine_depth_weight.is_finite() =>
                    format!(
                        "bivariate (depth at most {}x at the finest step)",
                        m.max_fine_depth_weight
                    ),
                _ => format!("{:?}", m.weighting),
            },
            m.depth_noise,
            m.prior,
            config.max_correction_distance,
            if config.fuse_corrections { "fused" } else { "replaced" },
            match config.refine_every {
                _ if config.keyframes => format!(
                    ", keyframe tracking ({:?} lookup depth, new keyframe below {} overlap or above {}x spread, fused every {} frames)",
                    config.lookup_depth,
                    config.keyframe_min_overlap,
                    config.keyframe_max_spread_growth,
                    config.keyframe_fuse_every
                ),
                0 => String::new(),
                n if config.fuse_corrections => {
                    format!(", refined against the level-1 reference every {n} frames")
                }
                _ => ", refinement off (needs fused corrections)".to_string(),
            },
            m.min_predicted_decrease,
            m.min_update_px,
            m.scale_passes_per_update
        )
        .to_lowercase()
    }
}

/// Name of a mode as the command line spells it.
pub fn mode_name(mode: Mode) -> &'static str {
    match mode {
        Mode::Naive => "naive",
        Mode::L1 => "l1",
        Mode::L2 => "l2",
    }
}

/// Name of a preset as the command line spells it.
pub fn preset_name(preset: Preset) -> &'static str {
    match preset {
        Preset::Pc => "pc",
        Preset::Phone => "phone",
    }
}

/// Levels written as `--levels` takes them (`30mm:7deg,120mm:12deg`).
pub fn levels_string(levels: &[ReferenceLevel]) -> String {
    if levels.is_empty() {
        return "none".into();
    }
    levels
        .iter()
        .map(|l| format!("{}mm:{}deg", l.max_distance_m * 1000.0, l.max_angle_deg))
        .collect::<Vec<_>>()
        .join(",")
}

impl TrackSettings {
    /// Opens the sequence, with the `--camera` file if one was given; with
    /// `--strict`, a list entry left unpaired is an error.
    pub fn open_sequence(&self, seq: &Path) -> Result<Sequence> {
        let camera = match &self.camera {
            Some(path) => Some(
                ecvo_io::load_camera_json(path)
                    .with_context(|| format!("--camera {}", shown_path(path)))?,
            ),
            None => None,
        };
        let options = OpenOptions::new().allow_outside(self.allow_outside);
        let sequence = Sequence::open_with(seq, camera, &options)?;
        let l = sequence.listing();
        if self.strict && (l.unpaired_rgb > 0 || l.unpaired_depth > 0) {
            bail!(
                "{}: {} colour and {} depth entries have no partner within {} s (--strict)",
                shown_path(seq),
                l.unpaired_rgb,
                l.unpaired_depth,
                ecvo_io::sequence::MAX_RGB_DEPTH_DT
            );
        }
        Ok(sequence.every_nth(self.frame_step))
    }

    /// The engine settings these make ([`ecvo_settings::Settings`], the one place
    /// the CLI, the Python package and the JNI turn settings into a [`Config`]).
    pub fn engine_settings(&self) -> Settings {
        let e = &self.engine;
        Settings {
            preset: self.preset,
            mode: self.mode,
            levels: self.levels.clone(),
            bilateral: self.bilateral,
            normal_filter: self.normal_filter,
            contour_filter: self.contour_filter,
            paper: e.paper,
            schedule: e.schedule.clone(),
            point_budget: e.point_budget.clone(),
            weighting: e.weighting,
            depth_noise: e.depth_noise,
            prior: e.prior,
            max_correction_distance: e.max_correction_distance,
            max_fine_depth_weight: e.max_fine_depth_weight,
            min_predicted_decrease: e.min_predicted_decrease,
            min_update_px: e.min_update_px,
            scale_passes: e.scale_passes,
            fuse_corrections: e.fuse_corrections,
            refine_every: e.refine_every,
            keyframes: e.keyframes,
            keyframe_min_overlap: e.keyframe_min_overlap,
            keyframe_max_spread_growth: e.keyframe_max_spread_growth,
            lookup_depth: e.lookup_depth,
            keyframe_fuse_every: e.keyframe_fuse_every,
            imu_fusion: e.imu_fusion,
            imu_prior_term: e.imu_prior_term,
            imu_depth_time: e.imu_depth_time,
            memory_budget: self.max_memory,
        }
    }

    /// The tracker configuration for `camera`.
    ///
    /// The reference levels are `--levels` if given, else the preset's; the mode keeps
    /// none of them (naive), the first (l1) or all of them (l2, at least two).
    pub fn config(&self, camera: Camera) -> Result<Config> {
        self.engine_settings().config(camera).map_err(|e| match e {
            SettingsError::Parse { key, text, source } => {
                // As the flags were quoted before: only --levels in backticks.
                let what = match key {
                    "levels" => format!("--levels `{text}`"),
                    _ => format!("--{} {text}", key.replace('_', "-")),
                };
                anyhow::Error::new(source).context(what)
            }
            SettingsError::TooFewLevels {
                mode,
                needed,
                levels,
                available,
            } => anyhow::anyhow!(
                "--mode {mode} needs at least {needed} reference level(s) but --levels `{levels}` gives {available}"
            ),
            SettingsError::Invalid(source) => {
                anyhow::Error::new(source).context("invalid tracker configuration")
            }
        })
    }
}
