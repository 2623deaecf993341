//! The keyword settings of `Tracker(...)` and `run_sequence(...)` and how they become
//! a [`Config`]: the same choices, names and order of application as `ecvo run`'s
//! flags (`rust/ecvo-cli/src/settings.rs`), so that equal settings give equal poses.

use ecvo_core::config::parse_levels;
use ecvo_core::{Camera, Config, DepthNoiseModel, Mode, MotionPrior, Preset, Weighting};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// The engine keywords every entry point takes (the flags of `ecvo run`).
pub const ENGINE_KEYS: &[&str] = &[
    "levels",
    "bilateral",
    "normal_filter",
    "contour_filter",
    "paper",
    "schedule",
    "point_budget",
    "weighting",
    "depth_noise",
    "prior",
    "max_correction_distance",
    "max_fine_depth_weight",
    "min_predicted_decrease",
    "min_update_px",
    "scale_passes",
    "corrections",
    "refine_every",
    "tracking",
    "keyframe_overlap",
    "keyframe_spread",
];

/// How the engine is configured, beyond the camera.
#[derive(Clone, Debug)]
pub struct EngineSettings {
    pub preset: Preset,
    pub mode: Mode,
    pub levels: Option<String>,
    pub bilateral: bool,
    pub normal_filter: bool,
    pub contour_filter: bool,
    pub paper: bool,
    pub schedule: Option<String>,
    pub point_budget: Option<String>,
    pub weighting: Option<(Weighting, Option<Weighting>)>,
    pub depth_noise: Option<DepthNoiseModel>,
    pub prior: Option<MotionPrior>,
    pub max_correction_distance: Option<f64>,
    pub max_fine_depth_weight: Option<f64>,
    pub min_predicted_decrease: Option<f64>,
    pub min_update_px: Option<f64>,
    pub scale_passes: Option<usize>,
    pub fuse_corrections: Option<bool>,
    pub refine_every: Option<u32>,
    pub keyframes: Option<bool>,
    pub keyframe_min_overlap: Option<f64>,
    pub keyframe_max_spread_growth: Option<f64>,
}

/// Parses `preset` / `mode` names.
pub fn parse_preset(name: &str) -> PyResult<Preset> {
    match name {
        "pc" => Ok(Preset::Pc),
        "phone" => Ok(Preset::Phone),
        _ => Err(PyValueError::new_err(format!(
            "preset must be \"pc\" or \"phone\", got {name:?}"
        ))),
    }
}

/// Parses a mode name.
pub fn parse_mode(name: &str) -> PyResult<Mode> {
    match name {
        "naive" => Ok(Mode::Naive),
        "l1" => Ok(Mode::L1),
        "l2" => Ok(Mode::L2),
        _ => Err(PyValueError::new_err(format!(
            "mode must be \"naive\", \"l1\" or \"l2\", got {name:?}"
        ))),
    }
}

fn mode_name(mode: Mode) -> &'static str {
    match mode {
        Mode::Naive => "naive",
        Mode::L1 => "l1",
        Mode::L2 => "l2",
    }
}

/// Keyword arguments, taken one by one; what is left at the end is an error.
pub struct Kwargs<'py> {
    dict: Option<Bound<'py, PyDict>>,
    func: &'static str,
}

impl<'py> Kwargs<'py> {
    /// Wraps the keyword arguments of `func` (a copy: the caller's dict is left alone).
    pub fn new(dict: Option<&Bound<'py, PyDict>>, func: &'static str) -> PyResult<Self> {
        Ok(Kwargs {
            dict: dict.map(|d| d.copy()).transpose()?,
            func,
        })
    }

    /// Removes and returns `key` if given (and not None).
    pub fn take_any(&mut self, key: &str) -> PyResult<Option<Bound<'py, PyAny>>> {
        let Some(d) = &self.dict else {
            return Ok(None);
        };
        let v = d.get_item(key)?;
        if v.is_some() {
            d.del_item(key)?;
        }
        Ok(v.filter(|v| !v.is_none()))
    }

    /// Removes and extracts `key` if given, with a TypeError naming it and the type.
    pub fn take<T>(&mut self, key: &str, what: &str) -> PyResult<Option<T>>
    where
        T: for<'a> FromPyObject<'a, 'py>,
    {
        match self.take_any(key)? {
            None => Ok(None),
            Some(v) => match v.extract::<T>() {
                Ok(x) => Ok(Some(x)),
                Err(_) => Err(PyTypeError::new_err(format!(
                    "{}(): {key} must be {what}, got {}",
                    self.func,
                    type_name(&v)
                ))),
            },
        }
    }

    /// Fails on any keyword not taken.
    pub fn finish(self) -> PyResult<()> {
        if let Some(d) = self.dict {
            if let Some((k, _)) = d.iter().next() {
                let key: String = k.str()?.to_string();
                return Err(PyTypeError::new_err(format!(
                    "{}() got an unexpected keyword argument '{key}' (engine settings: {})",
                    self.func,
                    ENGINE_KEYS.join(", ")
                )));
            }
        }
        Ok(())
    }
}

/// The Python type name of `v`, for messages.
pub fn type_name(v: &Bound<'_, PyAny>) -> String {
    v.get_type()
        .name()
        .map_or_else(|_| "?".to_string(), |n| n.to_string())
}

/// A float setting that must not be NaN.
fn take_f64(kw: &mut Kwargs<'_>, key: &str) -> PyResult<Option<f64>> {
    let v: Option<f64> = kw.take(key, "a float")?;
    if let Some(x) = v {
        if x.is_nan() {
            return Err(PyValueError::new_err(format!(
                "{}(): {key} must not be NaN",
                kw.func
            )));
        }
    }
    Ok(v)
}

fn choice<T: Copy>(kw: &mut Kwargs<'_>, key: &str, options: &[(&str, T)]) -> PyResult<Option<T>> {
    let Some(name) = kw.take::<String>(key, "a str")? else {
        return Ok(None);
    };
    match options.iter().find(|(n, _)| *n == name) {
        Some((_, v)) => Ok(Some(*v)),
        None => Err(PyValueError::new_err(format!(
            "{}(): {key} must be one of {}, got {name:?}",
            kw.func,
            options
                .iter()
                .map(|(n, _)| format!("\"{n}\""))
                .collect::<Vec<_>>()
                .join(", ")
        ))),
    }
}

impl EngineSettings {
    /// Takes the engine keywords out of `kw`.
    pub fn from_kwargs(preset: &str, mode: &str, kw: &mut Kwargs<'_>) -> PyResult<Self> {
        let flag = |kw: &mut Kwargs<'_>, key: &str| -> PyResult<bool> {
            Ok(kw.take::<bool>(key, "a bool")?.unwrap_or(true))
        };
        Ok(EngineSettings {
            preset: parse_preset(preset)?,
            mode: parse_mode(mode)?,
            levels: kw.take("levels", "a str such as \"30mm:7deg,120mm:12deg\"")?,
            bilateral: flag(kw, "bilateral")?,
            normal_filter: flag(kw, "normal_filter")?,
            contour_filter: flag(kw, "contour_filter")?,
            paper: kw.take::<bool>("paper", "a bool")?.unwrap_or(false),
            schedule: kw.take("schedule", "a str")?,
            point_budget: kw.take("point_budget", "a str such as \"1=4096,0=4096\"")?,
            weighting: choice(
                kw,
                "weighting",
                &[
                    ("scalar", (Weighting::Scalar, None)),
                    ("bivariate", (Weighting::Bivariate, None)),
                    ("hybrid", (Weighting::Bivariate, Some(Weighting::Scalar))),
                ],
            )?,
            depth_noise: choice(
                kw,
                "depth_noise",
                &[
                    ("constant", DepthNoiseModel::Constant),
                    ("quadratic", DepthNoiseModel::Quadratic),
                    ("fitted", DepthNoiseModel::Fitted),
                ],
            )?,
            prior: choice(
                kw,
                "prior",
                &[
                    ("identity", MotionPrior::Identity),
                    ("velocity", MotionPrior::ConstantVelocity),
                ],
            )?,
            max_correction_distance: take_f64(kw, "max_correction_distance")?,
            max_fine_depth_weight: take_f64(kw, "max_fine_depth_weight")?,
            min_predicted_decrease: take_f64(kw, "min_predicted_decrease")?,
            min_update_px: take_f64(kw, "min_update_px")?,
            scale_passes: kw.take("scale_passes", "an int >= 0")?,
            fuse_corrections: choice(kw, "corrections", &[("fuse", true), ("replace", false)])?,
            refine_every: kw.take("refine_every", "an int >= 0")?,
            keyframes: choice(kw, "tracking", &[("chain", false), ("keyframe", true)])?,
            keyframe_min_overlap: take_f64(kw, "keyframe_overlap")?,
            keyframe_max_spread_growth: take_f64(kw, "keyframe_spread")?,
        })
    }

    /// The tracker configuration for `camera`, built in the order `ecvo run` builds
    /// it; an invalid setting is a ValueError naming it.
    pub fn config(&self, camera: Camera) -> PyResult<Config> {
        let bad = |key: &str, e: ecvo_core::Error| PyValueError::new_err(format!("{key}: {e}"));
        let mut config = if self.paper {
            Config::paper(camera, self.preset, Mode::L2)
        } else {
            Config::new(camera, self.preset, Mode::L2)
        };
        if let Some(name) = &self.schedule {
            config.motion.levels =
                ecvo_core::parse_schedule(name, &camera).map_err(|e| bad("schedule", e))?;
        }
        if let Some(text) = &self.point_budget {
            let budgets =
                ecvo_core::parse_point_budget(text).map_err(|e| bad("point_budget", e))?;
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
        if let Some(f) = self.keyframe_max_spread_growth {
            config.keyframe_max_spread_growth = f;
        }
        if let Some(text) = &self.levels {
            config.reference_levels = parse_levels(text).map_err(|e| bad("levels", e))?;
        }
        let available = config.reference_levels.len();
        let keep = match self.mode {
            Mode::Naive => 0,
            Mode::L1 => 1,
            Mode::L2 => available.max(2),
        };
        if keep > available {
            return Err(PyValueError::new_err(format!(
                "mode {:?} needs at least {keep} reference level(s) but levels {:?} gives {available}",
                mode_name(self.mode),
                self.levels.as_deref().unwrap_or_default()
            )));
        }
        config.reference_levels.truncate(keep);
        if !self.bilateral {
            config.filter.bilateral = None;
        }
        if !self.normal_filter {
            config.filter.normal_max_angle_deg = None;
        }
        if !self.contour_filter {
            config.filter.contour_angle_deg = None;
        }
        config
            .validate()
            .map_err(|e| PyValueError::new_err(format!("invalid tracker configuration: {e}")))?;
        Ok(config)
    }
}
