#!/usr/bin/env bash
# Renders the depth-noise suite of issue 26, streams that expose where a fixed,
# Kinect-fitted depth-noise model and frame-to-frame chaining lose (150 frames each,
# seed 3):
#   - noise-free depth (`--noise none`: exact depth rounded to the millimetre, clean
#     intensity) with blank walls, texture contrast C = 0.02, 0.05 and 0.2: the slow
#     walk round the room, and the fast hand-held path (90 deg/s and 1 m/s peaks) in
#     front of a wall at 1 m and at 2 m (9 streams);
#   - the phone time-of-flight model (`--noise tof`: 1 mm + 0.3 % of z, flying pixels,
#     holes on weak returns) with the same blank walls at C = 0.02 and 0.2, slow walk
#     and fast at 2 m (4 streams);
#   - Kinect-noise far-depth hand-held orbits (`--motion orbit`) at 2, 3 and 4 m viewing
#     distance with peaks of 1 and 2 deg per frame (30 and 60 deg/s), at 320x180 for
#     2 m and at the Kinect's 640x480 for 3 m and 4 m (6 streams).
#
#   scripts/suite/make-noise-suite.sh OUTDIR
#
# Writes OUTDIR/<name>/ (TUM layout, camera.json, groundtruth.txt) and OUTDIR/suite.txt
# (one stream folder per line), for `ecvo run` and scripts/peers/run-peers.sh. Keep
# OUTDIR outside the repository. Environment: ECVO (the ecvo binary; default
# target/release/ecvo, built if missing), FRAMES (default 150), SEED (default 3).
set -euo pipefail

if [[ $# -ne 1 ]]; then
    echo "usage: $0 OUTDIR" >&2
    exit 2
fi
out=$1
root=$(cd "$(dirname "$0")/../.." && pwd)
ecvo=${ECVO:-$root/target/release/ecvo}
frames=${FRAMES:-150}
seed=${SEED:-3}
if [[ ! -x $ecvo ]]; then
    (cd "$root" && cargo build --release -p ecvo-cli)
fi
mkdir -p "$out"
: > "$out/suite.txt"
render() {
    local name=$1
    shift
    rm -rf "${out:?}/$name"
    "$ecvo" synth --out "$out/$name" --no-imu --frames "$frames" --seed "$seed" "$@" > /dev/null
    echo "$out/$name" >> "$out/suite.txt"
}
start=$(date +%s.%N)
for c in 0.02 0.05 0.2; do
    render "none_slow_c$c" --noise none --texture-contrast "$c"
    for depth in 1 2; do
        render "none_fast_${depth}m_c$c" --noise none --motion fast --depth "$depth" \
            --texture-contrast "$c"
    done
done
for c in 0.02 0.2; do
    render "tof_slow_c$c" --noise tof --texture-contrast "$c"
    render "tof_fast_2m_c$c" --noise tof --motion fast --depth 2 --texture-contrast "$c"
done
for depth in 2 3 4; do
    size=640x480
    [[ $depth == 2 ]] && size=320x180
    for deg in 1 2; do
        render "kinect_orbit_${depth}m_${deg}deg_$size" --noise kinect --motion orbit \
            --depth "$depth" --max-rot-speed $((deg * 30)) --size "$size"
    done
done
end=$(date +%s.%N)
echo "rendered $(wc -l < "$out/suite.txt") streams in $(echo "$end - $start" | bc) s into $out"
