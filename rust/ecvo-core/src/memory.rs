//! What the engine will allocate for a configuration, computed before allocating it,
//! and the budget it is checked against.
//!
//! Every buffer the engine uses is sized by the image and the schedule alone: the
//! prepared frames (image pyramid of interleaved samples, normals, template points),
//! the preparer's scratch (padded and smoothed depth, masks, per-level planes) and
//! MOTION's scratch (per-chunk residuals), and the gyroscope's ring of samples
//! ([`imu_bytes`], allocated at the first `push_imu`). [`estimate`] adds them up from the
//! [`Config`] with the same formulas the buffers are sized by, rounded up (a vector
//! grown by `push` is counted at twice its length), so that it is an upper bound of
//! the bytes [`crate::Odometry`] ever has outstanding (`tests/memory.rs` checks it
//! with a counting allocator). [`crate::Odometry::new`] refuses a configuration whose
//! estimate exceeds [`Config::memory_budget`] with [`Error::MemoryBudget`]; the
//! pipeline adds its pools and queues to it (`ecvo_pipeline::Pipeline::memory_needed`).

use crate::camera::Camera;
use crate::config::Config;
use crate::error::{Error, Result};
use crate::prepare::Sample;

pub use crate::config::DEFAULT_MEMORY_BUDGET;
pub use crate::error::{MB, format_mb};

/// Fixed allowance for the small allocations whose size does not depend on the image
/// (the tracker's per-level state, counters, the schedule, thread-local queues).
pub const FIXED_BYTES: usize = 256 << 10;

/// What [`crate::Odometry`] allocates for a configuration, in bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MemoryEstimate {
    /// One prepared frame: pyramid samples, normals and template points.
    pub frame_bytes: usize,
    /// How many prepared frames live at most: the previous frame, one reference per
    /// correction level, and the frame being prepared.
    pub frames: usize,
    /// The preparer's scratch buffers.
    pub preparer_bytes: usize,
    /// One motion estimator's scratch buffers.
    pub estimator_bytes: usize,
    /// The tracker's ring of gyroscope samples ([`imu_bytes`]), counted whether or
    /// not samples will be pushed.
    pub imu_bytes: usize,
    /// The total: `frames * frame_bytes + preparer_bytes + estimator_bytes +
    /// imu_bytes`, plus a margin of 1/64 of that and [`FIXED_BYTES`].
    pub bytes: usize,
}

/// What the sequential engine ([`crate::Odometry`]) allocates for `config`: an upper
/// bound, computed without allocating. `config` need not be valid, but the figures
/// mean something only for a valid one.
pub fn estimate(config: &Config) -> MemoryEstimate {
    let frame_bytes = prepared_frame_bytes(config);
    let frames = max_prepared_frames(config);
    let preparer_bytes = preparer_bytes(config);
    let estimator_bytes = estimator_bytes(config);
    let imu_bytes = imu_bytes();
    MemoryEstimate {
        frame_bytes,
        frames,
        preparer_bytes,
        estimator_bytes,
        imu_bytes,
        bytes: with_margin(
            frames
                .saturating_mul(frame_bytes)
                .saturating_add(preparer_bytes)
                .saturating_add(estimator_bytes)
                .saturating_add(imu_bytes),
        ),
    }
}

/// `bytes` plus the estimate's margin: 1/64 of it and [`FIXED_BYTES`].
pub fn with_margin(bytes: usize) -> usize {
    bytes.saturating_add(bytes / 64).saturating_add(FIXED_BYTES)
}

/// Refuses `need` bytes above `budget` with [`Error::MemoryBudget`].
pub fn check_budget(need: usize, budget: usize) -> Result<()> {
    if need > budget {
        return Err(Error::MemoryBudget { need, budget });
    }
    Ok(())
}

/// The most prepared frames [`crate::Odometry`] keeps alive: the previous frame, one
/// reference per correction level and the frame being prepared.
pub fn max_prepared_frames(config: &Config) -> usize {
    config.reference_levels.len() + 2
}

/// The intrinsics of every pyramid level of `config`'s schedule, full resolution
/// first (without allocating: the sizes only).
fn level_sizes(config: &Config) -> impl Iterator<Item = (usize, usize)> + '_ {
    let mut c: Camera = config.camera;
    (0..=config.pyramid_depth()).map(move |l| {
        if l > 0 {
            c = c.half();
        }
        (c.width, c.height)
    })
}

fn level_size(config: &Config, level: usize) -> (usize, usize) {
    level_sizes(config).nth(level).unwrap_or((0, 0))
}

/// The template points a step can hold at most (as `PreparedFrame::for_config`
/// reserves them).
fn template_capacity(config: &Config, level: usize, stride: usize) -> usize {
    let (w, h) = level_size(config, level);
    let s = stride.max(1);
    (w / s + 1) * (h / s + 1)
}

/// One prepared frame (`PreparedFrame::for_config`): the samples of every pyramid
/// level the schedule tracks (32 bytes a pixel), the full-resolution intensity and
/// depth when level 0 is not tracked (8 bytes a pixel), the full-resolution normals
/// (12 bytes a pixel) and each step's template points (16 bytes a point).
pub fn prepared_frame_bytes(config: &Config) -> usize {
    let tracked = crate::prepare::tracked_levels(config);
    let samples: usize = level_sizes(config)
        .zip(&tracked)
        .map(|((w, h), &t)| if t { w * h * size_of::<Sample>() } else { 0 })
        .sum::<usize>()
        + if tracked[0] {
            0
        } else {
            8 * config.camera.pixels()
        };
    let normals = config.camera.pixels() * size_of::<[f32; 3]>();
    let templates: usize = config
        .motion
        .levels
        .iter()
        .map(|l| template_capacity(config, l.pyramid_level, l.stride) * size_of::<[f32; 4]>())
        .sum();
    samples + normals + templates + crate::prepare::side_bytes(config)
}

/// The preparers' scratch (the filter's, and with lookup frames the tracker's
/// finisher's): padded and smoothed depth (4 bytes a pixel each), the two
/// per-pixel masks, the rays, the intensity and depth planes of every level (8 bytes
/// a pixel), the raw depth turned to the intensity's time (2 bytes a pixel) and, with a point budget, the selection's candidates (counted at twice
/// their number: they grow by `push`).
pub fn preparer_bytes(config: &Config) -> usize {
    let (w, h) = (config.camera.width, config.camera.height);
    let r = config.filter.bilateral.map_or(0, |b| b.radius);
    let padded = (w + 2 * r) * (h + 2 * r) * 4;
    let smoothed = w * h * 4;
    let masks = 2 * w * h + 2 * w;
    let rays = 4 * (w + h);
    let spatial = 4 * (2 * r + 1) * (2 * r + 1);
    // A lookup frame filtered on level 1: its padded depth and spatial weights.
    let half = crate::prepare::half_bilateral_bytes(config);
    let planes: usize = level_sizes(config).map(|(w, h)| 8 * w * h).sum();
    let selector: usize = config
        .motion
        .levels
        .iter()
        .filter(|l| l.max_points.is_some())
        .map(|l| {
            let n = template_capacity(config, l.pyramid_level, l.stride);
            // pixel, cell, score, depth score and the pool grow by push (x2); keep
            // and the per-cell winners are resized to at most n.
            2 * 5 * 4 * n + n + 4 * n
        })
        .max()
        .unwrap_or(0);
    // Raw depth turned to the intensity's time (`Preparer::prepare_turned_into`).
    let turned = 2 * w * h;
    let scratch = padded + smoothed + masks + rays + spatial + half + planes + selector + turned;
    scratch + finisher_bytes(config, scratch)
}

/// With frames prepared for lookup only ([`Config::lookup_depth`]), the tracker's
/// finisher: a second preparer's `scratch`, and the samples of each level a step
/// with a point budget selects from (32 bytes a pixel).
fn finisher_bytes(config: &Config, scratch: usize) -> usize {
    if crate::prepare::lookup_depth(config).is_none() {
        return 0;
    }
    let budgeted: usize = level_sizes(config)
        .enumerate()
        .filter(|(l, _)| {
            config
                .motion
                .levels
                .iter()
                .any(|s| s.pyramid_level == *l && s.max_points.is_some())
        })
        .map(|(_, (w, h))| w * h * size_of::<Sample>())
        .sum();
    scratch + budgeted
}

/// The tracker's ring of gyroscope samples ([`crate::imu::RING_CAPACITY`] of
/// them) and the depth clock's ([`crate::imu::depth_time::DEPTH_CLOCK_CAPACITY`]),
/// allocated once at the first `push_imu` whatever the configuration.
pub fn imu_bytes() -> usize {
    (crate::imu::RING_CAPACITY + crate::imu::depth_time::DEPTH_CLOCK_CAPACITY)
        * size_of::<crate::imu::GyroSample>()
}

/// One motion estimator's scratch for the largest template of `config`'s schedule
/// (`MotionEstimator::with_capacity`).
pub fn estimator_bytes(config: &Config) -> usize {
    crate::motion::scratch_bytes(crate::prepare::max_template_points(config))
}
