//! # ecvo-py
//!
//! The `ecvo` Python package's native module (`ecvo._ecvo`): the RGB-D tracker of
//! An et al. (WACV 2018) from numpy. `Tracker` pushes frames through the sequential
//! engine (`ecvo_core::Odometry`) with the GIL released; `run_sequence` tracks a
//! recorded sequence exactly as `ecvo run` does (the offline pipeline, the same
//! settings in the same order), so the poses are bit for bit the command's;
//! `read_sequence` decodes frames into numpy arrays; `ate` is ecvo-io's ATE, the one
//! `ecvo eval` prints. The Python side (`python/ecvo/`) re-exports it with type
//! stubs. Built with maturin (`pip install rust/ecvo-py`); tested by pytest
//! (`scripts/python/test-python.sh`).

use pyo3::exceptions::{PyFileNotFoundError, PyOSError, PyValueError};
use pyo3::prelude::*;

mod arrays;
mod camera;
mod eval;
mod imu;
mod input;
mod result;
mod sequence;
mod settings;
mod tracker;

/// An ecvo-io error as the Python exception that fits it.
pub(crate) fn io_err(e: ecvo_io::Error) -> PyErr {
    let text = e.to_string();
    match &e {
        ecvo_io::Error::Io { source, .. } if source.kind() == std::io::ErrorKind::NotFound => {
            PyFileNotFoundError::new_err(text)
        }
        ecvo_io::Error::Io { .. } => PyOSError::new_err(text),
        _ => PyValueError::new_err(text),
    }
}

#[pymodule]
fn _ecvo(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<camera::PyCamera>()?;
    m.add_class::<tracker::PyTracker>()?;
    m.add_class::<result::PyFrameResult>()?;
    m.add_class::<sequence::PySequence>()?;
    m.add_class::<sequence::PySequenceIter>()?;
    m.add_function(wrap_pyfunction!(sequence::read_sequence, m)?)?;
    m.add_function(wrap_pyfunction!(sequence::run_sequence, m)?)?;
    m.add_function(wrap_pyfunction!(eval::ate, m)?)?;
    m.add_function(wrap_pyfunction!(tracker::_engine_push_times, m)?)?;
    m.add("simd_path", ecvo_core::simd_path())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
