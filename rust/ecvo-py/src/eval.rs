//! `ecvo.ate`: the absolute trajectory error as `ecvo eval`, TUM's tools and evo
//! compute it (ecvo-io's [`ecvo_io::eval::ate`]).

use std::path::PathBuf;

use ecvo_core::Pose;
use ecvo_core::nalgebra::{Quaternion, Translation3, UnitQuaternion};
use ecvo_io::Trajectory;
use ecvo_io::eval::AteResult;
use numpy::{PyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString};

use crate::arrays::pose_array;
use crate::settings::type_name;

/// A trajectory argument: a TUM file path, or an `(N, 8)` float64 array of TUM rows.
fn trajectory_arg(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<Trajectory> {
    if obj.is_instance_of::<PyString>() || obj.hasattr("__fspath__")? {
        let path: PathBuf = obj.extract()?;
        return Trajectory::read_tum(&path).map_err(crate::io_err);
    }
    let arr: PyReadonlyArray2<'_, f64> = obj.extract().map_err(|_| {
        PyTypeError::new_err(format!(
            "{name} must be a TUM trajectory file path or an (N, 8) float64 array of rows \
             [t, tx, ty, tz, qx, qy, qz, qw], got {}",
            type_name(obj)
        ))
    })?;
    if arr.shape()[1] != 8 {
        return Err(PyValueError::new_err(format!(
            "{name} must have shape (N, 8) (rows [t, tx, ty, tz, qx, qy, qz, qw]), got ({}, {})",
            arr.shape()[0],
            arr.shape()[1]
        )));
    }
    let a = arr.as_array();
    let mut t = Trajectory::with_capacity(a.nrows());
    for (k, row) in a.rows().into_iter().enumerate() {
        let v: Vec<f64> = row.iter().copied().collect();
        if v.iter().any(|x| !x.is_finite()) {
            return Err(PyValueError::new_err(format!(
                "{name}: row {k} has a non-finite value"
            )));
        }
        if let Some(&last) = t.stamps.last() {
            if !(v[0] > last) {
                return Err(PyValueError::new_err(format!(
                    "{name}: row {k}: timestamp {} is not after the previous one ({last}); \
                     timestamps must be strictly increasing",
                    v[0]
                )));
            }
        }
        // As Trajectory::parse_tum normalises quaternions (rotations do not enter the
        // ATE, but the alignment's pose is built from them nowhere else).
        let q = Quaternion::new(v[7], v[4], v[5], v[6]);
        let norm = q.norm();
        if !(norm > 1e-6) {
            return Err(PyValueError::new_err(format!(
                "{name}: row {k}: the quaternion is zero"
            )));
        }
        let q = if (norm - 1.0).abs() > 1e-15 {
            q / norm
        } else {
            q
        };
        t.push(
            v[0],
            Pose::from_parts(
                Translation3::new(v[1], v[2], v[3]),
                UnitQuaternion::new_unchecked(q),
            ),
        );
    }
    Ok(t)
}

/// The ATE as a dict.
pub fn ate_dict<'py>(py: Python<'py>, a: &AteResult) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("rmse", a.rmse)?;
    d.set_item("mean", a.mean)?;
    d.set_item("median", a.median)?;
    d.set_item("std", a.std)?;
    d.set_item("min", a.min)?;
    d.set_item("max", a.max)?;
    d.set_item("count", a.count)?;
    d.set_item("alignment", pose_array(py, &a.alignment))?;
    d.set_item("errors", PyArray1::from_slice(py, &a.errors))?;
    Ok(d)
}

/// evo's `t_max_diff` default (seconds): `ecvo.ate` pairs poses as `evo_ape` does
/// by default. (`ecvo eval` and `run_sequence` keep ecvo-io's 0.02 s, TUM's
/// `evaluate_ate.py` default.)
pub const EVO_MAX_DT: f64 = 0.01;

/// ATE of ``est`` against ``gt`` (TUM files or (N, 8) arrays); see ecvo.ate.
#[pyfunction]
#[pyo3(signature = (gt, est, max_dt = EVO_MAX_DT))]
pub fn ate<'py>(
    py: Python<'py>,
    gt: &Bound<'py, PyAny>,
    est: &Bound<'py, PyAny>,
    max_dt: f64,
) -> PyResult<Bound<'py, PyDict>> {
    if !(max_dt > 0.0) {
        return Err(PyValueError::new_err(format!(
            "max_dt must be positive, got {max_dt}"
        )));
    }
    let g = trajectory_arg("gt", gt)?;
    let e = trajectory_arg("est", est)?;
    let a = py
        .detach(|| ecvo_io::eval::ate_with_max_dt(&g, &e, max_dt))
        .map_err(|e| PyValueError::new_err(format!("ate: {e}")))?;
    ate_dict(py, &a)
}
