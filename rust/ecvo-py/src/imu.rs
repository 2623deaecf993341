//! The IMU in Python: `Tracker(..., imu_rotation=, imu_time_offset=)` and
//! `Tracker.push_imu`.

use ecvo_core::{GyroSample, ImuCalibration};
use numpy::{PyReadonlyArray1, PyReadonlyArray2};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;

use crate::settings::Kwargs;

/// The calibration from the keywords `imu_rotation` (3x3 camera-from-IMU rotation),
/// `imu_time_offset` (seconds, t_frames = t_imu + offset), `gyro_noise_density` and
/// `gyro_bias_random_walk`, taken out of `kw`.
pub fn calibration(kw: &mut Kwargs<'_>) -> PyResult<ImuCalibration> {
    let mut c = ImuCalibration::default();
    if let Some(r) = kw.take_any("imu_rotation")? {
        c.camera_from_imu = crate::tracker::rigid(&r, "imu_rotation", true)?.rotation;
    }
    if let Some(t) = kw.take::<f64>("imu_time_offset", "a float (seconds)")? {
        c.time_offset = t;
    }
    c.gyro_noise_density = kw.take::<f64>("gyro_noise_density", "a float (rad/s/√Hz)")?;
    c.gyro_bias_random_walk = kw.take::<f64>("gyro_bias_random_walk", "a float (rad/s/√s)")?;
    c.validate()
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    Ok(c)
}

/// Gyro samples from `timestamps` (N) and `rates` (N x 3) array-likes.
pub fn samples<'py>(
    timestamps: &Bound<'py, PyAny>,
    rates: &Bound<'py, PyAny>,
) -> PyResult<Vec<GyroSample>> {
    let np = timestamps.py().import("numpy")?;
    let as_f64 = |obj: &Bound<'py, PyAny>, name: &str| -> PyResult<Bound<'py, PyAny>> {
        np.call_method1("asarray", (obj, "float64"))
            .map_err(|_| PyTypeError::new_err(format!("{name} must be an array of floats")))
    };
    let (t, w) = (as_f64(timestamps, "timestamps")?, as_f64(rates, "rates")?);
    let t: PyReadonlyArray1<'_, f64> = t
        .extract()
        .map_err(|_| PyValueError::new_err("timestamps must be a 1-d array (N,)"))?;
    let w: PyReadonlyArray2<'_, f64> = w
        .extract()
        .map_err(|_| PyValueError::new_err("rates must be a 2-d array (N, 3)"))?;
    let (t, w) = (t.as_array(), w.as_array());
    if w.shape() != [t.len(), 3] {
        return Err(PyValueError::new_err(format!(
            "rates must have shape ({}, 3) to match timestamps, got {:?}",
            t.len(),
            w.shape()
        )));
    }
    Ok((0..t.len())
        .map(|i| GyroSample {
            t: t[i],
            w: [w[(i, 0)], w[(i, 1)], w[(i, 2)]],
        })
        .collect())
}

/// The IMU counters as a dict.
pub fn counters_dict<'py>(
    py: Python<'py>,
    c: &ecvo_core::imu::ImuCounters,
) -> PyResult<Bound<'py, pyo3::types::PyDict>> {
    let d = pyo3::types::PyDict::new(py);
    d.set_item("samples", c.samples)?;
    d.set_item("refused", c.refused)?;
    d.set_item("dropped", c.dropped)?;
    d.set_item("priors", c.priors)?;
    d.set_item("late", c.late)?;
    d.set_item("missing", c.missing)?;
    d.set_item("bias_updates", c.bias_updates)?;
    d.set_item("bias_outliers", c.bias_outliers)?;
    d.set_item("depth_turned", c.depth_turned)?;
    d.set_item("depth_unturned", c.depth_unturned)?;
    Ok(d)
}
