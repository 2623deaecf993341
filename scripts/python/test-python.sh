#!/usr/bin/env bash
# The Python package's test suite on a fresh venv: builds `ecvo` (the command the
# tests compare with), pip-installs rust/ecvo-py (maturin fetched by pip as the
# build backend), or the wheel ECVO_WHEEL names (CI: scripts/python/build-wheels.sh's
# x86_64 manylinux wheel), with numpy and pytest, and runs pytest. Ends with pytest's
# summary line; exits non-zero on any failure.
#
# Builds share the workspace's target dir (CARGO_TARGET_DIR, default ./target), so
# after `cargo test --workspace --release` only pyo3 and the module itself compile.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$ROOT/target}"
PYTHON="${PYTHON:-python3}"

command -v "$PYTHON" >/dev/null || { echo "test-python.sh: $PYTHON not found" >&2; exit 1; }
if ! "$PYTHON" -c 'import venv, ensurepip' 2>/dev/null; then
    # Debian splits venv/ensurepip out of python3.
    if command -v apt-get >/dev/null; then
        apt-get update -qq && apt-get install -y -qq python3-venv >/dev/null
    else
        echo "test-python.sh: $PYTHON has no venv module" >&2
        exit 1
    fi
fi

echo "== cargo build --release -p ecvo-cli"
cargo build --release -q -p ecvo-cli

WORK="$(mktemp -d)"
trap 'rm -rf "$WORK"' EXIT
echo "== fresh venv in $WORK/venv"
"$PYTHON" -m venv "$WORK/venv"
PY="$WORK/venv/bin/python"
"$PY" -m pip install -q --disable-pip-version-check numpy pytest mypy
if [ -n "${ECVO_WHEEL:-}" ]; then
    # The tests against a built wheel (CI: the manylinux wheel of build-wheels.sh).
    [ -f "$ECVO_WHEEL" ] || { echo "test-python.sh: ECVO_WHEEL=$ECVO_WHEEL is not a file" >&2; exit 1; }
    echo "== pip install $ECVO_WHEEL"
    "$PY" -m pip install -q --disable-pip-version-check --no-cache-dir "$ECVO_WHEEL"
else
    echo "== pip install rust/ecvo-py"
    # --no-cache-dir: never a wheel cached from an earlier build of the same version.
    "$PY" -m pip install -q --disable-pip-version-check --no-cache-dir "$ROOT/rust/ecvo-py"
fi

echo "== pytest"
# Run from outside the source tree so that the installed package is the one tested.
cd "$WORK"
ECVO_BIN="$CARGO_TARGET_DIR/release/ecvo" "$PY" -m pytest -p no:cacheprovider -q \
    "$ROOT/rust/ecvo-py/tests"
