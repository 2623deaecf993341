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
    /// A frame does not match the camera it is meant for.
    #[error("bad frame: {0}")]
    BadFrame(String),
}

/// Result with the core's error.
pub type Result<T> = std::result::Result<T, Error>;
