//! # ecvo-io
//!
//! The file formats around the ecvo tracker (An et al., WACV 2018):
//!
//! - [`Sequence`]: TUM RGB-D and ICL-NUIM (TUM-style) sequence folders, decoded
//!   frame by frame or streamed by a background reader ([`FrameReader`]).
//! - [`SequenceWriter`]: recorded streams (the TUM layout plus `camera.json`).
//! - [`camera`]: `camera.json` files and the benchmark camera presets.
//! - [`imu`]: `imu.txt` IMU streams and the IMU calibration of `camera.json`.
//! - [`Trajectory`]: TUM trajectory files (`timestamp tx ty tz qx qy qz qw`).
//! - [`eval`]: ATE and RPE as the TUM tools and evo compute them.
//! - [`write_ply`]: binary PLY point clouds.
//! - [`datasets_dir`]: where the shared test datasets are.
//!
//! Errors ([`Error`]) always name the file and, for text files, the line.
//!
//! Input is treated as hostile ([`files`]): every file read is a regular file (or a
//! symlink to one) within a size limit, PNGs decode with bounded memory, and the
//! files a sequence's lists name must lie inside its folder unless
//! [`OpenOptions::allow_outside`].

pub mod camera;
pub mod datasets;
pub mod derive;
pub mod error;
pub mod eval;
pub mod files;
pub mod imu;
mod list;
pub mod ply;
pub mod png;
mod reader;
pub mod sequence;
pub mod trajectory;
pub mod writer;

pub use camera::{CameraPreset, load_camera_json, save_camera_json};
pub use datasets::{dataset, dataset_for_test, datasets_dir};
pub use error::{Error, Result};
pub use list::{ListEntry, associate_stamps, parse_image_list, parse_image_list_with};
pub use ply::write_ply;
pub use reader::FrameReader;
pub use sequence::{
    Frame, FrameInfo, Layout, Listing, OpenOptions, Sequence, parse_associations,
    parse_associations_with,
};
pub use trajectory::Trajectory;
pub use writer::SequenceWriter;

pub use ecvo_core::{Camera, FrameView, Pose};
