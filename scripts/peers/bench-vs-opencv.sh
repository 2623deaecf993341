#!/usr/bin/env bash
# ecvo's time per frame against OpenCV's RGB-D odometry (or another peer of peers.py),
# measured in the same run, as a ratio (issue 11's check):
#
#   scripts/peers/bench-vs-opencv.sh [--rounds 3] [--frame-step 1] [--peer opencv-rgbd]
#                                    SEQ... [-- ECVO RUN ARGS]
#
# For every sequence and round, alternating: `ecvo run SEQ --threads 1` (ecvo's CPU
# per frame: the medians of its filter and tracker stages from summary.json, which
# cover preparation and every MOTION call; reading the PNGs and the point cloud are
# not counted), then the peer through peers.py (default opencv-rgbd, OpenCV's RGB-D
# odometry: the median CPU time of making the OdometryFrame, prepareFrame and compute,
# one thread; open3d-hybrid: Open3D's RGB-D odometry, making the RGBDImages and
# compute_rgbd_odometry, one OpenMP thread; decoding not counted). Prints one row per
# round and, per sequence, the median, min and max of the per-round ratio peer / ecvo,
# and which kernel copies ecvo ran (summary.json's `simd`: avx512, avx2, sse2, neon).
# Writes DIR/bench.json
# (default DIR target/bench-vs-opencv). Same set-up as run-peers.sh (venv, ECVO).
set -euo pipefail

root=$(cd "$(dirname "$0")/../.." && pwd)
venv=${PEERS_VENV:-$root/target/peers-venv}
ecvo=${ECVO:-$root/target/release/ecvo}
out=$root/target/bench-vs-opencv
rounds=3
step=1
peer=opencv-rgbd
seqs=()
extra=()
while [[ $# -gt 0 ]]; do
    case $1 in
        --rounds) rounds=$2; shift 2 ;;
        --frame-step) step=$2; shift 2 ;;
        --peer) peer=$2; shift 2 ;;
        --out) out=$2; shift 2 ;;
        --) shift; extra=("$@"); break ;;
        -h|--help) sed -n '2,18p' "$0"; exit 0 ;;
        -*) echo "unknown option $1" >&2; exit 2 ;;
        *) seqs+=("$1"); shift ;;
    esac
done
if [[ ${#seqs[@]} -eq 0 ]]; then
    echo "usage: $0 [--rounds N] [--frame-step N] [--peer P] [--out DIR] SEQ... [-- ECVO RUN ARGS]" >&2
    exit 2
fi
[[ $rounds =~ ^[1-9][0-9]*$ ]] || { echo "--rounds: a positive integer, got '$rounds'" >&2; exit 2; }

# shellcheck source=setup.sh
. "$root/scripts/peers/setup.sh"
ensure_peers_venv "$venv"
ensure_ecvo "$root" "$ecvo"
case $peer in
    opencv-*) ;;
    open3d-*) ensure_open3d "$venv" ;;
    *) echo "--peer: one of peers.py's opencv-* or open3d-* peers, got '$peer'" >&2; exit 2 ;;
esac

mkdir -p "$out"
results=$out/rounds.tsv
: > "$results"
for seq in "${seqs[@]}"; do
    seq=${seq%/}
    name=$(basename "$seq")
    for r in $(seq 1 "$rounds"); do
        dir=$out/$name/round$r
        mkdir -p "$dir"
        "$ecvo" run "$seq" --threads 1 --frame-step "$step" --out "$dir/ecvo" "${extra[@]}" \
            > "$dir/ecvo.log" 2>&1 || { echo "ecvo run failed: $dir/ecvo.log" >&2; exit 1; }
        "$venv/bin/python" "$root/scripts/peers/peers.py" --ecvo "$ecvo" --peers "$peer" \
            --frame-steps "$step" --out "$dir/$peer" "$seq" > "$dir/$peer.log" 2>&1 \
            || { echo "peers.py failed: $dir/$peer.log" >&2; exit 1; }
        "$venv/bin/python" - "$dir" "$name" "$r" "$peer" >> "$results" <<'EOF'
import json, sys
d, name, r, peer = sys.argv[1:]
summary = json.load(open(f"{d}/ecvo/summary.json"))
s = summary["ms_per_frame"]
e = s["filter"]["median"] + s["tracker"]["median"]
o = json.load(open(f"{d}/{peer}/peers.json"))["rows"][0]["ms_per_frame_median"]
print(f"{name}\t{r}\t{e:.3f}\t{o:.3f}\t{o / e:.3f}\t{summary.get('simd', '?')}")
EOF
        tail -1 "$results" | awk -F'\t' -v p="$peer" '{printf "%s round %s: ecvo (%s) %.2f ms/frame, %s %.2f ms/frame, ratio %.2f\n", $1, $2, $6, $3, p, $4, $5}'
    done
done

"$venv/bin/python" - "$results" "$out/bench.json" "$peer" <<'EOF'
import json, statistics, sys
peer = sys.argv[3]
rows = [l.rstrip("\n").split("\t") for l in open(sys.argv[1]) if l.strip()]
by = {}
simd = sorted({row[5] for row in rows})
for name, r, e, o, q, _ in rows:
    by.setdefault(name, []).append((float(e), float(o), float(q)))
print(f"\necvo's kernels: {', '.join(simd)}")
print(f"\n| sequence | rounds | ecvo ms/frame, median (min-max) | {peer} ms/frame | {peer} / ecvo, median (min-max) |")
print("|---|---|---|---|---|")
out = {}
for name, v in by.items():
    e, o, q = zip(*v)
    f = lambda x: f"{statistics.median(x):.2f} ({min(x):.2f}-{max(x):.2f})"
    print(f"| {name} | {len(v)} | {f(e)} | {f(o)} | **{f(q)}** |")
    out[name] = {"peer": peer, "ecvo_ms": e, "peer_ms": o, "ratio": q,
                 "ratio_median": statistics.median(q), "ecvo_simd": simd}
json.dump(out, open(sys.argv[2], "w"), indent=2)
EOF
