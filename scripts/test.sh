#!/usr/bin/env bash
# The README's test command: `cargo test --workspace --exclude ecvo-py --exclude ecvo-bench
# --release --no-fail-fast` (extra arguments are passed on), then one last line counting the
# tests on real datasets that did not run because their data is absent, with the command that
# makes them run. The exit status is cargo's.
#
#   scripts/test.sh [cargo test arguments...]
#
# The JVM tests of the JNI library are not part of it: scripts/jni-jvm-tests.sh (.ci/run
# calls both).
set -uo pipefail
cd "$(dirname "$0")/.."
log=$(mktemp)
trap 'rm -f "$log"' EXIT
# ecvo-py has no Rust tests (test = false: its tests are pytest, scripts/python/test-python.sh);
# left out, its numpy and pyo3 are not built and do not change the features of the crates
# the run command built. ecvo-bench holds only criterion benches (`cargo bench -p ecvo-bench`);
# left out, criterion and its dependencies are not built.
cargo test --workspace --exclude ecvo-py --exclude ecvo-bench --release --no-fail-fast "$@" 2>&1 | tee "$log"
rc=${PIPESTATUS[0]}

# Each test without its data writes `NOT RUN (no data): <test>: dataset `<name>` not found ...`
# (ecvo_io::datasets::dataset_for_test).
tests=$(grep -o 'NOT RUN (no data): [^:]*' "$log" | sed 's/^NOT RUN (no data): //' | sort -u)
sets=$(grep 'NOT RUN (no data): ' "$log" | grep -o 'dataset `[^`]*`' | tr -d '`' | sed 's/^dataset //' | sort -u)
n=$(printf '%s' "$tests" | grep -c . || true)
echo
if [ "$n" = 0 ]; then
  echo "0 dataset tests not run"
else
  echo "$n dataset tests not run (no data: $(echo $sets | sed 's/ /, /g')): $(echo $tests | sed 's/ /, /g'); to run them: scripts/datasets/get-tum.sh --tests DIR, then ECVO_DATASETS=DIR scripts/test.sh"
fi
exit "$rc"
