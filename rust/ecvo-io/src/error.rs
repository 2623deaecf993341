//! The error type of ecvo-io: every variant that comes from a file names it, and
//! errors in text files also give the 1-based line number.

use std::fmt;
use std::path::{Path, PathBuf};

use crate::files::shown_path;

/// Anything that can go wrong while reading or writing ecvo's files.
///
/// Messages always name the file involved and, for text files, the line number.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A file or folder could not be opened, read, created or written.
    #[error("{}: {source}", shown_path(path))]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// The underlying I/O error.
        #[source]
        source: std::io::Error,
    },
    /// A line of a text file (list, trajectory, associations) could not be parsed.
    #[error("{}:{line}: {msg}", shown_path(path))]
    Parse {
        /// The text file.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// What is wrong with the line.
        msg: String,
    },
    /// Timestamps of a list or trajectory file are not strictly increasing.
    #[error(
        "{}:{line}: timestamp {} is not after the previous one ({}); \
         timestamps must be strictly increasing",
        shown_path(path),
        ecvo_core::Num(*timestamp),
        ecvo_core::Num(*previous)
    )]
    NonMonotonic {
        /// The text file.
        path: PathBuf,
        /// 1-based line number of the offending timestamp.
        line: usize,
        /// The offending timestamp.
        timestamp: f64,
        /// The timestamp before it.
        previous: f64,
    },
    /// A PNG could not be decoded or encoded, or has the wrong bit depth or colour type.
    #[error("{}: {msg}", shown_path(path))]
    Image {
        /// The PNG file.
        path: PathBuf,
        /// What is wrong with it.
        msg: String,
    },
    /// A PNG does not have the size of the camera.
    #[error(
        "{}: image is {width}x{height} but the camera is {expected_width}x{expected_height}",
        shown_path(path)
    )]
    ImageSize {
        /// The PNG file.
        path: PathBuf,
        /// Width found in the file.
        width: usize,
        /// Height found in the file.
        height: usize,
        /// Width of the camera.
        expected_width: usize,
        /// Height of the camera.
        expected_height: usize,
    },
    /// A camera file is malformed, misses a field, or holds unusable intrinsics.
    #[error("{}: invalid camera: {msg}", shown_path(path))]
    Camera {
        /// The camera file.
        path: PathBuf,
        /// What is wrong with it.
        msg: String,
    },
    /// A sequence folder has no camera file and no camera was given.
    #[error(
        "{}: no camera.json in the sequence folder; pass a camera (a camera.json file \
         or a preset such as fr1, fr2, fr3, icl)",
        shown_path(dir)
    )]
    MissingCamera {
        /// The sequence folder.
        dir: PathBuf,
    },
    /// A folder is neither a TUM RGB-D sequence nor an ICL-NUIM (TUM-style) one.
    #[error(
        "{}: not a sequence folder (expected rgb.txt and depth.txt, or associations.txt)",
        shown_path(dir)
    )]
    UnknownLayout {
        /// The folder.
        dir: PathBuf,
    },
    /// A sequence has no usable frame (for example no depth/colour pair within 0.02 s).
    #[error("{}: {msg}", shown_path(dir))]
    EmptySequence {
        /// The sequence folder.
        dir: PathBuf,
        /// Why there are no frames.
        msg: String,
    },
    /// A frame index past the end of a sequence.
    #[error("frame index {index} is out of range (the sequence has {len} frames)")]
    FrameIndex {
        /// The requested index.
        index: usize,
        /// Number of frames of the sequence.
        len: usize,
    },
    /// Too few associated pose pairs for an evaluation.
    #[error(
        "only {found} pose pairs could be associated by timestamp, at least {needed} are \
         needed (do the trajectories cover the same time span?)"
    )]
    TooFewPairs {
        /// Pairs found.
        found: usize,
        /// Pairs needed.
        needed: usize,
    },
    /// An input is not a regular file (a named pipe, a device, a folder): refused
    /// before it is opened, so that it cannot block or feed the reader forever.
    #[error(
        "{}: is {kind}; expected a regular file (or a symlink to one)",
        shown_path(path)
    )]
    NotRegularFile {
        /// The path.
        path: PathBuf,
        /// What it is instead.
        kind: &'static str,
    },
    /// An input file is larger than the reader's limit for its kind.
    #[error(
        "{}: larger than the limit of {limit} bytes for this kind of file",
        shown_path(path)
    )]
    TooLarge {
        /// The file.
        path: PathBuf,
        /// The limit in bytes.
        limit: u64,
    },
    /// A file named by a sequence's list resolves (through a symlink) to a place
    /// outside the sequence folder.
    #[error(
        "{}: resolves outside the sequence folder {}; refused (--allow-outside to read it anyway)",
        shown_path(path),
        shown_path(dir)
    )]
    OutsideSequence {
        /// The file as the list names it.
        path: PathBuf,
        /// The sequence folder (canonical).
        dir: PathBuf,
    },
    /// An argument is unusable (buffer of the wrong size, non-finite value, unknown name).
    #[error("{0}")]
    InvalidInput(String),
    /// The background frame reader stopped abnormally.
    #[error("the frame reader thread panicked")]
    ReaderPanicked,
}

/// Result with ecvo-io's error.
pub type Result<T> = std::result::Result<T, Error>;

impl Error {
    /// An I/O error on `path`.
    pub(crate) fn io(path: impl AsRef<Path>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.as_ref().to_path_buf(),
            source,
        }
    }

    /// A parse error at `line` (1-based) of `path`.
    pub(crate) fn parse(path: impl AsRef<Path>, line: usize, msg: impl fmt::Display) -> Self {
        Error::Parse {
            path: path.as_ref().to_path_buf(),
            line,
            msg: msg.to_string(),
        }
    }

    /// An image error on `path`.
    pub(crate) fn image(path: impl AsRef<Path>, msg: impl fmt::Display) -> Self {
        Error::Image {
            path: path.as_ref().to_path_buf(),
            msg: msg.to_string(),
        }
    }

    /// The file this error is about, if any.
    pub fn path(&self) -> Option<&Path> {
        match self {
            Error::Io { path, .. }
            | Error::Parse { path, .. }
            | Error::NonMonotonic { path, .. }
            | Error::Image { path, .. }
            | Error::ImageSize { path, .. }
            | Error::Camera { path, .. }
            | Error::NotRegularFile { path, .. }
            | Error::TooLarge { path, .. }
            | Error::OutsideSequence { path, .. } => Some(path),
            Error::MissingCamera { dir }
            | Error::UnknownLayout { dir }
            | Error::EmptySequence { dir, .. } => Some(dir),
            _ => None,
        }
    }
}
