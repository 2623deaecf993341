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
# The aarch64 wheel tracks the same stream under qemu-user: Debian's arm64 CPython
# (python3.11-minimal and libpython3.11-stdlib for arm64, fetched with `apt-get
# download` and unpacked in a scratch folder, nothing installed), run by qemu-aarch64
# with the wheel and numpy's aarch64 wheel put in a folder on its PYTHONPATH by the
# host's pip (`--platform manylinux2014_aarch64`). ECVO_AARCH64_PYTHON=/path/to/python3
# (an aarch64 Python that runs here, e.g. in a chroot run by binfmt) replaces that.
# Without qemu-aarch64 or apt, only the tag and auditwheel are checked, and the script
# says so.
#
# Needs: cargo with the Rust targets (`rustup target add aarch64-unknown-linux-gnu`);
# maturin, ziglang and auditwheel come from PyPI into a throwaway venv. A missing
# Rust target is an error naming the command that adds it. For the aarch64 run:
# qemu-user and dpkg's arm64 architecture (scripts/android/test-core-aarch64.sh
# --setup-only installs both).
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
# Absolute: maturin runs from rust/ecvo-py, where a relative --out would land.
mkdir -p "$OUT"
OUT="$(cd "$OUT" && pwd)"

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

    if [ "$arch" = "$(uname -m)" ]; then
        echo "== $name: fresh venv, install, track testdata"
        "$PYTHON" -m venv "$WORK/venv-$arch"
        "$WORK/venv-$arch/bin/pip" install -q --disable-pip-version-check "$wheel"
        run=("$WORK/venv-$arch/bin/python")
    elif [ "$arch" = aarch64 ] && [ -n "${ECVO_AARCH64_PYTHON:-}" ]; then
        echo "== $name: fresh venv of $ECVO_AARCH64_PYTHON, install, track testdata"
        "$ECVO_AARCH64_PYTHON" -m venv "$WORK/venv-$arch"
        "$WORK/venv-$arch/bin/pip" install -q --disable-pip-version-check "$wheel"
        run=("$WORK/venv-$arch/bin/python")
    elif [ "$arch" = aarch64 ] && command -v qemu-aarch64 >/dev/null && command -v apt-get >/dev/null; then
        echo "== $name: Debian's arm64 CPython under qemu-aarch64, wheel + numpy (aarch64) on its path, track testdata"
        arm="$WORK/arm64"
        mkdir -p "$arm/debs"
        (cd "$arm/debs" && apt-get download -q python3.11-minimal:arm64 libpython3.11-minimal:arm64 \
            libpython3.11-stdlib:arm64 libexpat1:arm64 >/dev/null)
        for deb in "$arm"/debs/*.deb; do dpkg -x "$deb" "$arm/root"; done
        pip_arm=(--disable-pip-version-check -q --target "$arm/site" --only-binary=:all: --implementation cp
            --python-version 3.11 --platform manylinux_2_17_aarch64 --platform manylinux2014_aarch64)
        "$PYTHON" -m pip install "${pip_arm[@]}" "numpy<2.3" 2>&1 | grep -v "^WARNING: Running pip as" || true
        "$PYTHON" -m pip install "${pip_arm[@]}" --no-deps "$wheel" 2>&1 | grep -v "^WARNING: Running pip as" || true
        run=(env PYTHONHOME="$arm/root/usr" PYTHONPATH="$arm/site"
            LD_LIBRARY_PATH="$arm/root/usr/lib/aarch64-linux-gnu:$arm/root/lib/aarch64-linux-gnu"
            qemu-aarch64 "$arm/root/usr/bin/python3.11")
    else
        echo "== $name: NOT run (no qemu-aarch64 or apt-get, and no ECVO_AARCH64_PYTHON); tag and auditwheel checked only"
        # In CI a wheel that was not run is a failure, not a skip.
        [ "${CI:-}" != true ] || exit 1
        continue
    fi
    (cd "$WORK" && "${run[@]}" - "$ROOT/testdata/synth_phone_320x180" <<'PY'
import platform
import sys

import ecvo

seq = ecvo.read_sequence(sys.argv[1])
with ecvo.Tracker(seq.camera) as tracker:
    for frame in seq:
        result = tracker.push(*frame)
    ate = ecvo.ate(seq.groundtruth, tracker.trajectory())
assert result.state == "tracking" and ate["rmse"] < 0.002, ate["rmse"]
print(f"   ecvo {ecvo.__version__} from the wheel on {platform.machine()}, {platform.libc_ver()}: {len(tracker)} frames, ATE {ate['rmse'] * 1e3:.2f} mm, simd {ecvo._ecvo.simd_path}")
PY
    )
done
echo "== wheels in $OUT"
ls -l "$OUT"
