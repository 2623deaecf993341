# Sourced by run-peers.sh and bench-vs-peer.sh: the set-up both need.

# ensure_peers_venv VENV: a Python venv with opencv-contrib-python and numpy.
ensure_peers_venv() {
    local venv=$1
    if [[ ! -x $venv/bin/python ]] || ! "$venv/bin/python" -c 'import cv2, numpy' 2>/dev/null; then
        echo "setting up $venv (opencv-contrib-python, numpy)" >&2
        python3 -m venv "$venv"
        "$venv/bin/pip" install --quiet opencv-contrib-python numpy >&2
    fi
}

# ensure_ecvo ROOT ECVO: builds the ecvo binary when ECVO (target/release/ecvo) is missing.
ensure_ecvo() {
    if [[ ! -x $2 ]]; then
        (cd "$1" && cargo build --release -p ecvo-cli >&2)
    fi
}

# ensure_open3d VENV: Open3D (PyPI's `open3d`, a 400 MB wheel) in the venv, for the
# open3d-* peers. Its Python module links libusb-1.0 (Debian: libusb-1.0-0).
ensure_open3d() {
    local venv=$1
    if ! "$venv/bin/python" -c 'import open3d' 2>/dev/null; then
        # Install only when it is missing, not when it is there but fails to load.
        if ! "$venv/bin/python" -c 'import importlib.util, sys; sys.exit(importlib.util.find_spec("open3d") is None)'; then
            echo "installing open3d into $venv" >&2
            "$venv/bin/pip" install --quiet open3d >&2
        fi
        if ! err=$("$venv/bin/python" -c 'import open3d' 2>&1); then
            echo "open3d does not import: ${err##*$'\n'}" >&2
            echo "(its wheel needs libusb-1.0: apt-get install libusb-1.0-0)" >&2
            return 1
        fi
    fi
}

# ensure_vors_cam ROOT CACHE: builds scripts/peers/vors-cam (a driver of the
# visual-odometry-rs crate) into CACHE/vors-cam-target and prints the binary's path.
# Cargo rebuilds only when the driver's sources changed.
ensure_vors_cam() {
    (cd "$1/scripts/peers/vors-cam" &&
        cargo build --release --locked --quiet --target-dir "$2/vors-cam-target" >&2)
    echo "$2/vors-cam-target/release/vors-cam"
}
