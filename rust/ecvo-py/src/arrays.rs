//! numpy arrays in and out: the checks on a frame's planes (type, dtype, shape, with
//! messages that say what was expected) and poses as 4x4 arrays.

use ecvo_core::Pose;
use ecvo_io::Trajectory;
use numpy::ndarray::Array2;
use numpy::{
    Element, PyArray2, PyArrayDescrMethods, PyArrayMethods, PyReadonlyArray2, PyUntypedArray,
    PyUntypedArrayMethods, dtype,
};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;

use crate::settings::type_name;

/// `obj` as a read-only 2-D numpy array of `T` with shape `(height, width)`; any
/// strides. A non-array or another dtype is a TypeError, another shape a ValueError.
pub fn plane<'py, T: Element>(
    obj: &Bound<'py, PyAny>,
    name: &str,
    dtype_name: &str,
    height: usize,
    width: usize,
) -> PyResult<PyReadonlyArray2<'py, T>> {
    let py = obj.py();
    let Ok(untyped) = obj.cast::<PyUntypedArray>() else {
        return Err(PyTypeError::new_err(format!(
            "{name} must be a numpy.ndarray of {dtype_name}, got {}",
            type_name(obj)
        )));
    };
    let dt = untyped.dtype();
    if !dt.is_equiv_to(&dtype::<T>(py)) {
        return Err(PyTypeError::new_err(format!(
            "{name} must have dtype {dtype_name} (native byte order), got {}",
            dt.str().map_or_else(|_| "?".to_string(), |s| s.to_string())
        )));
    }
    let shape = untyped.shape();
    if shape != [height, width] {
        return Err(PyValueError::new_err(format!(
            "{name} must have shape ({height}, {width}) (height, width of the camera), got {}",
            shape_text(shape)
        )));
    }
    let arr = obj.cast::<PyArray2<T>>().map_err(|_| {
        PyTypeError::new_err(format!(
            "{name} must be a 2-D numpy.ndarray of {dtype_name}"
        ))
    })?;
    arr.try_readonly()
        .map_err(|e| PyValueError::new_err(format!("{name} cannot be read: {e}")))
}

fn shape_text(shape: &[usize]) -> String {
    match shape {
        [n] => format!("({n},)"),
        _ => format!(
            "({})",
            shape
                .iter()
                .map(|n| n.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}

/// The plane's values in row-major order: borrowed when the array is C-contiguous,
/// otherwise copied into `scratch` (reused from frame to frame).
pub fn row_major<'a, T: Element + Copy>(
    arr: &'a PyReadonlyArray2<'_, T>,
    scratch: &'a mut Vec<T>,
) -> &'a [T] {
    // `as_slice` also takes Fortran-ordered arrays (column-major): only C order is
    // the row-major order the engine reads.
    match arr.as_slice() {
        Ok(s) if arr.is_c_contiguous() => s,
        _ => {
            scratch.clear();
            scratch.extend(arr.as_array().iter().copied());
            scratch
        }
    }
}

/// The 4x4 homogeneous matrix of a pose.
pub fn pose_matrix(pose: &Pose) -> Array2<f64> {
    let m = pose.to_homogeneous();
    Array2::from_shape_fn((4, 4), |(r, c)| m[(r, c)])
}

/// A pose as a new 4x4 float64 array.
pub fn pose_array<'py>(py: Python<'py>, pose: &Pose) -> Bound<'py, PyArray2<f64>> {
    PyArray2::from_owned_array(py, pose_matrix(pose))
}

/// One TUM row `[t, tx, ty, tz, qx, qy, qz, qw]`.
pub fn tum_row(t: f64, pose: &Pose) -> [f64; 8] {
    let tr = &pose.translation.vector;
    let q = pose.rotation.quaternion();
    [t, tr.x, tr.y, tr.z, q.i, q.j, q.k, q.w]
}

/// Poses as an `(N, 8)` float64 array of TUM rows.
pub fn tum_array<'py>(py: Python<'py>, traj: &Trajectory) -> Bound<'py, PyArray2<f64>> {
    let n = traj.len();
    let mut data = Vec::with_capacity(n * 8);
    for (t, p) in traj.iter() {
        data.extend_from_slice(&tum_row(t, p));
    }
    let arr = Array2::from_shape_vec((n, 8), data).expect("8 values a row");
    PyArray2::from_owned_array(py, arr)
}
