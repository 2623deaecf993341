//! # ecvo-core
//!
//! The tracking engine of ecvo: An, Lee, Jeong, Ihm, "Tracking an RGB-D Camera on
//! Mobile Devices Using an Improved Frame-to-Frame Pose Estimation Method"
//! (WACV 2018). Frames in, poses out: no file I/O, no Java, no threads of its own.
//! Its heavy loops (MOTION's chunks of template points, the filter's rows) run with
//! rayon in the caller's pool, over fixed chunks merged in a fixed order, so the
//! poses are the same whatever the number of threads.
//!
//! - [`prepare`]: the filter stage (bilateral, normal-based and contour-based
//!   depth removal) and the per-level images and template points.
//! - [`motion`]: `MOTION(Fi, Fj, Tinit)`, dense photometric and depth alignment by
//!   iteratively re-weighted Gauss-Newton with t-distribution weights.
//! - [`tracker`]: adaptive multi-level pose error correction (Figure 1(b)).
//! - [`imu`]: the gyroscope's rotation prior for \[A\] and its bias estimate.
//! - [`se3`]: the exponential and logarithm of SE(3).

pub mod camera;
pub mod config;
pub mod correction;
pub mod counters;
pub mod error;
pub mod imu;
pub mod lost;
pub mod memory;
pub mod motion;
pub mod noise;
pub mod num;
pub mod odometry;
pub mod prepare;
pub mod prior;
pub mod scale;
pub mod se3;
pub mod spread;
pub mod tracker;

pub use camera::{Camera, FrameView};
pub use config::{
    Config, DepthNoiseModel, FilterConfig, LookupDepth, MAX_PYRAMID_LEVEL, MAX_SCHEDULE_SHIFT,
    MIN_LEVEL_SIDE, Mode, MotionConfig, MotionLevel, MotionPrior, Preset, ReferenceLevel,
    SCHEDULE_SHIFT_SIDE, Schedule, Weighting, parse_point_budget, parse_schedule,
};
pub use error::{Error, Result};
pub use imu::{GyroSample, ImuCalibration};
pub use lost::LostReason;
pub use memory::{DEFAULT_MEMORY_BUDGET, MemoryEstimate};
pub use motion::{MotionEstimator, MotionResult};
pub use nalgebra;
pub use num::Num;
pub use odometry::Odometry;
pub use prepare::simd::path_name as simd_path;
pub use prepare::{PreparedFrame, Preparer};
pub use tracker::{Counters, FrameOutput, Tracker, TrackingState, comp, frame_to_frame};

/// A rigid motion in double precision. Poses are camera-to-world; the world is the
/// first camera.
pub type Pose = nalgebra::Isometry3<f64>;
