//! `ecvo.Camera`: pinhole intrinsics and depth units.

use std::collections::hash_map::DefaultHasher;
use std::hash::{Hash, Hasher};

use numpy::{PyArray2, PyReadonlyArray2};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// Pinhole intrinsics and depth units of an RGB-D stream whose intensity is
/// registered to its depth: Camera(width, height, fx, fy, cx, cy, depth_scale).
/// fy may be negative (a flipped y axis); depth_scale is raw depth units per metre
/// (5000 for TUM, 1000 for millimetres). Non-finite or unusable values are a
/// ValueError naming the field. Cameras compare equal field by field, hash alike
/// when equal, and pickle.
#[pyclass(module = "ecvo._ecvo", name = "Camera", frozen, eq, from_py_object)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PyCamera {
    pub inner: ecvo_core::Camera,
}

/// The constructor's arguments, for pickling.
type CameraArgs = (usize, usize, f64, f64, f64, f64, f64);

#[pymethods]
impl PyCamera {
    #[new]
    #[pyo3(signature = (width, height, fx, fy, cx, cy, depth_scale))]
    fn new(
        width: i64,
        height: i64,
        fx: f64,
        fy: f64,
        cx: f64,
        cy: f64,
        depth_scale: f64,
    ) -> PyResult<Self> {
        if width <= 0 || height <= 0 {
            return Err(PyValueError::new_err(format!(
                "Camera: width and height must be positive, got {width}x{height}"
            )));
        }
        let inner = ecvo_core::Camera {
            width: width as usize,
            height: height as usize,
            fx,
            fy,
            cx,
            cy,
            depth_scale,
        };
        inner
            .validate()
            .map_err(|e| PyValueError::new_err(format!("Camera: {e}")))?;
        Ok(PyCamera { inner })
    }

    /// Reads a camera.json (the file ecvo sequences carry).
    #[staticmethod]
    fn from_json(path: std::path::PathBuf) -> PyResult<Self> {
        let inner = ecvo_io::load_camera_json(&path).map_err(crate::io_err)?;
        Ok(PyCamera { inner })
    }

    /// Image width, pixels.
    #[getter]
    fn width(&self) -> usize {
        self.inner.width
    }
    /// Image height, pixels.
    #[getter]
    fn height(&self) -> usize {
        self.inner.height
    }
    /// Focal length along x, pixels.
    #[getter]
    fn fx(&self) -> f64 {
        self.inner.fx
    }
    /// Focal length along y, pixels (negative: a flipped y axis).
    #[getter]
    fn fy(&self) -> f64 {
        self.inner.fy
    }
    /// Principal point x, pixels.
    #[getter]
    fn cx(&self) -> f64 {
        self.inner.cx
    }
    /// Principal point y, pixels.
    #[getter]
    fn cy(&self) -> f64 {
        self.inner.cy
    }
    /// Raw depth units per metre.
    #[getter]
    fn depth_scale(&self) -> f64 {
        self.inner.depth_scale
    }

    /// The 3x3 intrinsic matrix K (float64).
    fn intrinsic_matrix<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        let c = &self.inner;
        let k = numpy::ndarray::arr2(&[[c.fx, 0.0, c.cx], [0.0, c.fy, c.cy], [0.0, 0.0, 1.0]]);
        PyArray2::from_owned_array(py, k)
    }

    /// A camera from the 3x3 intrinsic matrix K ([[fx, 0, cx], [0, fy, cy], [0, 0,
    /// 1]]; skew must be 0), the image size in pixels and the raw depth units per
    /// metre. Anything else is a ValueError.
    #[staticmethod]
    #[pyo3(signature = (k, width, height, depth_scale))]
    fn from_matrix(
        k: &Bound<'_, PyAny>,
        width: i64,
        height: i64,
        depth_scale: f64,
    ) -> PyResult<Self> {
        let arr = k
            .py()
            .import("numpy")?
            .call_method1("asarray", (k, "float64"))
            .map_err(|_| PyTypeError::new_err("K must be a 3x3 array of floats"))?;
        let arr: PyReadonlyArray2<'_, f64> = arr
            .extract()
            .map_err(|_| PyValueError::new_err("K must be a 3x3 array"))?;
        let a = arr.as_array();
        if a.shape() != [3, 3] {
            return Err(PyValueError::new_err(format!(
                "K must be 3x3, got shape {:?}",
                a.shape()
            )));
        }
        if a[(0, 1)] != 0.0 || a[(1, 0)] != 0.0 || a[(2, 0)] != 0.0 || a[(2, 1)] != 0.0 {
            return Err(PyValueError::new_err(
                "K: skew and off-diagonal terms must be 0 (a pinhole camera without skew)",
            ));
        }
        if a[(2, 2)] != 1.0 {
            return Err(PyValueError::new_err(format!(
                "K[2, 2] must be 1, got {}",
                a[(2, 2)]
            )));
        }
        Self::new(
            width,
            height,
            a[(0, 0)],
            a[(1, 1)],
            a[(0, 2)],
            a[(1, 2)],
            depth_scale,
        )
    }

    /// The fields as a dict with the keys of camera.json and of the constructor:
    /// Camera(**camera.to_dict()) == camera.
    #[allow(clippy::wrong_self_convention)] // the Python name
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let c = &self.inner;
        let d = PyDict::new(py);
        d.set_item("width", c.width)?;
        d.set_item("height", c.height)?;
        d.set_item("fx", c.fx)?;
        d.set_item("fy", c.fy)?;
        d.set_item("cx", c.cx)?;
        d.set_item("cy", c.cy)?;
        d.set_item("depth_scale", c.depth_scale)?;
        Ok(d)
    }

    fn __hash__(&self) -> u64 {
        let c = &self.inner;
        let mut h = DefaultHasher::new();
        (c.width, c.height).hash(&mut h);
        // +0.0 for -0.0, so that equal cameras hash alike (NaN is refused).
        for v in [c.fx, c.fy, c.cx, c.cy, c.depth_scale] {
            (v + 0.0).to_bits().hash(&mut h);
        }
        h.finish()
    }

    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, CameraArgs)> {
        let c = slf.get().inner;
        Ok((
            slf.get_type().into_any(),
            (c.width, c.height, c.fx, c.fy, c.cx, c.cy, c.depth_scale),
        ))
    }

    fn __repr__(&self) -> String {
        let c = &self.inner;
        format!(
            "Camera(width={}, height={}, fx={:?}, fy={:?}, cx={:?}, cy={:?}, depth_scale={:?})",
            c.width, c.height, c.fx, c.fy, c.cx, c.cy, c.depth_scale
        )
    }
}
