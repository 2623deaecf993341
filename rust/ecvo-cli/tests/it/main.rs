//! ecvo-cli's integration tests: the `ecvo` binary end to end.
//!
//! One integration-test binary for the crate (linking one binary instead of one per
//! file is most of what `cargo test` saves). Tests that measure the whole process
//! (a global counting allocator, the process's threads or its children's peak RSS)
//! stay in binaries of their own beside this folder.

mod bad_input;
mod common;
mod hostile_input;
mod output;
mod real_data;
mod synth_imu;
mod synth_motion;
mod synth_orbit;
mod synth_stream;
