//! ecvo-jni's integration tests. The JVM tests (a real JVM under -Xcheck:jni) are run by
//! `scripts/jni-jvm-tests.sh`, not by `cargo test`.
//!
//! One integration-test binary for the crate (linking one binary instead of one per
//! file is most of what `cargo test` saves). Tests that measure the whole process
//! (a global counting allocator, the process's threads or its children's peak RSS)
//! stay in binaries of their own beside this folder.

mod signatures;
mod tof;
