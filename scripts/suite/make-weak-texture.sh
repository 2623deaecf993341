#!/usr/bin/env bash
# Renders the weak-texture streams: `ecvo synth --texture-contrast C` (the room's
# texture contrast times C, towards blank walls; the per-face shading stays), 150
# frames each, seed 3:
#   - the slow walk around the room with the phone noise model at C = 1, 0.2, 0.05 and
#     0.02, and with the Kinect model at 0.02;
#   - the fast hand-held path (90 deg/s and 1 m/s peaks) in front of a wall at 1 m and
#     2 m, phone noise, at C = 0.2 and 0.05.
#
#   scripts/suite/make-weak-texture.sh OUTDIR
#
# Writes OUTDIR/<name>/ (TUM layout, camera.json, groundtruth.txt) and OUTDIR/suite.txt
# (one stream folder per line), for `ecvo run` and scripts/peers/run-peers.sh. Keep
# OUTDIR outside the repository. ECVO overrides the binary (default
# target/release/ecvo, built if missing).
set -euo pipefail

if [[ $# -ne 1 ]]; then
    echo "usage: $0 OUTDIR" >&2
    exit 2
fi
out=$1
root=$(cd "$(dirname "$0")/../.." && pwd)
ecvo=${ECVO:-$root/target/release/ecvo}
if [[ ! -x $ecvo ]]; then
    (cd "$root" && cargo build --release -p ecvo-cli)
fi
mkdir -p "$out"
: > "$out/suite.txt"
render() {
    local name=$1
    shift
    rm -rf "${out:?}/$name"
    "$ecvo" synth --out "$out/$name" --no-imu --frames 150 --seed 3 "$@" > /dev/null
    echo "$out/$name" >> "$out/suite.txt"
}
for c in 1 0.2 0.05 0.02; do
    render "slow_phone_c$c" --noise phone --texture-contrast "$c"
done
render slow_kinect_c0.02 --noise kinect --texture-contrast 0.02
for depth in 1 2; do
    for c in 0.2 0.05; do
        render "fast_phone_${depth}m_c$c" --noise phone --motion fast --depth "$depth" \
            --texture-contrast "$c"
    done
done
echo "rendered $(wc -l < "$out/suite.txt") streams into $out"
