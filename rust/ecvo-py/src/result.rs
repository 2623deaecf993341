//! `ecvo.FrameResult`: what `Tracker.push` returns for one frame: the pose and state
//! (it unpacks as `(pose, state)`), with the registration's quality beside them.

use ecvo_core::FrameOutput;
use numpy::PyArray2;
use numpy::ndarray::Array2;
use pyo3::exceptions::PyIndexError;
use pyo3::prelude::*;
use pyo3::types::PyTuple;

use crate::arrays::pose_array;
use crate::tracker::state_name;

/// What Tracker.push returns for one frame: the pose and the state (it unpacks as
/// (pose, state)), and the quality of the registration the pose came from.
#[pyclass(module = "ecvo._ecvo", name = "FrameResult", frozen)]
pub struct PyFrameResult {
    pose: Py<PyArray2<f64>>,
    state: &'static str,
    timestamp: f64,
    index: u64,
    information: [[f64; 6]; 6],
    scale: Option<[f64; 3]>,
    valid_points: usize,
    template_points: usize,
    reason: Option<&'static str>,
    recovered: bool,
    reanchored: bool,
    reference_levels: u8,
    motion_estimations: u32,
    refused_corrections: u8,
}

impl PyFrameResult {
    /// The result of `out`.
    pub fn new(py: Python<'_>, out: &FrameOutput) -> Self {
        let reg = out.registration.as_ref();
        // ecvo orders the twist [v; ω]; Open3D (and this result) [ω; v].
        let mut information = [[0.0; 6]; 6];
        if let Some(r) = reg {
            let swap = |k: usize| (k + 3) % 6;
            for (i, row) in information.iter_mut().enumerate() {
                for (j, x) in row.iter_mut().enumerate() {
                    *x = r.information[(swap(i), swap(j))];
                }
            }
        }
        PyFrameResult {
            pose: pose_array(py, &out.pose).unbind(),
            state: state_name(out.state),
            timestamp: out.timestamp,
            index: out.index,
            information,
            scale: reg.and_then(|r| r.scale).map(|s| [s.ii, s.iz, s.zz]),
            valid_points: reg.map_or(0, |r| r.valid_pixels),
            template_points: reg.map_or(0, |r| r.template_points),
            reason: out.lost_reason.map(|r| r.name()),
            recovered: out.recovered,
            reanchored: out.reanchored,
            reference_levels: out.reference_levels,
            motion_estimations: out.motion_estimations,
            refused_corrections: out.refused_corrections,
        }
    }

    fn pair<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        (self.pose.bind(py).clone(), self.state).into_pyobject(py)
    }
}

#[pymethods]
impl PyFrameResult {
    /// Camera-to-world pose (4x4 float64; the world is the first camera); a lost
    /// frame keeps the last good pose.
    #[getter]
    fn pose<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        self.pose.bind(py).clone()
    }

    /// "tracking" or "lost".
    #[getter]
    fn state(&self) -> &'static str {
        self.state
    }

    /// The frame's timestamp (seconds).
    #[getter]
    fn timestamp(&self) -> f64 {
        self.timestamp
    }

    /// The frame's position in the stream, from 0.
    #[getter]
    fn index(&self) -> u64 {
        self.index
    }

    /// 6x6 information matrix (float64, symmetric) of the registration the pose came
    /// from: the normal equations' JᵀWJ at the solution, whitened by the fitted
    /// residual scale (units of the noise), in the tangent space of the motion from
    /// the frame registered against (the previous frame, the keyframe or the
    /// reference a recovery used) to this one, perturbed on the left, ordered
    /// (rx, ry, rz, tx, ty, tz) as Open3D's compute_rgbd_odometry(previous, current)
    /// returns it. Its inverse approximates the motion's covariance (radians,
    /// metres). Zeros on the first frame and on lost frames (no constraint).
    #[getter]
    fn information<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        let m = Array2::from_shape_fn((6, 6), |(i, j)| self.information[i][j]);
        PyArray2::from_owned_array(py, m)
    }

    /// The fitted residual scale Σ of that registration, 2x2 float64 over
    /// (intensity in [0, 1], depth residual times its gain), or None without one.
    #[getter]
    fn residual_scale<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray2<f64>>> {
        self.scale.map(|[ii, iz, zz]| {
            PyArray2::from_owned_array(py, numpy::ndarray::arr2(&[[ii, iz], [iz, zz]]))
        })
    }

    /// Template points that landed on valid pixels at the finest step.
    #[getter]
    fn valid_points(&self) -> usize {
        self.valid_points
    }

    /// Template points of the finest step.
    #[getter]
    fn template_points(&self) -> usize {
        self.template_points
    }

    /// valid_points / template_points: the fraction of the template used (0.0
    /// without a registration).
    #[getter]
    fn point_fraction(&self) -> f64 {
        if self.template_points == 0 {
            0.0
        } else {
            self.valid_points as f64 / self.template_points as f64
        }
    }

    /// Why the frame was lost ("no_valid_depth", "too_few_points", "degenerate",
    /// "diverged", "inconsistent", "implausible_speed", "spread_jump"), None unless
    /// lost.
    #[getter]
    fn reason(&self) -> Option<&'static str> {
        self.reason
    }

    /// [A] failed and the frame registered against a kept reference instead.
    #[getter]
    fn recovered(&self) -> bool {
        self.recovered
    }

    /// After too many lost frames tracking started afresh at this frame.
    #[getter]
    fn reanchored(&self) -> bool {
        self.reanchored
    }

    /// The frame became the reference at levels 1..=reference_levels (0: none).
    #[getter]
    fn reference_levels(&self) -> u8 {
        self.reference_levels
    }

    /// MOTION calls spent on this frame.
    #[getter]
    fn motion_estimations(&self) -> u32 {
        self.motion_estimations
    }

    /// Corrections of this frame that failed or were rejected.
    #[getter]
    fn refused_corrections(&self) -> u8 {
        self.refused_corrections
    }

    fn __len__(&self) -> usize {
        2
    }

    fn __getitem__<'py>(&self, py: Python<'py>, index: isize) -> PyResult<Bound<'py, PyAny>> {
        match index {
            0 | -2 => Ok(self.pose.bind(py).clone().into_any()),
            1 | -1 => Ok(self.state.into_pyobject(py)?.into_any()),
            _ => Err(PyIndexError::new_err(
                "a FrameResult unpacks as (pose, state)",
            )),
        }
    }

    fn __iter__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.pair(py)?.try_iter().map(|i| i.into_any())
    }

    fn __repr__(&self) -> String {
        match self.reason {
            Some(r) => format!(
                "FrameResult(index={}, timestamp={}, state={:?}, reason={r:?})",
                self.index, self.timestamp, self.state
            ),
            None => format!(
                "FrameResult(index={}, timestamp={}, state={:?}, point_fraction={:.3})",
                self.index,
                self.timestamp,
                self.state,
                self.point_fraction()
            ),
        }
    }
}
