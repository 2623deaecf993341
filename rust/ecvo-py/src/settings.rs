//! The keyword settings of `Tracker(...)` and `run_sequence(...)`: parsed into
//! [`ecvo_settings::Settings`], which the CLI's flags and the JNI's init arguments
//! are parsed into too and which alone turns them into a [`Config`], so that equal
//! settings give equal poses.

use ecvo_core::{
    Camera, Config, DepthNoiseModel, LookupDepth, Mode, MotionPrior, Preset, Weighting,
};
use ecvo_settings::{Settings, SettingsError};
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
    "lookup_depth",
    "keyframe_fuse_every",
    "imu_fusion",
    "imu_prior_term",
    "imu_depth_time",
    "memory_budget",
];

/// How the engine is configured, beyond the camera: [`Settings`], the one set of
/// settings the CLI, this package and the JNI turn into a [`Config`] the same way.
#[derive(Clone, Debug)]
pub struct EngineSettings(pub Settings);

/// Parses `preset` / `mode` names.
pub fn parse_preset(name: &str) -> PyResult<Preset> {
    ecvo_settings::parse_preset(name).ok_or_else(|| {
        PyValueError::new_err(format!("preset must be \"pc\" or \"phone\", got {name:?}"))
    })
}

/// Parses a mode name.
pub fn parse_mode(name: &str) -> PyResult<Mode> {
    ecvo_settings::parse_mode(name).ok_or_else(|| {
        PyValueError::new_err(format!(
            "mode must be \"naive\", \"l1\" or \"l2\", got {name:?}"
        ))
    })
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
        Ok(EngineSettings(Settings {
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
            lookup_depth: choice(
                kw,
                "lookup_depth",
                &[
                    ("filtered", LookupDepth::Filtered),
                    ("raw", LookupDepth::Raw),
                    ("bilateral", LookupDepth::Bilateral),
                ],
            )?,
            keyframe_fuse_every: kw.take("keyframe_fuse_every", "an int >= 0")?,
            imu_fusion: kw.take("imu_fusion", "a bool")?,
            imu_prior_term: kw.take("imu_prior_term", "a bool")?,
            imu_depth_time: kw.take("imu_depth_time", "a bool")?,
            memory_budget: kw.take("memory_budget", "an int (bytes)")?,
        }))
    }

    /// The tracker configuration for `camera` ([`Settings::config`]); an invalid
    /// setting is a ValueError naming it.
    pub fn config(&self, camera: Camera) -> PyResult<Config> {
        self.0.config(camera).map_err(|e| match e {
            SettingsError::Parse { key, source, .. } => {
                PyValueError::new_err(format!("{key}: {source}"))
            }
            SettingsError::TooFewLevels {
                mode,
                needed,
                levels,
                available,
            } => PyValueError::new_err(format!(
                "mode {mode:?} needs at least {needed} reference level(s) but levels \
                 {levels:?} gives {available}"
            )),
            SettingsError::Invalid(e) => {
                PyValueError::new_err(format!("invalid tracker configuration: {e}"))
            }
        })
    }
}
