//! `ecvo.read_sequence` and `ecvo.run_sequence`: recorded sequences from Python, and
//! tracking one the way `ecvo run` does.

use std::path::PathBuf;
use std::time::Instant;

use ecvo_core::{FrameOutput, TrackingState};
use ecvo_io::{Sequence, Trajectory};
use ecvo_pipeline::{Admission, Pipeline, PipelineOptions, PushStatus};
use numpy::ndarray::Array2;
use numpy::{PyArray1, PyArray2};
use pyo3::exceptions::{PyIndexError, PyRuntimeError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

use crate::arrays::tum_array;
use crate::eval::ate_dict;
use crate::settings::{EngineSettings, Kwargs, type_name};
use crate::tracker::{PyCamera, counters_dict, poses_array, state_name};

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

/// A recorded RGB-D sequence: a sequence of `(timestamp, intensity, depth)` frames.
#[pyclass(module = "ecvo._ecvo", name = "Sequence", frozen)]
pub struct PySequence {
    inner: Sequence,
    len: usize,
}

#[pymethods]
impl PySequence {
    fn __len__(&self) -> usize {
        self.len
    }

    /// Frame `index` (negative counts from the end), decoded.
    fn __getitem__<'py>(&self, py: Python<'py>, index: isize) -> PyResult<Bound<'py, PyTuple>> {
        let n = self.len as isize;
        let k = if index < 0 { index + n } else { index };
        if !(0..n).contains(&k) {
            return Err(PyIndexError::new_err(format!(
                "frame {index} is out of range for a sequence of {n} frames"
            )));
        }
        let frame = py
            .detach(|| self.inner.load_frame(k as usize))
            .map_err(crate::io_err)?;
        let (h, w) = (self.inner.camera().height, self.inner.camera().width);
        let shape =
            |what: &str| PyRuntimeError::new_err(format!("decoded {what} has the wrong size"));
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

    /// The frames' timestamps.
    #[getter]
    fn timestamps<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let t = self.inner.timestamps();
        PyArray1::from_slice(py, &t[..self.len])
    }

    /// The ground truth as an `(N, 8)` array of TUM rows, or None.
    #[getter]
    fn groundtruth<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray2<f64>>> {
        self.inner.groundtruth().map(|g| tum_array(py, g))
    }

    /// The sequence folder.
    #[getter]
    fn path(&self) -> PathBuf {
        self.inner.dir().to_path_buf()
    }

    fn __repr__(&self) -> String {
        format!(
            "Sequence({:?}, {} frames, {}x{})",
            self.inner.dir().display().to_string(),
            self.len,
            self.inner.camera().width,
            self.inner.camera().height
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
        if k >= seq.len {
            self.next.store(seq.len, Ordering::Relaxed);
            return Ok(None);
        }
        seq.__getitem__(py, k as isize).map(Some)
    }
}

/// Opens a recorded sequence (TUM layout with camera.json, or ICL-NUIM).
#[pyfunction]
#[pyo3(signature = (path, camera = None, frame_step = 1, max_frames = None))]
pub fn read_sequence(
    path: PathBuf,
    camera: Option<&Bound<'_, PyAny>>,
    frame_step: usize,
    max_frames: Option<usize>,
) -> PyResult<PySequence> {
    let inner = open(&path, camera_override(camera)?, frame_step)?;
    let len = max_frames.map_or(inner.len(), |m| m.min(inner.len()));
    Ok(PySequence { inner, len })
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
        match pipeline.push_view(frame.view()) {
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

/// Tracks a recorded sequence as `ecvo run SEQ` does and returns a dict with the
/// trajectory, the states, the counters and the ATE against the ground truth.
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
    kw.finish()?;
    if !(1..=256).contains(&threads) {
        return Err(PyValueError::new_err(format!(
            "threads must be 1 to 256, got {threads}"
        )));
    }
    let sequence = open(&path, camera_override(camera)?, frame_step)?;
    let config = engine.config(*sequence.camera())?;
    let n = max_frames.map_or(sequence.len(), |m| m.min(sequence.len()));
    let run = py.detach(|| track(&sequence, config, threads, n))?;
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
