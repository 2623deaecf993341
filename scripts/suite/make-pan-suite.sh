#!/usr/bin/env bash
# Renders the fast in-place pan suite of issue 47: `ecvo synth --motion pan` (the camera
# standing at the centre of the hall, panning round its walls at a viewing distance of
# 2.5 m, the pan rate swinging between 0 and the peak twice every 5 s) at peaks of 60,
# 120 and 200 deg/s, with the phone-like noise, 150 frames (5 s) each, and each with
# the imu.txt `ecvo synth` writes: a SIMULATED phone gyroscope and accelerometer
# (200-400 Hz, datasheet noise and turn-on bias, a camera-IMU rotation of 2-5 deg and
# a 5-20 ms time offset, all in camera.json).
#
#   scripts/suite/make-pan-suite.sh OUTDIR
#
# Writes OUTDIR/pan_<deg>/ and OUTDIR/suite.txt (one stream folder per line). `ecvo
# run` uses the imu.txt; `--no-imu` tracks without it. Keep OUTDIR outside the
# repository. Environment: ECVO (the ecvo binary; default target/release/ecvo, built
# if missing), RATES (default "60 120 200"), FRAMES (default 150), SEED (default 3),
# DEPTH_DELAY_MS (default 0: each depth image taken that much after its intensity, as
# a Kinect's unsynchronised streams; `ecvo run` turns it back with the gyro).
set -euo pipefail

if [[ $# -ne 1 ]]; then
    echo "usage: $0 OUTDIR" >&2
    exit 2
fi
out=$1
root=$(cd "$(dirname "$0")/../.." && pwd)
ecvo=${ECVO:-$root/target/release/ecvo}
rates=${RATES:-60 120 200}
frames=${FRAMES:-150}
seed=${SEED:-3}
delay=${DEPTH_DELAY_MS:-0}

if [[ ! -x $ecvo ]]; then
    (cd "$root" && cargo build --release -p ecvo-cli)
fi
mkdir -p "$out"
: > "$out/suite.txt"
for deg in $rates; do
    dir=$out/pan_$deg
    rm -rf "$dir"
    "$ecvo" synth --out "$dir" --motion pan --max-rot-speed "$deg" --depth 2.5 \
        --noise phone --frames "$frames" --seed "$seed" --depth-delay-ms "$delay" > /dev/null
    echo "$dir" >> "$out/suite.txt"
done
echo "rendered $(wc -l < "$out/suite.txt") pan streams into $out"
