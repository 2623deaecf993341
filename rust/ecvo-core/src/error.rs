//! The one error type of the core.

/// What can go wrong in the core: a bad setting or a bad frame. Tracking failure is
/// not an error: it is reported in the per-frame output.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum Error {
    /// A configuration field is out of range; `field` names it.
    #[error("invalid config field `{field}`: {why}")]
    InvalidConfig {
        /// The offending field.
        field: &'static str,
        /// Why it is rejected.
        why: String,
    },
    /// The engine would allocate more than its budget for this image size and these
    /// settings ([`crate::memory`]); nothing was allocated.
    #[error(
        "the image size and settings need {} of memory, over the budget of {} (a smaller image, fewer reference levels or a larger budget would do)",
        format_mb(*need),
        format_mb(*budget)
    )]
    MemoryBudget {
        /// Bytes the engine would allocate.
        need: usize,
        /// Bytes it may allocate.
        budget: usize,
    },
    /// A frame does not match the camera it is meant for.
    #[error("bad frame: {0}")]
    BadFrame(String),
    /// A batch of IMU samples with a non-finite value ([`crate::imu`]); none of the
    /// batch was taken.
    #[error("bad IMU sample: {0}")]
    BadImuSample(String),
}

/// Result with the core's error.
pub type Result<T> = std::result::Result<T, Error>;

/// Bytes per mebibyte, for messages.
pub const MB: usize = 1 << 20;

/// `bytes` in mebibytes with one decimal, for messages.
pub fn format_mb(bytes: usize) -> String {
    format!("{:.1} MB", bytes as f64 / MB as f64)
}
