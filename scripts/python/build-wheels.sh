#!/usr/bin/env bash
# Builds the Python package's wheels for Linux and checks each one:
#
#   scripts/python/build-wheels.sh [--targets x86_64,aarch64] [--out DIR]
#
# For each target: `maturin build --release --strip --zig` with a manylinux2014
# (glibc 2.17) baseline, so that the wheel installs on Ubuntu 20.04 / Debian 11
# (glibc 2.31) and older (zig links against that glibc's symbols; maturin checks the
# result as auditwheel does). Then: the wheel must be under 1.5 MB, its tag
# manylinux_2_17 (or lower), `auditwheel show` must agree with the tag; the x86_64
# wheel is installed in a fresh venv and tracks the test stream (ATE under 2 mm).
# The aarch64 wheel is installed and run the same way when an aarch64 Python is
# available through qemu-user (ECVO_AARCH64_PYTHON=/path/to/chroot's python3 run by
# binfmt, e.g. a debootstrapped Debian bullseye arm64); otherwise only its tag and
# auditwheel are checked, and the script says so.
#
# Needs: cargo with the Rust targets (`rustup target add aarch64-unknown-linux-gnu`);
# maturin, ziglang and auditwheel come from PyPI into a throwaway venv. A missing
# Rust target is an error naming the command that adds it.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$ROOT/target}"
PYTHON="${PYTHON:-python3}"
TARGETS="x86_64,aarch64"
OUT="$CARGO_TARGET_DIR/wheels-manylinux"
MAX_BYTES=$((1536 * 1024))
while [ $# -gt 0 ]; do
    case "$1" in
        --targets) TARGETS="$2"; shift 2 ;;
        --out) OUT="$2"; shift 2 ;;
        *) echo "build-wheels.sh: unknown argument $1" >&2; exit 2 ;;
    esac
done

command -v cargo >/dev/null || { echo "build-wheels.sh: cargo not found (a Rust toolchain is needed)" >&2; exit 1; }
installed="$(rustup target list --installed 2>/dev/null || rustc --print target-list)"
IFS=',' read -r -a arches <<< "$TARGETS"
for arch in "${arches[@]}"; do
    case "$arch" in x86_64|aarch64) ;; *) echo "build-wheels.sh: unknown target $arch" >&2; exit 2 ;; esac
    if ! grep -qx "$arch-unknown-linux-gnu" <<< "$installed"; then
        echo "build-wheels.sh: the Rust target $arch-unknown-linux-gnu is not installed:" >&2
        echo "    rustup target add $arch-unknown-linux-gnu" >&2
        exit 1
    fi
done

WORK="$(mktemp -d)"
trap 'rm -rf "$WORK"' EXIT
echo "== tools: maturin, ziglang, auditwheel (PyPI) in $WORK/tools"
"$PYTHON" -m venv "$WORK/tools"
"$WORK/tools/bin/pip" install -q --disable-pip-version-check "maturin>=1.9,<2" ziglang auditwheel
export PATH="$WORK/tools/bin:$PATH"
mkdir -p "$OUT"

for arch in "${arches[@]}"; do
    target="$arch-unknown-linux-gnu"
    echo "== $target: maturin build --release --strip --zig --compatibility manylinux2014"
    rm -f "$OUT"/ecvo-*-"$arch".whl "$OUT"/ecvo-*_"$arch".whl
    (cd "$ROOT/rust/ecvo-py" && nice -n 5 maturin build --release --strip --zig \
        --target "$target" --compatibility manylinux2014 --out "$OUT" --quiet)
    wheel="$(ls "$OUT"/ecvo-*"$arch".whl | head -n 1)"
    size=$(stat -c %s "$wheel")
    name="$(basename "$wheel")"
    echo "   $name: $size bytes"
    [ "$size" -lt "$MAX_BYTES" ] || { echo "build-wheels.sh: $name is $size bytes, over 1.5 MB" >&2; exit 1; }
    case "$name" in
        *manylinux_2_17_"$arch"*|*manylinux2014_"$arch"*) ;;
        *) echo "build-wheels.sh: $name is not tagged manylinux_2_17" >&2; exit 1 ;;
    esac
    echo "== auditwheel show $name"
    "$WORK/tools/bin/auditwheel" show "$wheel" | tee "$WORK/audit.txt"
    grep -q "manylinux_2_17_$arch" "$WORK/audit.txt" || {
        echo "build-wheels.sh: auditwheel does not place $name at manylinux_2_17" >&2; exit 1; }

    py=""
    if [ "$arch" = "$(uname -m)" ]; then
        py="$PYTHON"
    elif [ -n "${ECVO_AARCH64_PYTHON:-}" ] && [ "$arch" = aarch64 ]; then
        py="$ECVO_AARCH64_PYTHON"
    fi
    if [ -z "$py" ]; then
        echo "== $name: NOT run (no $arch Python here; set ECVO_AARCH64_PYTHON); tag and auditwheel checked only"
        continue
    fi
    echo "== $name: fresh venv, install, track testdata"
    "$py" -m venv "$WORK/venv-$arch"
    "$WORK/venv-$arch/bin/pip" install -q --disable-pip-version-check "$wheel"
    (cd "$WORK" && "$WORK/venv-$arch/bin/python" - "$ROOT/testdata/synth_phone_320x180" <<'PY'
import sys

import ecvo

seq = ecvo.read_sequence(sys.argv[1])
with ecvo.Tracker(seq.camera) as tracker:
    for frame in seq:
        result = tracker.push(*frame)
    ate = ecvo.ate(seq.groundtruth, tracker.trajectory())
assert result.state == "tracking" and ate["rmse"] < 0.002, ate["rmse"]
print(f"   ecvo {ecvo.__version__} from the wheel: {len(tracker)} frames, ATE {ate['rmse'] * 1e3:.2f} mm, simd {ecvo._ecvo.simd_path}")
PY
    )
done
echo "== wheels in $OUT"
ls -l "$OUT"
