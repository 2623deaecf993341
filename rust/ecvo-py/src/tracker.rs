//! `ecvo.Camera` and `ecvo.Tracker`: the sequential engine ([`Odometry`]) behind a
//! push-a-frame, get-a-pose API, the GIL released while it tracks.

use std::time::Instant;

use ecvo_core::{Counters, FrameView, Odometry, TrackingState};
use ecvo_io::Trajectory;
use numpy::{PyArray1, PyArray2};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

use crate::arrays::{plane, pose_array, row_major, tum_array};
use crate::settings::{EngineSettings, Kwargs};

/// Pinhole intrinsics and depth units of an RGB-D stream whose intensity is
/// registered to its depth.
#[pyclass(module = "ecvo._ecvo", name = "Camera", frozen, eq, from_py_object)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PyCamera {
    pub inner: ecvo_core::Camera,
}

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

    /// Reads a `camera.json` file (the format `ecvo` sequences carry).
    #[staticmethod]
    fn from_json(path: std::path::PathBuf) -> PyResult<Self> {
        let inner = ecvo_io::load_camera_json(&path).map_err(crate::io_err)?;
        Ok(PyCamera { inner })
    }

    #[getter]
    fn width(&self) -> usize {
        self.inner.width
    }
    #[getter]
    fn height(&self) -> usize {
        self.inner.height
    }
    #[getter]
    fn fx(&self) -> f64 {
        self.inner.fx
    }
    #[getter]
    fn fy(&self) -> f64 {
        self.inner.fy
    }
    #[getter]
    fn cx(&self) -> f64 {
        self.inner.cx
    }
    #[getter]
    fn cy(&self) -> f64 {
        self.inner.cy
    }
    #[getter]
    fn depth_scale(&self) -> f64 {
        self.inner.depth_scale
    }

    /// The 3x3 intrinsic matrix K.
    fn intrinsic_matrix<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        let c = &self.inner;
        let k = numpy::ndarray::arr2(&[[c.fx, 0.0, c.cx], [0.0, c.fy, c.cy], [0.0, 0.0, 1.0]]);
        PyArray2::from_owned_array(py, k)
    }

    fn __repr__(&self) -> String {
        let c = &self.inner;
        format!(
            "Camera(width={}, height={}, fx={:?}, fy={:?}, cx={:?}, cy={:?}, depth_scale={:?})",
            c.width, c.height, c.fx, c.fy, c.cx, c.cy, c.depth_scale
        )
    }
}

/// Name of a tracking state as Python sees it.
pub fn state_name(s: TrackingState) -> &'static str {
    match s {
        TrackingState::Initialising => "initialising",
        TrackingState::Tracking => "tracking",
        TrackingState::Lost => "lost",
    }
}

/// The counters as a dict (the columns of the paper's Table 1 and what went wrong).
pub fn counters_dict<'py>(py: Python<'py>, c: &Counters) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("frames", c.frames)?;
    d.set_item("motion_estimations", c.motion_estimations)?;
    d.set_item("references", c.references.clone())?;
    d.set_item("lost_frames", c.lost_frames)?;
    d.set_item("failed_corrections", c.failed_corrections)?;
    d.set_item("rejected_corrections", c.rejected_corrections)?;
    d.set_item("stale_references", c.stale_references)?;
    d.set_item("recovered_frames", c.recovered_frames)?;
    d.set_item("predicted_starts", c.predicted_starts)?;
    d.set_item("reanchors", c.reanchors)?;
    d.set_item("implausible_motions", c.implausible_motions)?;
    d.set_item("refinements", c.refinements)?;
    d.set_item("refused_refinements", c.refused_refinements)?;
    d.set_item("spread_jumps", c.spread_jumps)?;
    d.set_item("keyframe_fallbacks", c.keyframe_fallbacks)?;
    d.set_item("overlap_keyframes", c.overlap_keyframes)?;
    d.set_item("keyframe_spread_refusals", c.keyframe_spread_refusals)?;
    d.set_item("keyframe_fusions", c.keyframe_fusions)?;
    Ok(d)
}

/// A rayon pool of `threads` workers for the engine's inner loops, or None for the
/// global pool.
pub fn thread_pool(threads: Option<usize>) -> PyResult<Option<rayon::ThreadPool>> {
    match threads {
        None => Ok(None),
        Some(n) if !(1..=256).contains(&n) => Err(PyValueError::new_err(format!(
            "threads must be 1 to 256, got {n}"
        ))),
        Some(n) => rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .thread_name(|i| format!("ecvo-py-{i}"))
            .build()
            .map(Some)
            .map_err(|e| PyValueError::new_err(format!("cannot start {n} threads: {e}"))),
    }
}

/// Runs `f` in `pool`, or on the calling thread (the global pool) without one.
fn in_pool<R: Send>(pool: Option<&rayon::ThreadPool>, f: impl FnOnce() -> R + Send) -> R {
    match pool {
        Some(p) => p.install(f),
        None => f(),
    }
}

/// The camera argument: a `Camera`.
fn camera_arg(obj: &Bound<'_, PyAny>) -> PyResult<ecvo_core::Camera> {
    obj.extract::<PyCamera>().map(|c| c.inner).map_err(|_| {
        PyTypeError::new_err(format!(
            "camera must be an ecvo.Camera, got {}",
            crate::settings::type_name(obj)
        ))
    })
}

/// Frame-to-frame RGB-D tracking with multi-level error correction.
#[pyclass(module = "ecvo._ecvo", name = "Tracker")]
pub struct PyTracker {
    odo: Odometry,
    camera: ecvo_core::Camera,
    pool: Option<rayon::ThreadPool>,
    trajectory: Trajectory,
    states: Vec<TrackingState>,
    scratch_intensity: Vec<u8>,
    scratch_depth: Vec<u16>,
    last_engine_s: f64,
}

#[pymethods]
impl PyTracker {
    #[new]
    #[pyo3(signature = (camera, preset = "pc", mode = "l2", threads = None, **settings))]
    fn new(
        camera: &Bound<'_, PyAny>,
        preset: &str,
        mode: &str,
        threads: Option<usize>,
        settings: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Self> {
        let camera = camera_arg(camera)?;
        let mut kw = Kwargs::new(settings, "Tracker")?;
        let engine = EngineSettings::from_kwargs(preset, mode, &mut kw)?;
        kw.finish()?;
        let config = engine.config(camera)?;
        let odo = Odometry::new(config)
            .map_err(|e| PyValueError::new_err(format!("invalid tracker configuration: {e}")))?;
        Ok(PyTracker {
            odo,
            camera,
            pool: thread_pool(threads)?,
            trajectory: Trajectory::new(),
            states: Vec::new(),
            scratch_intensity: Vec::new(),
            scratch_depth: Vec::new(),
            last_engine_s: f64::NAN,
        })
    }

    /// Tracks one frame; returns `(pose, state)`.
    fn push<'py>(
        mut slf: PyRefMut<'py, Self>,
        timestamp: f64,
        intensity: &Bound<'py, PyAny>,
        depth: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyTuple>> {
        let py = slf.py();
        let this = &mut *slf;
        let (h, w) = (this.camera.height, this.camera.width);
        let i = plane::<u8>(intensity, "intensity", "uint8", h, w)?;
        let d = plane::<u16>(depth, "depth", "uint16", h, w)?;
        if !timestamp.is_finite() {
            return Err(PyValueError::new_err(format!(
                "timestamp must be finite, got {timestamp}"
            )));
        }
        if let Some(&last) = this.trajectory.stamps.last() {
            if !(timestamp > last) {
                return Err(PyValueError::new_err(format!(
                    "timestamp {timestamp} is not after the previous frame's ({last}); \
                     timestamps must increase"
                )));
            }
        }
        let view = FrameView {
            timestamp,
            intensity: row_major(&i, &mut this.scratch_intensity),
            depth: row_major(&d, &mut this.scratch_depth),
        };
        let odo = &mut this.odo;
        let pool = this.pool.as_ref();
        let (out, engine_s) = py.detach(|| {
            in_pool(pool, || {
                let t0 = Instant::now();
                let out = odo.push(view);
                (out, t0.elapsed().as_secs_f64())
            })
        });
        let out = out.map_err(|e| PyValueError::new_err(e.to_string()))?;
        this.last_engine_s = engine_s;
        this.trajectory.push(out.timestamp, out.pose);
        this.states.push(out.state);
        let pose = pose_array(py, &out.pose);
        (pose, state_name(out.state)).into_pyobject(py)
    }

    /// New intrinsics of the same image size for the frames pushed from now on.
    fn set_intrinsics(&mut self, camera: &Bound<'_, PyAny>) -> PyResult<()> {
        let camera = camera_arg(camera)?;
        camera
            .validate_change_from(&self.camera)
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
        self.odo
            .set_intrinsics(camera)
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
        self.camera = camera;
        Ok(())
    }

    /// The poses so far as an `(N, 8)` array of TUM rows.
    fn trajectory<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        tum_array(py, &self.trajectory)
    }

    /// The poses so far as an `(N, 4, 4)` array.
    fn poses<'py>(&self, py: Python<'py>) -> Bound<'py, numpy::PyArray3<f64>> {
        poses_array(py, &self.trajectory)
    }

    /// The timestamps so far.
    fn timestamps<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, &self.trajectory.stamps)
    }

    /// Every frame's state so far.
    fn states(&self) -> Vec<&'static str> {
        self.states.iter().map(|s| state_name(*s)).collect()
    }

    /// The tracker's counters.
    fn counters<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        counters_dict(py, self.odo.tracker().counters())
    }

    /// The current state.
    #[getter]
    fn state(&self) -> &'static str {
        state_name(self.odo.tracker().state())
    }

    /// The camera of the frames pushed next.
    #[getter]
    fn camera(&self) -> PyCamera {
        PyCamera { inner: self.camera }
    }

    fn __len__(&self) -> usize {
        self.trajectory.len()
    }

    /// Seconds the engine itself (`Odometry::push`, timed in Rust) took over the last
    /// push: what `Tracker.push` costs beyond it is the binding's
    /// (`scripts/python/bench_push.py`).
    #[getter]
    fn _last_engine_s(&self) -> f64 {
        self.last_engine_s
    }
}

/// Poses as an `(N, 4, 4)` float64 array.
pub fn poses_array<'py>(py: Python<'py>, t: &Trajectory) -> Bound<'py, numpy::PyArray3<f64>> {
    let mut data = Vec::with_capacity(t.len() * 16);
    for p in &t.poses {
        data.extend(crate::arrays::pose_matrix(p).iter().copied());
    }
    let arr = numpy::ndarray::Array3::from_shape_vec((t.len(), 4, 4), data).expect("16 a pose");
    numpy::PyArray3::from_owned_array(py, arr)
}

/// The Rust engine's own cost per frame on frames already in memory: `Odometry::push`
/// timed in Rust, for comparison with `Tracker.push` timed from Python
/// (`scripts/python/bench_push.py`). Returns seconds per frame.
#[pyfunction]
#[pyo3(signature = (camera, frames, preset = "pc", mode = "l2", threads = None, **settings))]
pub fn _engine_push_times(
    py: Python<'_>,
    camera: &Bound<'_, PyAny>,
    frames: Vec<(f64, Bound<'_, PyAny>, Bound<'_, PyAny>)>,
    preset: &str,
    mode: &str,
    threads: Option<usize>,
    settings: Option<&Bound<'_, PyDict>>,
) -> PyResult<Vec<f64>> {
    let camera = camera_arg(camera)?;
    let mut kw = Kwargs::new(settings, "_engine_push_times")?;
    let engine = EngineSettings::from_kwargs(preset, mode, &mut kw)?;
    kw.finish()?;
    let config = engine.config(camera)?;
    let mut owned = Vec::with_capacity(frames.len());
    for (t, i, d) in &frames {
        let i = plane::<u8>(i, "intensity", "uint8", camera.height, camera.width)?;
        let d = plane::<u16>(d, "depth", "uint16", camera.height, camera.width)?;
        owned.push(ecvo_io::Frame {
            index: owned.len(),
            timestamp: *t,
            intensity: i.as_array().iter().copied().collect(),
            depth: d.as_array().iter().copied().collect(),
        });
    }
    let pool = thread_pool(threads)?;
    let mut odo = Odometry::new(config).map_err(|e| PyValueError::new_err(e.to_string()))?;
    py.detach(|| {
        in_pool(pool.as_ref(), || {
            let mut times = Vec::with_capacity(owned.len());
            for f in &owned {
                let t0 = Instant::now();
                let out = odo.push(f.view());
                times.push(t0.elapsed().as_secs_f64());
                if let Err(e) = out {
                    return Err(PyValueError::new_err(e.to_string()));
                }
            }
            Ok(times)
        })
    })
}
