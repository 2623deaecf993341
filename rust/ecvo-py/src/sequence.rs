//! `ecvo.read_sequence` and `ecvo.run_sequence`: recorded sequences from Python, and
//! tracking one the way `ecvo run` does.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use ecvo_core::{FrameOutput, TrackingState};
use ecvo_io::{Sequence, Trajectory};
use ecvo_pipeline::{Admission, Pipeline, PipelineOptions, PushStatus};
use numpy::ndarray::{Array2, Array3};
use numpy::{PyArray1, PyArray2, PyArray3};
use pyo3::exceptions::{PyIndexError, PyRuntimeError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PySlice, PySliceMethods, PyTuple};

use crate::arrays::tum_array;
use crate::camera::PyCamera;
use crate::eval::ate_dict;
use crate::settings::{EngineSettings, Kwargs, type_name};
use crate::tracker::{counters_dict, poses_array, state_name};

/// Decoded frames the reader thread keeps ahead of the pipeline (as `ecvo run`).
const PREFETCH: usize = 4;
/// Capacity of the pipeline's output channel (as `ecvo run`).
const OUTPUT_QUEUE: usize = 1024;

/// The `camera` argument of the sequence functions: a Camera, or a camera.json path.
fn camera_override(obj: Option<&Bound<'_, PyAny>>) -> PyResult<Option<ecvo_core::Camera>> {
    let Some(obj) = obj else { return Ok(None) };
    if let Ok(c) = obj.extract::<PyCamera>() {
        return Ok(Some(c.inner));
    }
    match obj.extract::<PathBuf>() {
        Ok(path) => Ok(Some(
            ecvo_io::load_camera_json(&path).map_err(crate::io_err)?,
        )),
        Err(_) => Err(PyTypeError::new_err(format!(
            "camera must be an ecvo.Camera or the path of a camera.json, got {}",
            type_name(obj)
        ))),
    }
}

fn open(
    path: &PathBuf,
    camera: Option<ecvo_core::Camera>,
    frame_step: usize,
) -> PyResult<Sequence> {
    if frame_step == 0 {
        return Err(PyValueError::new_err("frame_step must be at least 1"));
    }
    Ok(Sequence::open(path, camera)
        .map_err(crate::io_err)?
        .every_nth(frame_step))
}

/// A recorded RGB-D sequence (read_sequence): seq[i] decodes frame i as
/// (timestamp, intensity, depth): intensity (height, width) uint8 grey, or (height,
/// width, 3) uint8 RGB when opened with colour=True; depth (height, width) uint16
/// raw units. seq[a:b:c] is a Sequence of those frames; iterating yields every
/// frame in order, decoded when reached.
#[pyclass(module = "ecvo._ecvo", name = "Sequence", frozen)]
pub struct PySequence {
    inner: Arc<Sequence>,
    /// The frames of `inner` this sequence holds, in order (a slice picks some).
    indices: Vec<usize>,
    /// Frames decode as colour `(H, W, 3)` RGB instead of grey.
    colour: bool,
}

impl PySequence {
    fn len(&self) -> usize {
        self.indices.len()
    }

    fn frame<'py>(&self, py: Python<'py>, k: usize) -> PyResult<Bound<'py, PyTuple>> {
        let index = self.indices[k];
        let (h, w) = (self.inner.camera().height, self.inner.camera().width);
        let shape =
            |what: &str| PyRuntimeError::new_err(format!("decoded {what} has the wrong size"));
        if self.colour {
            let (t, rgb, depth) = py
                .detach(|| self.inner.load_colour_frame(index))
                .map_err(crate::io_err)?;
            let rgb = Array3::from_shape_vec((h, w, 3), rgb).map_err(|_| shape("colour"))?;
            let depth = Array2::from_shape_vec((h, w), depth).map_err(|_| shape("depth"))?;
            return (
                t,
                PyArray3::from_owned_array(py, rgb),
                PyArray2::from_owned_array(py, depth),
            )
                .into_pyobject(py);
        }
        let frame = py
            .detach(|| self.inner.load_frame(index))
            .map_err(crate::io_err)?;
        let intensity =
            Array2::from_shape_vec((h, w), frame.intensity).map_err(|_| shape("intensity"))?;
        let depth = Array2::from_shape_vec((h, w), frame.depth).map_err(|_| shape("depth"))?;
        (
            frame.timestamp,
            PyArray2::from_owned_array(py, intensity),
            PyArray2::from_owned_array(py, depth),
        )
            .into_pyobject(py)
    }
}

#[pymethods]
impl PySequence {
    fn __len__(&self) -> usize {
        self.len()
    }

    /// Frame `key` (negative counts from the end), decoded; a slice is a Sequence of
    /// those frames (decoded when read).
    fn __getitem__<'py>(
        &self,
        py: Python<'py>,
        key: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        if let Ok(slice) = key.cast::<PySlice>() {
            let ix = slice.indices(self.len() as isize)?;
            let mut indices = Vec::with_capacity(ix.slicelength);
            let mut i = ix.start;
            for _ in 0..ix.slicelength {
                indices.push(self.indices[i as usize]);
                i += ix.step;
            }
            let sub = PySequence {
                inner: self.inner.clone(),
                indices,
                colour: self.colour,
            };
            return Ok(Bound::new(py, sub)?.into_any());
        }
        let index: isize = key.extract().map_err(|_| {
            PyTypeError::new_err(format!(
                "Sequence indices must be integers or slices, not {}",
                type_name(key)
            ))
        })?;
        let n = self.len() as isize;
        let k = if index < 0 { index + n } else { index };
        if !(0..n).contains(&k) {
            return Err(PyIndexError::new_err(format!(
                "frame {index} is out of range for a sequence of {n} frames"
            )));
        }
        Ok(self.frame(py, k as usize)?.into_any())
    }

    /// The frames in order, each decoded when it is reached.
    fn __iter__(slf: Py<Self>) -> PySequenceIter {
        PySequenceIter {
            sequence: slf,
            next: std::sync::atomic::AtomicUsize::new(0),
        }
    }

    /// The sequence's camera.
    #[getter]
    fn camera(&self) -> PyCamera {
        PyCamera {
            inner: *self.inner.camera(),
        }
    }

    /// The frames' timestamps (seconds).
    #[getter]
    fn timestamps<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let t = self.inner.timestamps();
        let picked: Vec<f64> = self.indices.iter().map(|&k| t[k]).collect();
        PyArray1::from_vec(py, picked)
    }

    /// The whole recording's ground truth as (N, 8) TUM rows, or None.
    #[getter]
    fn groundtruth<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray2<f64>>> {
        self.inner.groundtruth().map(|g| tum_array(py, g))
    }

    /// The sequence folder.
    #[getter]
    fn path(&self) -> PathBuf {
        self.inner.dir().to_path_buf()
    }

    /// Whether frames decode as colour.
    #[getter]
    fn colour(&self) -> bool {
        self.colour
    }

    fn __repr__(&self) -> String {
        format!(
            "Sequence({:?}, {} frames, {}x{}{})",
            self.inner.dir().display().to_string(),
            self.len(),
            self.inner.camera().width,
            self.inner.camera().height,
            if self.colour { ", colour" } else { "" }
        )
    }
}

/// An iterator over a [`PySequence`]'s frames.
#[pyclass(module = "ecvo._ecvo", name = "SequenceIterator", frozen)]
pub struct PySequenceIter {
    sequence: Py<PySequence>,
    next: std::sync::atomic::AtomicUsize,
}

#[pymethods]
impl PySequenceIter {
    fn __iter__(slf: Py<Self>) -> Py<Self> {
        slf
    }

    fn __next__<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyTuple>>> {
        use std::sync::atomic::Ordering;
        let seq = self.sequence.get();
        let k = self.next.fetch_add(1, Ordering::Relaxed);
        if k >= seq.len() {
            self.next.store(seq.len(), Ordering::Relaxed);
            return Ok(None);
        }
        seq.frame(py, k).map(Some)
    }
}

/// Opens a TUM-layout (with camera.json) or ICL-NUIM sequence folder. camera (a
/// Camera or a camera.json path) overrides the folder's; frame_step keeps frames 0,
/// n, 2n, ...; max_frames the first so many; colour=True decodes intensity as
/// (height, width, 3) RGB. A missing folder is a FileNotFoundError, a malformed one
/// a ValueError.
#[pyfunction]
#[pyo3(signature = (path, camera = None, frame_step = 1, max_frames = None, colour = false))]
pub fn read_sequence(
    path: PathBuf,
    camera: Option<&Bound<'_, PyAny>>,
    frame_step: usize,
    max_frames: Option<usize>,
    colour: bool,
) -> PyResult<PySequence> {
    let inner = open(&path, camera_override(camera)?, frame_step)?;
    let len = max_frames.map_or(inner.len(), |m| m.min(inner.len()));
    Ok(PySequence {
        inner: Arc::new(inner),
        indices: (0..len).collect(),
        colour,
    })
}

/// What one run gave.
struct Run {
    outputs: Vec<FrameOutput>,
    counters: ecvo_core::Counters,
    skipped: u64,
    wall_s: f64,
}

/// Tracks the first `n` frames of `sequence` as `ecvo run` does (its engine.rs,
/// without the point cloud): the offline pipeline, frames decoded ahead, repeated
/// frames and non-increasing timestamps skipped.
fn track(
    sequence: &Sequence,
    config: ecvo_core::Config,
    threads: usize,
    n: usize,
    mut imu: Option<ecvo_io::imu::ImuFeed>,
) -> PyResult<Run> {
    let err = |what: String| PyValueError::new_err(what);
    let pipeline = Pipeline::new(
        config,
        PipelineOptions {
            threads,
            admission: Admission::Offline,
            geometry: None,
            keep_trajectory: false,
            output_queue: Some(OUTPUT_QUEUE),
            ..PipelineOptions::default()
        },
    )
    .map_err(|e| err(format!("invalid tracker configuration: {e}")))?;
    let rx = pipeline
        .outputs()
        .ok_or_else(|| PyRuntimeError::new_err("the pipeline has no output channel"))?;
    let start = Instant::now();
    let mut outputs: Vec<FrameOutput> = Vec::with_capacity(n);
    let mut reader = sequence.reader(Some(n), PREFETCH);
    #[allow(clippy::while_let_on_iterator)]
    while let Some(item) = reader.next() {
        let frame = item.map_err(crate::io_err)?;
        if let Some(f) = &mut imu {
            pipeline
                .push_imu(f.before_frame(&frame))
                .map_err(|e| err(format!("IMU samples: {e}")))?;
        }
        // As `ecvo run`: the depth's own time, turned to the intensity's by the gyro.
        match pipeline.push_view_with_depth_time(frame.view(), frame.depth_timestamp) {
            Ok(PushStatus::Repeated) | Err(ecvo_pipeline::Error::TimestampNotIncreasing { .. }) => {
            }
            Ok(_) => {}
            Err(e) => {
                return Err(err(format!(
                    "frame {} (timestamp {}): {e}",
                    frame.index, frame.timestamp
                )));
            }
        }
        reader.recycle(frame);
        while let Ok(t) = rx.try_recv() {
            outputs.push(t.output);
        }
    }
    pipeline.close_input();
    outputs.extend(rx.iter().map(|t| t.output));
    drop(rx);
    let summary = pipeline
        .finish()
        .map_err(|e| PyRuntimeError::new_err(format!("the tracking pipeline failed: {e}")))?;
    let skipped = summary.stats.repeated_frames + summary.stats.timestamps_rejected;
    for (k, o) in outputs.iter().enumerate() {
        if o.index != k as u64 {
            return Err(err(format!("frame {k} could not be prepared")));
        }
    }
    if outputs.len() as u64 + skipped != n as u64 {
        return Err(err(format!(
            "frame {} could not be prepared",
            outputs.len()
        )));
    }
    Ok(Run {
        outputs,
        counters: summary.stats.counters.clone(),
        skipped,
        wall_s: start.elapsed().as_secs_f64(),
    })
}

/// The IMU stream `ecvo run` would use for the sequence in `dir` (`imu`: None for
/// its `imu.txt` if any, False for none, a path for that file), its calibration put
/// in `config`.
fn imu_feed(
    dir: &std::path::Path,
    imu: Option<&Bound<'_, PyAny>>,
    config: &mut ecvo_core::Config,
) -> PyResult<Option<ecvo_io::imu::ImuFeed>> {
    let path = match imu {
        None => {
            let p = dir.join(ecvo_io::imu::IMU_FILE);
            if !p.exists() {
                return Ok(None);
            }
            p
        }
        Some(v) if v.is_instance_of::<pyo3::types::PyBool>() => {
            if v.extract::<bool>()? {
                return Err(PyValueError::new_err(
                    "run_sequence(): imu must be None (the sequence's imu.txt if any), \
                     False (none) or a path",
                ));
            }
            return Ok(None);
        }
        Some(v) => v.extract::<PathBuf>().map_err(|_| {
            PyTypeError::new_err("run_sequence(): imu must be None, False or a path")
        })?,
    };
    let samples = ecvo_io::imu::load_imu(&path).map_err(crate::io_err)?;
    if let Some((c, _)) = ecvo_io::imu::find_calibration(&path, dir).map_err(crate::io_err)? {
        config.imu = c;
    }
    Ok(Some(ecvo_io::imu::ImuFeed::new(
        samples.iter().map(|s| s.gyro()).collect(),
        config.imu.time_offset,
    )))
}

/// Tracks a recorded sequence exactly as ``ecvo run`` does (the same settings
/// give bit for bit the same poses): frames decoded ahead, the filter and tracker
/// stages on ``threads`` threads; bit-identical repeated frames and non-increasing
/// timestamps are skipped. Settings as for :class:`Tracker`, and imu: None (the
/// folder's imu.txt if it has one, as ecvo run), False (none, as --no-imu) or the
/// path of an imu.txt (as --imu), its calibration from the camera.json beside it
/// or the folder's.
#[pyfunction]
#[pyo3(signature = (path, preset = "pc", mode = "l2", camera = None, max_frames = None, threads = 2, frame_step = 1, **settings))]
pub fn run_sequence<'py>(
    py: Python<'py>,
    path: PathBuf,
    preset: &str,
    mode: &str,
    camera: Option<&Bound<'py, PyAny>>,
    max_frames: Option<usize>,
    threads: usize,
    frame_step: usize,
    settings: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
    let mut kw = Kwargs::new(settings, "run_sequence")?;
    let engine = EngineSettings::from_kwargs(preset, mode, &mut kw)?;
    let imu_arg = kw.take_any("imu")?;
    kw.finish()?;
    if !(1..=256).contains(&threads) {
        return Err(PyValueError::new_err(format!(
            "threads must be 1 to 256, got {threads}"
        )));
    }
    let sequence = open(&path, camera_override(camera)?, frame_step)?;
    let mut config = engine.config(*sequence.camera())?;
    let imu = imu_feed(&path, imu_arg.as_ref(), &mut config)?;
    let n = max_frames.map_or(sequence.len(), |m| m.min(sequence.len()));
    let run = py.detach(|| track(&sequence, config, threads, n, imu))?;
    if run.outputs.is_empty() {
        return Err(PyValueError::new_err(format!(
            "{}: no frame was tracked",
            path.display()
        )));
    }
    let mut trajectory = Trajectory::with_capacity(run.outputs.len());
    for o in &run.outputs {
        trajectory.push(o.timestamp, o.pose);
    }
    let d = PyDict::new(py);
    d.set_item("trajectory", tum_array(py, &trajectory))?;
    d.set_item("poses", poses_array(py, &trajectory))?;
    d.set_item(
        "states",
        run.outputs
            .iter()
            .map(|o| state_name(o.state))
            .collect::<Vec<_>>(),
    )?;
    d.set_item(
        "lost_frame_indices",
        run.outputs
            .iter()
            .filter(|o| o.state == TrackingState::Lost)
            .map(|o| o.index)
            .collect::<Vec<_>>(),
    )?;
    d.set_item("counters", counters_dict(py, &run.counters)?)?;
    d.set_item("skipped_frames", run.skipped)?;
    let ate = match sequence.groundtruth() {
        Some(gt) => match ecvo_io::eval::ate(gt, &trajectory) {
            Ok(a) => Some(ate_dict(py, &a)?),
            Err(_) => None,
        },
        None => None,
    };
    d.set_item("ate", ate)?;
    d.set_item(
        "camera",
        PyCamera {
            inner: *sequence.camera(),
        },
    )?;
    d.set_item("wall_time_s", run.wall_s)?;
    d.set_item("threads", threads)?;
    Ok(d)
}
