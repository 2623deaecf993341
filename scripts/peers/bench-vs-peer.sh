#!/usr/bin/env bash
# ecvo's time per frame against a peer's, measured in the same run, rounds alternated,
# as ratios (issues 11 and 30):
#
#   scripts/peers/bench-vs-peer.sh [--peer opencv-rgbd|open3d-hybrid|vors|...]
#       [--rounds 3] [--frame-step 1] [--max-frames N] [--peer-cpu 0|none] [--out DIR]
#       SEQ... [-- ECVO RUN ARGS]
#
# For every sequence and round, in turn: `ecvo run SEQ --threads 1`, then the peer on
# the same frames through peers.py. Per frame, ecvo counts its preparation and its
# tracking (every MOTION call) as CPU time of its one compute thread (summary.json's
# pipeline.stages.work_cpu, per frame, so its median and p95 are exact; the wall-clock
# figure of the same work is beside it; reading the PNGs is not counted). A
# summary.json from before those figures falls back to the sums of the filter and
# tracker stages' wall-clock medians, means and p95s. The peer counts
# its odometry only (decoding not counted): opencv-* and open3d-* the process CPU time
# of making the frames and computing the motion, OpenCV on one thread
# (cv2.setNumThreads(1)), Open3D with OMP_NUM_THREADS=1; both bound to CPU --peer-cpu
# (default 0; `none` leaves the affinity alone), which is what keeps Open3D's oneTBB
# pool to the main thread; vors the thread CPU time of Tracker::track (vors-cam).
# The JSON also has ecvo's whole-process CPU per frame (bash's `time`: user + system of
# every thread, decoding included, an upper bound). Prints per round ecvo's and the
# peer's median / mean / p95 and the ratios peer / ecvo of the means and of the
# medians, then per sequence the median and range over the rounds of each ratio, and
# which kernel copies ecvo ran (summary.json's `simd`).
# Writes DIR/rounds.jsonl and DIR/bench.json (default DIR target/bench-vs-PEER).
# Same set-up as run-peers.sh (venv, vors-cam build, ECVO, PEERS_VENV, PEERS_CACHE).
set -euo pipefail

root=$(cd "$(dirname "$0")/../.." && pwd)
venv=${PEERS_VENV:-$root/target/peers-venv}
cache=${PEERS_CACHE:-$HOME/.cache/ecvo-peers}
ecvo=${ECVO:-$root/target/release/ecvo}
out=
rounds=3
step=1
max_frames=0
peer=opencv-rgbd
peer_cpu=0
seqs=()
extra=()
while [[ $# -gt 0 ]]; do
    case $1 in
        --rounds) rounds=$2; shift 2 ;;
        --frame-step) step=$2; shift 2 ;;
        --max-frames) max_frames=$2; shift 2 ;;
        --peer) peer=$2; shift 2 ;;
        --peer-cpu) peer_cpu=$2; shift 2 ;;
        --out) out=$2; shift 2 ;;
        --) shift; extra=("$@"); break ;;
        -h|--help) sed -n '2,/^set /{/^set /d;s/^# \{0,1\}//;p}' "$0"; exit 0 ;;
        -*) echo "unknown option $1" >&2; exit 2 ;;
        *) seqs+=("$1"); shift ;;
    esac
done
if [[ ${#seqs[@]} -eq 0 ]]; then
    echo "usage: $0 [--peer P] [--rounds N] [--frame-step N] [--max-frames N] [--peer-cpu N|none] [--out DIR] SEQ... [-- ECVO RUN ARGS]" >&2
    exit 2
fi
[[ $rounds =~ ^[1-9][0-9]*$ ]] || { echo "--rounds: a positive integer, got '$rounds'" >&2; exit 2; }
[[ $max_frames =~ ^[0-9]+$ ]] || { echo "--max-frames: a count, got '$max_frames'" >&2; exit 2; }
[[ $peer_cpu == none || $peer_cpu =~ ^[0-9]+$ ]] || { echo "--peer-cpu: a CPU number or none, got '$peer_cpu'" >&2; exit 2; }
out=${out:-$root/target/bench-vs-$peer}

# shellcheck source=setup.sh
. "$root/scripts/peers/setup.sh"
ensure_peers_venv "$venv"
ensure_ecvo "$root" "$ecvo"
peer_args=()
case $peer in
    opencv-*) ;;
    open3d-*) ensure_open3d "$venv" ;;
    vors) peer_args+=(--vors-cam "$(ensure_vors_cam "$root" "$cache")") ;;
    *) echo "--peer: one of peers.py's peers (opencv-rgbd, open3d-hybrid, vors, ...), got '$peer'" >&2; exit 2 ;;
esac
[[ $peer_cpu == none ]] || peer_args+=(--pin-cpu "$peer_cpu")
ecvo_args=(--threads 1 --frame-step "$step")
[[ $max_frames == 0 ]] || { ecvo_args+=(--max-frames "$max_frames"); peer_args+=(--max-frames "$max_frames"); }

mkdir -p "$out"
results=$out/rounds.jsonl
: > "$results"
echo "load average at start: $(cut -d' ' -f1-3 /proc/loadavg)" >&2
for seq in "${seqs[@]}"; do
    seq=${seq%/}
    name=$(basename "$seq")
    for r in $(seq 1 "$rounds"); do
        dir=$out/$name/round$r
        mkdir -p "$dir"
        # bash's `time` gives the whole process's user and system CPU (every thread,
        # PNG decoding and start-up included): an upper bound beside the stage times.
        TIMEFORMAT='%U %S'
        { time "$ecvo" run "$seq" "${ecvo_args[@]}" --out "$dir/ecvo" "${extra[@]}" \
            > "$dir/ecvo.log" 2>&1; } 2> "$dir/ecvo.cpu" \
            || { echo "ecvo run failed: $dir/ecvo.log" >&2; exit 1; }
        "$venv/bin/python" "$root/scripts/peers/peers.py" --ecvo "$ecvo" --peers "$peer" \
            --frame-steps "$step" "${peer_args[@]}" --out "$dir/$peer" "$seq" \
            > "$dir/$peer.log" 2>&1 || { echo "peers.py failed: $dir/$peer.log" >&2; exit 1; }
        # The record goes to rounds.jsonl, the round's line (stderr) to the terminal.
        "$venv/bin/python" "$root/scripts/peers/timing.py" round "$dir" "$name" "$r" "$peer" \
            >> "$results"
    done
done
echo "load average at end: $(cut -d' ' -f1-3 /proc/loadavg)" >&2

"$venv/bin/python" "$root/scripts/peers/timing.py" report "$results" "$out/bench.json" "$peer"
