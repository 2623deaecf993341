#!/usr/bin/env bash
# Runs ecvo's frame-to-frame peers on TUM-layout sequences and scores them with
# `ecvo eval`: OpenCV's RGB-D and photometric (RGB) odometry from PyPI's
# opencv-contrib-python, and the visual-odometry-rs (vors) tracker from crates.io.
#
#   scripts/peers/run-peers.sh SEQ... [--frame-steps 1,2,3,4] [--out DIR]
#                              [--peers opencv-rgbd,opencv-rgb,vors] [--pin-cpu N]
#                              [--max-frames N]
#
# Prints a Markdown table (sequence, frame step, peer, frames, ATE RMSE, the clock and
# the median / mean / p95 ms/frame on it and on the wall clock, threads, failed
# alignments) and writes DIR/peers.json (default DIR: target/peers). --pin-cpu N binds
# the Python peers to CPU N (an honest one-thread time for Open3D; see
# docs/speed-peers.md); --max-frames N keeps the first N frames. Peers: opencv-rgbd, opencv-rgb, opencv-depth, open3d-hybrid,
# open3d-color, vors.
#
# First use sets up, all outside the repository's sources:
#   - a Python venv with opencv-contrib-python and numpy in PEERS_VENV
#     (default target/peers-venv), and open3d in it when an open3d-* peer is asked
#     for (a 400 MB wheel that needs libusb-1.0: Debian's libusb-1.0-0);
#   - scripts/peers/vors-cam (a driver of the visual-odometry-rs crate that takes
#     camera.json's intrinsics and depth scale) built into PEERS_CACHE/vors-cam-target
#     (default ~/.cache/ecvo-peers), about 3-4 minutes here;
#   - target/release/ecvo, if missing (ECVO overrides the binary).
set -euo pipefail

root=$(cd "$(dirname "$0")/../.." && pwd)
venv=${PEERS_VENV:-$root/target/peers-venv}
cache=${PEERS_CACHE:-$HOME/.cache/ecvo-peers}
ecvo=${ECVO:-$root/target/release/ecvo}
out=$root/target/peers
steps=1
peers=opencv-rgbd,opencv-rgb,vors
seqs=()
pass=()
while [[ $# -gt 0 ]]; do
    case $1 in
        --frame-steps) steps=$2; shift 2 ;;
        --out) out=$2; shift 2 ;;
        --peers) peers=$2; shift 2 ;;
        --pin-cpu|--max-frames) pass+=("$1" "$2"); shift 2 ;;
        -h|--help) sed -n '2,/^set /{/^set /d;s/^# \{0,1\}//;p}' "$0"; exit 0 ;;
        -*) echo "unknown option $1" >&2; exit 2 ;;
        *) seqs+=("$1"); shift ;;
    esac
done
if [[ ${#seqs[@]} -eq 0 ]]; then
    echo "usage: $0 SEQ... [--frame-steps 1,2,3,4] [--out DIR] [--peers LIST]" >&2
    exit 2
fi

# shellcheck source=setup.sh
. "$root/scripts/peers/setup.sh"
ensure_peers_venv "$venv"
ensure_ecvo "$root" "$ecvo"
if [[ ,$peers, == *,open3d-* ]]; then
    ensure_open3d "$venv"
fi

args=()
if [[ ,$peers, == *,vors,* ]]; then
    args+=(--vors-cam "$(ensure_vors_cam "$root" "$cache")")
fi

exec "$venv/bin/python" "$root/scripts/peers/peers.py" --ecvo "$ecvo" --peers "$peers" \
    --frame-steps "$steps" --out "$out" "${args[@]}" "${pass[@]}" "${seqs[@]}"
