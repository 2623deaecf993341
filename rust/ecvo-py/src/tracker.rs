//! `ecvo.Tracker`: the sequential engine ([`Odometry`]) behind a
//! push-a-frame, get-a-pose API, the GIL released while it tracks.

use std::sync::{Mutex, MutexGuard, TryLockError};
use std::time::Instant;

use ecvo_core::nalgebra::{Matrix3, Rotation3, Translation3, UnitQuaternion, Vector3};
use ecvo_core::{Config, Counters, FrameView, Odometry, Pose, TrackingState};
use ecvo_io::Trajectory;
use numpy::{PyArray1, PyArray2, PyReadonlyArray2};
use pyo3::exceptions::{PyRuntimeError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

use crate::arrays::{plane, tum_array};
use crate::camera::PyCamera;
use crate::input::{self, Channels};
use crate::result::PyFrameResult;
use crate::settings::{EngineSettings, Kwargs};

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
    d.set_item("noise_refits", c.noise_refits)?;
    d.set_item("imu", crate::imu::counters_dict(py, &c.imu)?)?;
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

/// What a tracker holds; behind a lock so that a second thread gets a clear error.
struct Inner {
    /// None once closed.
    odo: Option<Odometry>,
    /// The configuration it was made with (for `reset`).
    config: Config,
    camera: ecvo_core::Camera,
    pool: Option<rayon::ThreadPool>,
    trajectory: Trajectory,
    states: Vec<TrackingState>,
    scratch_intensity: Vec<u8>,
    scratch_depth: Vec<u16>,
    last_engine_s: f64,
}

impl Inner {
    fn odo(&mut self) -> PyResult<&mut Odometry> {
        self.odo
            .as_mut()
            .ok_or_else(|| PyValueError::new_err("the tracker is closed"))
    }
}

/// Frame-to-frame RGB-D tracking with multi-level pose error correction (An et
/// al., WACV 2018), frame by frame: Tracker(camera, preset="pc", mode="l2",
/// threads=None, **settings).
///
/// preset picks the paper's thresholds and filter angles ("pc": Table 1, "phone":
/// Table 2); mode which correction levels run ("naive", "l1", "l2"). threads sizes
/// a private thread pool for the engine's inner loops (None: the process-wide
/// pool). The other settings are the flags of ecvo run with underscores: levels
/// ("30mm:7deg,120mm:12deg"), bilateral, normal_filter, contour_filter (bools,
/// default True), paper (bool), schedule, point_budget (str), weighting ("scalar",
/// "bivariate", "hybrid"), depth_noise ("constant", "quadratic", "fitted": the
/// default), prior ("identity", "velocity"), max_correction_distance,
/// max_fine_depth_weight, min_predicted_decrease, min_update_px (floats),
/// scale_passes, refine_every (ints), corrections ("fuse", "replace"), tracking
/// ("keyframe": the default, "chain": the paper's frame-to-frame chain),
/// keyframe_overlap, keyframe_spread (floats), lookup_depth ("bilateral": the
/// default, "raw", "filtered"), keyframe_fuse_every (int), memory_budget
/// (int, bytes: the engine refuses a configuration that needs more). With a
/// gyroscope (push_imu): imu_rotation (3x3 rotation taking IMU-frame vectors into
/// the camera frame, x right, y down, z forward; default the identity),
/// imu_time_offset (seconds added to an IMU timestamp to put it on the frames'
/// clock; default 0), gyro_noise_density (rad/s/√Hz), gyro_bias_random_walk
/// (rad/s/√s), imu_fusion (bool, default False: also fuse the gyro's rotation
/// into each believed registration) and imu_prior_term (bool, default True: the
/// gyro's rotation is also a prior term in the registration's normal equations),
/// imu_depth_time (bool, default True: a depth pushed with its own depth_timestamp
/// is turned to the intensity's time by the gyro). An
/// unknown keyword is a TypeError, a bad value a ValueError.
///
/// One tracker serves one thread at a time (another thread calling it meanwhile
/// gets a RuntimeError saying so); several trackers run in parallel on several
/// threads (the GIL is released while a frame is tracked). close() or a with block
/// frees its memory.
#[pyclass(module = "ecvo._ecvo", name = "Tracker", frozen)]
pub struct PyTracker {
    inner: Mutex<Inner>,
}

impl PyTracker {
    /// The tracker's state, or a RuntimeError when another thread is using it.
    fn lock(&self) -> PyResult<MutexGuard<'_, Inner>> {
        match self.inner.try_lock() {
            Ok(g) => Ok(g),
            Err(TryLockError::Poisoned(p)) => Ok(p.into_inner()),
            Err(TryLockError::WouldBlock) => Err(PyRuntimeError::new_err(
                "this Tracker is in use by another thread: a Tracker serves one thread at \
                 a time (give each thread its own Tracker, or guard it with a \
                 threading.Lock)",
            )),
        }
    }
}

/// A pose from a 4x4 (rigid) or the rotation of a 3x3 array-like, checked.
pub(crate) fn rigid(obj: &Bound<'_, PyAny>, name: &str, rotation_only: bool) -> PyResult<Pose> {
    let n = if rotation_only { 3 } else { 4 };
    let arr = obj
        .py()
        .import("numpy")?
        .call_method1("asarray", (obj, "float64"))
        .map_err(|_| PyTypeError::new_err(format!("{name} must be a {n}x{n} array of floats")))?;
    let arr: PyReadonlyArray2<'_, f64> = arr
        .extract()
        .map_err(|_| PyValueError::new_err(format!("{name} must be a {n}x{n} array")))?;
    let a = arr.as_array();
    if a.shape() != [n, n] || a.iter().any(|x| !x.is_finite()) {
        return Err(PyValueError::new_err(format!(
            "{name} must be a {n}x{n} array of finite floats, got shape {:?}",
            a.shape()
        )));
    }
    let r = Matrix3::from_fn(|i, j| a[(i, j)]);
    let orthonormal = (r.transpose() * r - Matrix3::identity()).abs().max() < 1e-6;
    if !orthonormal || r.determinant() < 0.0 {
        return Err(PyValueError::new_err(format!(
            "{name}: the rotation part is not a rotation (RᵀR ≠ I or det R < 0)"
        )));
    }
    if !rotation_only
        && (a[(3, 0)] != 0.0 || a[(3, 1)] != 0.0 || a[(3, 2)] != 0.0 || a[(3, 3)] != 1.0)
    {
        return Err(PyValueError::new_err(format!(
            "{name}: the last row must be [0, 0, 0, 1]"
        )));
    }
    let t = if rotation_only {
        Vector3::zeros()
    } else {
        Vector3::new(a[(0, 3)], a[(1, 3)], a[(2, 3)])
    };
    let q = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(r));
    Ok(Pose::from_parts(Translation3::from(t), q))
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
        let imu = crate::imu::calibration(&mut kw)?;
        kw.finish()?;
        let mut config = engine.config(camera)?;
        config.imu = imu;
        let odo = Odometry::new(config.clone()).map_err(|e| {
            let hint = match e {
                ecvo_core::Error::MemoryBudget { .. } => {
                    "; Tracker(..., memory_budget=BYTES) sets the budget"
                }
                _ => "",
            };
            PyValueError::new_err(format!("invalid tracker configuration: {e}{hint}"))
        })?;
        Ok(PyTracker {
            inner: Mutex::new(Inner {
                odo: Some(odo),
                config,
                camera,
                pool: thread_pool(threads)?,
                trajectory: Trajectory::new(),
                states: Vec::new(),
                scratch_intensity: Vec::new(),
                scratch_depth: Vec::new(),
                last_engine_s: f64::NAN,
            }),
        })
    }

    /// Tracks one frame and returns its FrameResult (which unpacks as (pose,
    /// state)). Timestamps (seconds) must increase.
    ///
    /// intensity: grey (height, width) uint8; colour (height, width, 3 or 4) uint8 in
    /// the channel order channels ("rgb" or "bgr"; alpha ignored), converted to grey
    /// as 0.299 R + 0.587 G + 0.114 B rounded (as read_sequence); or grey float32 /
    /// float64 in [0, 1] (Open3D's RGBDImage.color). depth: uint16 raw units (0: no
    /// measurement) or float32 / float64 metres (NaN or 0: no measurement), rounded
    /// to the camera's units (1 / depth_scale m; exact for metres that came from raw
    /// / depth_scale). Any object numpy.asarray takes works (the buffer protocol:
    /// open3d.geometry.Image, memoryview); an object with .color and .depth (an
    /// Open3D RGBDImage) may stand for both planes. A masked array's masked pixels
    /// have no depth. C-contiguous uint8 grey and uint16 depth are read in place,
    /// everything else converted once into a reused buffer; the arrays must not be
    /// written by another thread during the call.
    ///
    /// initial_guess: a 4x4 camera-to-world pose guess for this frame (as the poses
    /// returned), or rotation_guess: a 3x3 rotation of this camera relative to the
    /// previous frame's (a gyroscope's), the translation then predicted from the
    /// velocity. Registration starts from the identity and from the guess, and the
    /// better start wins at the coarsest level; ignored on the first frame.
    ///
    /// depth_timestamp: when the depth image was taken (seconds, the frames' clock),
    /// if not with the intensity: with gyroscope samples pushed that cover the two
    /// times, the depth is turned to the intensity's time by the gyro's rotation
    /// between them (imu_depth_time=False turns this off).
    ///
    /// A wrong type or dtype is a TypeError; a wrong shape, an out-of-range value,
    /// a non-increasing timestamp or a closed tracker a ValueError.
    #[pyo3(signature = (timestamp, intensity, depth = None, channels = "rgb", initial_guess = None, rotation_guess = None, depth_timestamp = None))]
    fn push<'py>(
        &self,
        py: Python<'py>,
        timestamp: f64,
        intensity: &Bound<'py, PyAny>,
        depth: Option<&Bound<'py, PyAny>>,
        channels: &str,
        initial_guess: Option<&Bound<'py, PyAny>>,
        rotation_guess: Option<&Bound<'py, PyAny>>,
        depth_timestamp: Option<f64>,
    ) -> PyResult<PyFrameResult> {
        let mut guard = self.lock()?;
        let this = &mut *guard;
        this.odo()?;
        let channels = Channels::parse(channels)?;
        // An RGBDImage (Open3D) carries both planes.
        let (intensity, depth) = match depth {
            Some(d) => (intensity.clone(), d.clone()),
            None if intensity.hasattr("color")? && intensity.hasattr("depth")? => {
                (intensity.getattr("color")?, intensity.getattr("depth")?)
            }
            None => {
                return Err(PyTypeError::new_err(
                    "push() needs depth (or an RGBDImage-like object with .color and .depth)",
                ));
            }
        };
        let (h, w) = (this.camera.height, this.camera.width);
        let (i, mask) = input::intensity(&intensity, channels, h, w, &mut this.scratch_intensity)?;
        let d = input::depth(
            &depth,
            this.camera.depth_scale,
            h,
            w,
            mask,
            &mut this.scratch_depth,
        )?;
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
        let guess = match (initial_guess, rotation_guess) {
            (Some(_), Some(_)) => {
                return Err(PyValueError::new_err(
                    "give initial_guess or rotation_guess, not both",
                ));
            }
            (Some(g), None) => Some((rigid(g, "initial_guess", false)?, false)),
            (None, Some(r)) => Some((rigid(r, "rotation_guess", true)?, true)),
            (None, None) => None,
        };
        let odo = this.odo.as_mut().expect("checked above");
        if let (Some((g, rotation_only)), Some(prev)) = (guess, odo.tracker().previous()) {
            let motion = if rotation_only {
                // The rotation from the outside, the translation from the prediction.
                let t = odo
                    .tracker()
                    .prior_for(timestamp)
                    .map_or(Translation3::identity(), |p| p.translation);
                Pose::from_parts(t, g.rotation)
            } else {
                prev.pose.inverse() * g
            };
            odo.set_guess(motion);
        }
        let view = FrameView {
            timestamp,
            intensity: i.values(&mut this.scratch_intensity),
            depth: d.values(&mut this.scratch_depth),
        };
        let pool = this.pool.as_ref();
        let (out, engine_s) = py.detach(|| {
            in_pool(pool, || {
                let t0 = Instant::now();
                let out = match depth_timestamp {
                    Some(d) => odo.push_with_depth_time(view, d),
                    None => odo.push(view),
                };
                (out, t0.elapsed().as_secs_f64())
            })
        });
        let out = out.map_err(|e| PyValueError::new_err(e.to_string()))?;
        this.last_engine_s = engine_s;
        this.trajectory.push(out.timestamp, out.pose);
        this.states.push(out.state);
        Ok(PyFrameResult::new(py, &out))
    }

    /// Gyroscope samples for the frames pushed after this call: timestamps (N,)
    /// seconds on the IMU's clock, rates (N, 3) rad/s in the IMU's frame, in time
    /// order. Each frame's registration then starts from the gyro's rotation since
    /// the previous frame (less its bias, estimated as it goes) besides the
    /// identity. A sample not after the last one taken is dropped and counted
    /// (counters()["imu"]["refused"]); samples that do not cover a frame leave it
    /// tracked without them (counted "late" or "missing"), never an error. A
    /// non-finite value refuses the whole batch with a ValueError; a wrong shape
    /// is a ValueError.
    fn push_imu(&self, timestamps: &Bound<'_, PyAny>, rates: &Bound<'_, PyAny>) -> PyResult<()> {
        let samples = crate::imu::samples(timestamps, rates)?;
        let mut this = self.lock()?;
        this.odo()?
            .push_imu(&samples)
            .map_err(|e| PyValueError::new_err(e.to_string()))
    }

    /// New intrinsics of the same image size (a zoom) for the frames pushed from
    /// now on.
    fn set_intrinsics(&self, camera: &Bound<'_, PyAny>) -> PyResult<()> {
        let camera = camera_arg(camera)?;
        let mut this = self.lock()?;
        camera
            .validate_change_from(&this.camera)
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
        this.odo()?
            .set_intrinsics(camera)
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
        this.camera = camera;
        Ok(())
    }

    /// Forgets every frame: the next one starts a new trajectory at the identity,
    /// with the same settings and the current camera. Reopens a closed tracker.
    fn reset(&self) -> PyResult<()> {
        let mut this = self.lock()?;
        this.odo = None;
        let mut config = this.config.clone();
        config.camera = this.camera;
        this.odo = Some(Odometry::new(config).map_err(|e| PyValueError::new_err(e.to_string()))?);
        this.trajectory = Trajectory::new();
        this.states.clear();
        this.last_engine_s = f64::NAN;
        Ok(())
    }

    /// Frees the engine's memory; pushing afterwards is a ValueError. The
    /// trajectory stays readable. Idempotent.
    fn close(&self) -> PyResult<()> {
        let mut this = self.lock()?;
        this.odo = None;
        this.scratch_intensity = Vec::new();
        this.scratch_depth = Vec::new();
        Ok(())
    }

    /// True once closed.
    #[getter]
    fn closed(&self) -> PyResult<bool> {
        Ok(self.lock()?.odo.is_none())
    }

    fn __enter__(slf: Py<Self>) -> Py<Self> {
        slf
    }

    #[pyo3(signature = (*_args))]
    fn __exit__(&self, _args: &Bound<'_, PyTuple>) -> PyResult<bool> {
        self.close()?;
        Ok(false)
    }

    /// The poses so far as an (N, 8) float64 array of TUM rows [t, tx, ty, tz, qx,
    /// qy, qz, qw].
    fn trajectory<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        Ok(tum_array(py, &self.lock()?.trajectory))
    }

    /// The poses so far as an (N, 4, 4) float64 array.
    fn poses<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, numpy::PyArray3<f64>>> {
        Ok(poses_array(py, &self.lock()?.trajectory))
    }

    /// The timestamps so far (seconds).
    fn timestamps<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        Ok(PyArray1::from_slice(py, &self.lock()?.trajectory.stamps))
    }

    /// Every frame's state so far.
    fn states(&self) -> PyResult<Vec<&'static str>> {
        Ok(self.lock()?.states.iter().map(|s| state_name(*s)).collect())
    }

    /// The tracker's counters (the paper's Table 1 and what went wrong).
    fn counters<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let mut this = self.lock()?;
        counters_dict(py, this.odo()?.tracker().counters())
    }

    /// The state after the last frame ("initialising" before the first).
    #[getter]
    fn state(&self) -> PyResult<&'static str> {
        let mut this = self.lock()?;
        Ok(state_name(this.odo()?.tracker().state()))
    }

    /// The camera of the frames pushed next.
    #[getter]
    fn camera(&self) -> PyResult<PyCamera> {
        Ok(PyCamera {
            inner: self.lock()?.camera,
        })
    }

    fn __len__(&self) -> PyResult<usize> {
        Ok(self.lock()?.trajectory.len())
    }

    /// Seconds the engine itself (Odometry::push, timed in Rust) took over the last
    /// push: what Tracker.push costs beyond it is the binding's
    /// (scripts/python/bench_push.py).
    #[getter]
    fn _last_engine_s(&self) -> PyResult<f64> {
        Ok(self.lock()?.last_engine_s)
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

/// Seconds per frame of the Rust engine's own Odometry::push on these frames
/// (for scripts/python/bench_push.py).
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
            depth_timestamp: *t,
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
