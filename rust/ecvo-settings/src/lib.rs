//! # ecvo-settings
//!
//! The settings a user gives ecvo's front ends (the flags of `ecvo run`, the keywords
//! of the Python package's `Tracker` and `run_sequence`, the JNI's `init`) and the one
//! function that turns them into an engine [`Config`]: start from the preset
//! ([`Config::new`], or [`Config::paper`]), apply each override in a fixed order,
//! keep the reference levels the mode asks for, drop the filters turned off, set the
//! memory budget, validate. Equal settings give equal configurations, hence equal
//! poses, whichever front end they came through.
//!
//! Each front end parses its own syntax (clap flags, Python keywords, JNI codes) into
//! [`Settings`]; errors name the setting ([`SettingsError::key`]) so that a front end
//! can say it its own way (`--schedule`, `schedule=`).

use ecvo_core::config::parse_levels;
use ecvo_core::{
    Camera, Config, DepthNoiseModel, Mode, MotionPrior, Preset, Weighting, parse_point_budget,
    parse_schedule,
};

/// Everything a user can choose about the engine, beyond the camera.
#[derive(Clone, Debug, PartialEq)]
pub struct Settings {
    /// Which thresholds and filter angles to start from.
    pub preset: Preset,
    /// Which error-correction levels run.
    pub mode: Mode,
    /// Reference levels overriding the preset's (`"30mm:7deg,120mm:12deg"`).
    pub levels: Option<String>,
    /// Bilateral filter on depth.
    pub bilateral: bool,
    /// Normal-based removal filter.
    pub normal_filter: bool,
    /// Contour-based removal filter.
    pub contour_filter: bool,
    /// Start from [`Config::paper`] instead of [`Config::new`].
    pub paper: bool,
    /// Coarse-to-fine schedule by name ([`parse_schedule`]).
    pub schedule: Option<String>,
    /// Template point budgets, `LEVEL=POINTS,...` ([`parse_point_budget`]).
    pub point_budget: Option<String>,
    /// Residual weighting, and the finest step's if different.
    pub weighting: Option<(Weighting, Option<Weighting>)>,
    /// Depth noise model.
    pub depth_noise: Option<DepthNoiseModel>,
    /// What \[A\] starts from.
    pub prior: Option<MotionPrior>,
    /// Correction gate ([`Config::max_correction_distance`]).
    pub max_correction_distance: Option<f64>,
    /// Cap on the depth residual's weight at the finest step.
    pub max_fine_depth_weight: Option<f64>,
    /// A step's Gauss-Newton stops below this predicted relative decrease.
    pub min_predicted_decrease: Option<f64>,
    /// A step's Gauss-Newton stops after an update below this many pixels of flow.
    pub min_update_px: Option<f64>,
    /// Scale fit passes after an accepted update.
    pub scale_passes: Option<usize>,
    /// Fuse corrections with the chain (true) or replace it (false).
    pub fuse_corrections: Option<bool>,
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
    /// With a gyroscope, fuse its rotation into each believed registration
    /// ([`Config::imu_fusion`]; `None`: the engine's default, off).
    pub imu_fusion: Option<bool>,
    /// With a gyroscope, its rotation is also a prior term in `MOTION`'s normal
    /// equations ([`Config::imu_prior_term`]; `None`: the engine's default).
    pub imu_prior_term: Option<bool>,
    /// With a gyroscope, a frame's depth captured at another time than its intensity
    /// is turned to the intensity's time ([`Config::imu_depth_time`]; `None`: the
    /// engine's default).
    pub imu_depth_time: Option<bool>,
    /// The memory budget in bytes (`None`: the engine's default).
    pub memory_budget: Option<usize>,
}

impl Default for Settings {
    /// The `pc` preset in mode `l2` with every filter on and nothing overridden: what
    /// `ecvo run` and `ecvo.Tracker` do without options.
    fn default() -> Self {
        Settings::new(Preset::Pc, Mode::L2)
    }
}

/// A setting that cannot be applied.
#[derive(Debug, thiserror::Error)]
pub enum SettingsError {
    /// A text setting did not parse (`key` is `"levels"`, `"schedule"` or
    /// `"point_budget"`).
    #[error("{key} `{text}`: {source}")]
    Parse {
        /// The setting.
        key: &'static str,
        /// What was given.
        text: String,
        /// Why it does not parse.
        source: ecvo_core::Error,
    },
    /// The mode keeps more reference levels than `levels` gives.
    #[error(
        "mode {mode} needs at least {needed} reference level(s) but levels `{levels}` gives {available}"
    )]
    TooFewLevels {
        /// The mode's name (`naive`, `l1`, `l2`).
        mode: &'static str,
        /// Levels it needs.
        needed: usize,
        /// The levels given.
        levels: String,
        /// Levels they give.
        available: usize,
    },
    /// The resulting configuration is invalid ([`Config::validate`]).
    #[error("invalid tracker configuration: {0}")]
    Invalid(ecvo_core::Error),
}

impl SettingsError {
    /// The setting at fault (`"mode"` for [`SettingsError::TooFewLevels`], `None`
    /// for a configuration invalid as a whole).
    pub fn key(&self) -> Option<&'static str> {
        match self {
            SettingsError::Parse { key, .. } => Some(key),
            SettingsError::TooFewLevels { .. } => Some("mode"),
            SettingsError::Invalid(_) => None,
        }
    }
}

/// The name of a mode as the front ends spell it.
pub fn mode_name(mode: Mode) -> &'static str {
    match mode {
        Mode::Naive => "naive",
        Mode::L1 => "l1",
        Mode::L2 => "l2",
    }
}

/// Parses a preset name (`"pc"`, `"phone"`).
pub fn parse_preset(name: &str) -> Option<Preset> {
    match name {
        "pc" => Some(Preset::Pc),
        "phone" => Some(Preset::Phone),
        _ => None,
    }
}

/// Parses a mode name (`"naive"`, `"l1"`, `"l2"`).
pub fn parse_mode(name: &str) -> Option<Mode> {
    match name {
        "naive" => Some(Mode::Naive),
        "l1" => Some(Mode::L1),
        "l2" => Some(Mode::L2),
        _ => None,
    }
}

impl Settings {
    /// `preset` and `mode` with every filter on and nothing overridden.
    pub fn new(preset: Preset, mode: Mode) -> Self {
        Settings {
            preset,
            mode,
            levels: None,
            bilateral: true,
            normal_filter: true,
            contour_filter: true,
            paper: false,
            schedule: None,
            point_budget: None,
            weighting: None,
            depth_noise: None,
            prior: None,
            max_correction_distance: None,
            max_fine_depth_weight: None,
            min_predicted_decrease: None,
            min_update_px: None,
            scale_passes: None,
            fuse_corrections: None,
            refine_every: None,
            keyframes: None,
            keyframe_min_overlap: None,
            keyframe_max_spread_growth: None,
            lookup_depth: None,
            keyframe_fuse_every: None,
            imu_fusion: None,
            imu_prior_term: None,
            imu_depth_time: None,
            memory_budget: None,
        }
    }

    /// The tracker configuration for `camera`.
    ///
    /// The reference levels are `levels` if given, else the preset's; the mode keeps
    /// none of them (naive), the first (l1) or all of them (l2, at least two).
    pub fn config(&self, camera: Camera) -> Result<Config, SettingsError> {
        let parse = |key: &'static str, text: &str, source| SettingsError::Parse {
            key,
            text: text.to_string(),
            source,
        };
        let mut config = if self.paper {
            Config::paper(camera, self.preset, Mode::L2)
        } else {
            Config::new(camera, self.preset, Mode::L2)
        };
        if let Some(name) = &self.schedule {
            config.motion.levels =
                parse_schedule(name, &camera).map_err(|e| parse("schedule", name, e))?;
        }
        if let Some(text) = &self.point_budget {
            let budgets = parse_point_budget(text).map_err(|e| parse("point_budget", text, e))?;
            for (level, points) in budgets {
                config.motion.set_point_budget(level, points);
            }
        }
        if let Some((w, fine)) = self.weighting {
            config.motion.weighting = w;
            config.motion.fine_weighting = fine;
        }
        if let Some(d) = self.depth_noise {
            config.motion.depth_noise = d;
        }
        if let Some(p) = self.prior {
            config.motion.prior = p;
        }
        if let Some(d) = self.max_correction_distance {
            config.max_correction_distance = d;
        }
        if let Some(d) = self.min_predicted_decrease {
            config.motion.min_predicted_decrease = d;
        }
        if let Some(d) = self.min_update_px {
            config.motion.min_update_px = d;
        }
        if let Some(n) = self.scale_passes {
            config.motion.scale_passes_per_update = n;
        }
        if let Some(d) = self.max_fine_depth_weight {
            config.motion.max_fine_depth_weight = d;
        }
        if let Some(f) = self.fuse_corrections {
            config.fuse_corrections = f;
        }
        if let Some(n) = self.refine_every {
            config.refine_every = n;
        }
        if let Some(k) = self.keyframes {
            config.keyframes = k;
        }
        if let Some(f) = self.keyframe_min_overlap {
            config.keyframe_min_overlap = f;
        }
        if let Some(d) = self.lookup_depth {
            config.lookup_depth = d;
        }
        if let Some(n) = self.keyframe_fuse_every {
            config.keyframe_fuse_every = n;
        }
        if let Some(f) = self.keyframe_max_spread_growth {
            config.keyframe_max_spread_growth = f;
        }
        if let Some(f) = self.imu_fusion {
            config.imu_fusion = f;
        }
        if let Some(f) = self.imu_prior_term {
            config.imu_prior_term = f;
        }
        if let Some(f) = self.imu_depth_time {
            config.imu_depth_time = f;
        }
        if let Some(text) = &self.levels {
            config.reference_levels = parse_levels(text).map_err(|e| parse("levels", text, e))?;
        }
        let available = config.reference_levels.len();
        let keep = match self.mode {
            Mode::Naive => 0,
            Mode::L1 => 1,
            Mode::L2 => available.max(2),
        };
        if keep > available {
            return Err(SettingsError::TooFewLevels {
                mode: mode_name(self.mode),
                needed: keep,
                levels: self.levels.clone().unwrap_or_default(),
                available,
            });
        }
        config.reference_levels.truncate(keep);
        if keep == 0 && self.keyframes.is_none() {
            // Naive tracking has no reference, so no keyframe: the paper's chain
            // (asking for keyframes with it stays an error of the config).
            config.keyframes = false;
        }
        if !self.bilateral {
            config.filter.bilateral = None;
        }
        if !self.normal_filter {
            config.filter.normal_max_angle_deg = None;
        }
        if !self.contour_filter {
            config.filter.contour_angle_deg = None;
        }
        if let Some(b) = self.memory_budget {
            config.memory_budget = b;
        }
        config.validate().map_err(SettingsError::Invalid)?;
        Ok(config)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera() -> Camera {
        Camera {
            width: 320,
            height: 180,
            fx: 250.0,
            fy: 250.0,
            cx: 159.5,
            cy: 89.5,
            depth_scale: 1000.0,
        }
    }

    #[test]
    fn defaults_are_the_presets_config() {
        for preset in [Preset::Pc, Preset::Phone] {
            for mode in [Mode::Naive, Mode::L1, Mode::L2] {
                let c = Settings::new(preset, mode).config(camera()).unwrap();
                assert_eq!(
                    format!("{c:?}"),
                    format!("{:?}", Config::new(camera(), preset, mode)),
                    "{preset:?} {mode:?}"
                );
            }
        }
    }

    #[test]
    fn errors_name_the_setting() {
        let e = Settings {
            levels: Some("30mm:7deg".into()),
            ..Settings::default()
        }
        .config(camera())
        .unwrap_err();
        assert_eq!(e.key(), Some("mode"));
        assert!(e.to_string().contains("needs at least 2"), "{e}");
        let e = Settings {
            schedule: Some("no-such".into()),
            ..Settings::default()
        }
        .config(camera())
        .unwrap_err();
        assert_eq!(e.key(), Some("schedule"));
        let e = Settings {
            max_correction_distance: Some(f64::NAN),
            ..Settings::default()
        }
        .config(camera())
        .unwrap_err();
        assert!(matches!(e, SettingsError::Invalid(_)), "{e}");
        let c = Settings {
            memory_budget: Some(1),
            ..Settings::default()
        }
        .config(camera())
        .unwrap();
        assert_eq!(c.memory_budget, 1);
    }

    #[test]
    fn imu_settings_default_to_the_engines_and_apply() {
        let engine = Config::new(camera(), Preset::Pc, Mode::L2);
        assert!(!engine.imu_fusion, "the engine's default is off");
        let c = Settings::default().config(camera()).unwrap();
        assert_eq!(c.imu_fusion, engine.imu_fusion);
        assert_eq!(c.imu_prior_term, engine.imu_prior_term);
        assert_eq!(c.imu_depth_time, engine.imu_depth_time);
        for on in [true, false] {
            let c = Settings {
                imu_fusion: Some(on),
                ..Settings::default()
            }
            .config(camera())
            .unwrap();
            assert_eq!(c.imu_fusion, on);
            let c = Settings {
                imu_prior_term: Some(on),
                ..Settings::default()
            }
            .config(camera())
            .unwrap();
            assert_eq!(c.imu_prior_term, on);
            let c = Settings {
                imu_depth_time: Some(on),
                ..Settings::default()
            }
            .config(camera())
            .unwrap();
            assert_eq!(c.imu_depth_time, on);
        }
    }
}
