# Sourced by run-peers.sh and bench-vs-opencv.sh: the set-up both need.

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
