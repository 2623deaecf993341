#!/usr/bin/env bash
# CI for ecvo, on a fresh machine (2 cores, root, crates.io / npm / Debian reachable).
# Installs what it uses, then: formatting, clippy with warnings denied, the README's
# test command, the Android app check (aapt, Kotlin against generated API stubs) and the
# Android cross-compilation check.
set -euo pipefail
cd "$(dirname "$0")/.."
export CARGO_TERM_COLOR=never
# Absent real datasets are a failure in CI, not a skip.
export ECVO_REQUIRE_DATASETS=1
[ -d ../shared/datasets ] && export ECVO_DATASETS="$(cd ../shared/datasets && pwd)"

t0=$(date +%s)
step() { echo; echo "=== [$(( $(date +%s) - t0 ))s] $*"; }

step "fuzz targets: nightly and cargo-fuzz, build, then 10 s of each on its seeds and regression inputs"
rustup toolchain list | grep -q '^nightly' || rustup toolchain install nightly --profile minimal
command -v cargo-fuzz >/dev/null || cargo install cargo-fuzz --locked
cargo +nightly fuzz build
python3 scripts/fuzz/seeds.py
for t in $(cargo +nightly fuzz list); do
  mkdir -p "fuzz/corpus/$t"
  cargo +nightly fuzz run "$t" "fuzz/corpus/$t" $( [ -d "fuzz/regressions/$t" ] && echo "fuzz/regressions/$t" ) -- \
    -max_total_time=10 -timeout=10 -rss_limit_mb=2048 -malloc_limit_mb=512 -max_len=262144 2>&1 | tail -2
done

step "Kotlin modules on the JVM (plain Kotlin: :tracker, :shared)"
bash scripts/kotlin/test-kotlin.sh

step "Android app without the SDK: aapt on manifest+resources, :app's Kotlin against generated API stubs"
bash scripts/android-stubs/check-app.sh

step "Android cross-compilation check (clippy, linked .so for 3 ABIs, ELF checks, core tests on aarch64/qemu)"
bash scripts/android/ci-cross-check.sh

step "done in $(( $(date +%s) - t0 ))s"
