#!/usr/bin/env bash
# Runs ecvo-core's and ecvo-pipeline's tests under AddressSanitizer (with
# LeakSanitizer) or ThreadSanitizer, on nightly with the standard library rebuilt
# instrumented (-Zbuild-std; needs `rustup component add rust-src --toolchain nightly`).
#
#   scripts/sanitizers.sh address|thread [extra cargo test args]
#
# By default the two crates' lib (unit) tests and the pipeline's `lifecycle` test
# (pipelines created and dropped in a loop: threads, pools, queues); extra arguments
# go to cargo test, e.g. `-- --skip slow_test`. SAN_TARGETS overrides the test
# selection (e.g. SAN_TARGETS="--lib --tests" for every test; slow).
# Builds into target/san-<kind>; niced. Not part of CI (a full instrumented rebuild).
set -euo pipefail
cd "$(dirname "$0")/.."
kind=${1:?address or thread}; shift
host=$(rustc +nightly -vV | sed -n 's/^host: //p')
export RUSTFLAGS="-Zsanitizer=$kind --cfg sanitizer"
export RUSTDOCFLAGS="-Zsanitizer=$kind"
export CARGO_TARGET_DIR="target/san-$kind"
# TSan: rayon's and crossbeam's lock-free code is instrumented through build-std too.
export TSAN_OPTIONS="${TSAN_OPTIONS:-halt_on_error=1 second_deadlock_stack=1}"
export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1 detect_stack_use_after_return=1}"
# shellcheck disable=SC2086 # SAN_TARGETS is a list of cargo arguments
nice -n 19 cargo +nightly test -Zbuild-std --target "$host" -p ecvo-core -p ecvo-pipeline \
  ${SAN_TARGETS:---lib --test lifecycle} "$@"
