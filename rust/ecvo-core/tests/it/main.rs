//! ecvo-core's integration tests.
//!
//! One integration-test binary for the crate (linking one binary instead of one per
//! file is most of what `cargo test` saves). Tests that measure the whole process
//! (a global counting allocator, the process's threads or its children's peak RSS)
//! stay in binaries of their own beside this folder.

mod basin;
mod common;
mod frame_quality;
mod imu;
mod keyframes;
mod motion;
mod properties;
mod threads;
mod tracker;
