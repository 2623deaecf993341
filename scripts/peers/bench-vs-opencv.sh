#!/usr/bin/env bash
# The older name of bench-vs-peer.sh, kept for the commands quoted in docs/: the same
# options (default peer opencv-rgbd), results in target/bench-vs-opencv unless --out
# says otherwise.
#
#   scripts/peers/bench-vs-opencv.sh [--rounds 3] [--frame-step 1] [--peer opencv-rgbd]
#                                    SEQ... [-- ECVO RUN ARGS]
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
exec "$here/bench-vs-peer.sh" --out "$here/../../target/bench-vs-opencv" "$@"
