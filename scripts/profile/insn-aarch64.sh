#!/usr/bin/env bash
# Instructions per frame of ecvo and of visual-odometry-rs (vors) on aarch64, counted
# under qemu-user with QEMU's `insn` TCG plugin (issue 30). Not a time: a count of the
# guest instructions each engine executes on the same frames, which the x86 timings
# cannot give for a phone's core.
#
#   scripts/profile/insn-aarch64.sh [SEQ=<datasets>/tum_fr1_xyz_half] [FRAMES=30]
#
# Set-up (installed once): the aarch64 toolchain of test-core-aarch64.sh (Debian's rustc
# with its arm64 std, aarch64-linux-gnu-gcc, qemu-user); the plugin built from the
# Debian source of the installed qemu-user (`apt-get source`, a deb-src entry added
# when there is none; two files of it are compiled: tests/plugin/insn.c against
# include/qemu/qemu-plugin.h), with glib.
#
# Each engine runs on the first FRAMES and the first 2 x FRAMES associated frames of SEQ,
# one compute thread, each time twice: tracking, and only reading and decoding the same
# images. Tracking minus decoding is the engine's count; the difference between the two
# lengths, divided by FRAMES, is its count per frame without the start-up (allocation,
# threads, the first frame), which is printed too. ecvo is the offline pipeline
# of one compute thread and no geometry stage (as `ecvo run --threads 1`: the filter
# stage without normals, the tracker, defaults of `Config::new`), through
# rust/ecvo-pipeline/examples/throughput.rs. vors is `Tracker::track` (and the first
# frame's `init`) through scripts/peers/vors-cam, with the settings of vors_track.
set -euo pipefail
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
REPO="$(cd "$HERE/../.." && pwd)"
# shellcheck source=../android/lib.sh
. "$REPO/scripts/android/lib.sh"
_ecvo_tag=insn-aarch64
DATASETS="${ECVO_DATASETS:-$REPO/../shared/datasets}"
SEQ="${1:-$DATASETS/tum_fr1_xyz_half}"
FRAMES="${2:-30}"
[[ $FRAMES =~ ^[1-9][0-9]*$ ]] || die "FRAMES: a positive integer, got '$FRAMES'"
[ -f "$SEQ/rgb.txt" ] && [ -f "$SEQ/depth.txt" ] && [ -f "$SEQ/camera.json" ] \
  || die "$SEQ: not a TUM-layout sequence (rgb.txt, depth.txt, camera.json)"
SEQ="$(cd "$SEQ" && pwd)"
WORK="$REPO/target/insn-aarch64"
mkdir -p "$WORK"

"$REPO/scripts/android/test-core-aarch64.sh" --setup-only
ensure_debs libglib2.0-dev pkg-config xz-utils

# The plugin, from the source of the qemu-user that runs it (the plugin API is checked
# against the emulator's version at load).
PLUGIN="$WORK/libinsn.so"
if [ ! -f "$PLUGIN" ]; then
  src_version="$(dpkg-query -W -f='${source:Version}' qemu-user)"
  mkdir -p "$WORK/qemu-src"
  if ! (cd "$WORK/qemu-src" && apt-get source --download-only "qemu=$src_version" >/dev/null 2>&1); then
    codename="$(. /etc/os-release && echo "$VERSION_CODENAME")"
    log "adding a deb-src entry for $codename (Debian's qemu source)"
    cat > /etc/apt/sources.list.d/ecvo-deb-src.sources <<EOF
Types: deb-src
URIs: http://deb.debian.org/debian
Suites: $codename $codename-updates
Components: main
Signed-By: /usr/share/keyrings/debian-archive-keyring.gpg
EOF
    apt-get update -qq
    (cd "$WORK/qemu-src" && apt-get source --download-only "qemu=$src_version" >/dev/null) \
      || die "apt-get source qemu=$src_version failed"
  fi
  orig="$(ls "$WORK"/qemu-src/qemu_*.orig.tar.xz | head -1)"
  top="$(tar tf "$orig" | head -1 | cut -d/ -f1 || true)"  # head closes the pipe early
  tar xf "$orig" -C "$WORK/qemu-src" "$top/tests/plugin/insn.c" "$top/include/qemu/qemu-plugin.h"
  # shellcheck disable=SC2046
  gcc -shared -fPIC -O2 -I"$WORK/qemu-src/$top/include/qemu" $(pkg-config --cflags glib-2.0) \
    "$WORK/qemu-src/$top/tests/plugin/insn.c" -o "$PLUGIN" $(pkg-config --libs glib-2.0)
  log "built $PLUGIN from $top (qemu-user $src_version)"
fi

# Debian's cargo for aarch64, as test-core-aarch64.sh runs it.
dcargo() { # $1: target dir, rest: cargo arguments
  local tdir="$1"; shift
  env -u RUSTUP_TOOLCHAIN -u RUSTC_WRAPPER -u RUSTFLAGS -u CARGO_BUILD_TARGET \
    PATH="/usr/bin:$PATH" RUSTC=/usr/bin/rustc RUSTDOC=/usr/bin/rustdoc CARGO_TARGET_DIR="$tdir" \
    CARGO_TARGET_AARCH64_UNKNOWN_LINUX_GNU_LINKER=aarch64-linux-gnu-gcc \
    /usr/bin/cargo build --release --quiet --target aarch64-unknown-linux-gnu "$@"
}
log "building ecvo's throughput example and vors-cam for aarch64"
(cd "$REPO" && dcargo "$REPO/target/aarch64-insn" -p ecvo-pipeline --example throughput)
(cd "$REPO/scripts/peers/vors-cam" && dcargo "$REPO/target/aarch64-insn-vors" --locked)
ECVO_BIN="$REPO/target/aarch64-insn/aarch64-unknown-linux-gnu/release/examples/throughput"
VORS_BIN="$REPO/target/aarch64-insn-vors/aarch64-unknown-linux-gnu/release/vors-cam"

# The same frames for vors: the first 2 x FRAMES pairs, paired as ecvo's reader pairs them.
ASSOC="$WORK/vors-associations.txt"
REPO_PEERS="$REPO/scripts/peers" python3 - "$SEQ" "$((2 * FRAMES))" "$ASSOC" <<'EOF'
import os, sys
sys.path.insert(0, os.environ["REPO_PEERS"])
from assoc import sequence_pairs
seq, n, out = sys.argv[1], int(sys.argv[2]), sys.argv[3]
pairs = sequence_pairs(seq)
if len(pairs) < n:
    sys.exit(f"{seq}: {len(pairs)} associated frames, fewer than {n}")
with open(out, "w") as f:
    for (t_rgb, rgb), (t_d, depth) in pairs[:n]:
        f.write(f"{t_d:.6f} {os.path.join(seq, depth)} {t_rgb:.6f} {os.path.join(seq, rgb)}\n")
EOF

count() { # $1: label, rest: command; prints the guest instructions of the whole run
  local label="$1"; shift
  local logf="$WORK/$label.insn.log"
  qemu-aarch64 -plugin "$PLUGIN" -d plugin -D "$logf" "$@" >"$WORK/$label.out" 2>"$WORK/$label.err" \
    || die "$label failed (exit $?): $(tail -3 "$WORK/$label.err")"
  local n
  n="$(sed -n 's/^total insns: \([0-9]*\)$/\1/p' "$logf")"
  [ -n "$n" ] || die "$label: no 'total insns' in $logf"
  echo "$n"
}
N2=$((2 * FRAMES))
log "counting (8 emulated runs: $FRAMES and $N2 frames of $SEQ, tracking and decoding only)"
head -n "$FRAMES" "$ASSOC" > "$WORK/vors-associations-1.txt"
cp "$ASSOC" "$WORK/vors-associations-2.txt"
res=()
for k in 1 2; do
  n=$FRAMES; [ "$k" = 2 ] && n=$N2
  a="$WORK/vors-associations-$k.txt"
  res+=("$(count "ecvo-track-$k" "$ECVO_BIN" "$SEQ" --frames "$n" --only pipeline --threads 1)")
  res+=("$(count "ecvo-decode-$k" "$ECVO_BIN" "$SEQ" --frames "$n" --only decode)")
  res+=("$(count "vors-track-$k" "$VORS_BIN" "$SEQ/camera.json" "$a")")
  res+=("$(count "vors-decode-$k" "$VORS_BIN" --decode-only "$SEQ/camera.json" "$a")")
  [ "$(grep -c . "$WORK/vors-track-$k.out")" = "$n" ] \
    || die "vors-cam wrote $(grep -c . "$WORK/vors-track-$k.out") poses for $n frames"
done
python3 - "$SEQ" "$FRAMES" "${res[@]}" <<'PY'
import os, sys
seq, n = os.path.basename(sys.argv[1]), int(sys.argv[2])
et1, ed1, vt1, vd1, et2, ed2, vt2, vd2 = (int(x) for x in sys.argv[3:11])
print(f"{seq}: aarch64 guest instructions (qemu-user insn plugin), millions per frame")
print("  whole run minus decoding, divided by the frames (start-up included):")
for m, (t, d) in ((n, (et1, ed1)), (2 * n, (et2, ed2))):
    print(f"    ecvo, {m} frames: {(t - d) / m / 1e6:.2f}")
for m, (t, d) in ((n, (vt1, vd1)), (2 * n, (vt2, vd2))):
    print(f"    vors, {m} frames: {(t - d) / m / 1e6:.2f}")
e = ((et2 - ed2) - (et1 - ed1)) / n
v = ((vt2 - vd2) - (vt1 - vd1)) / n
print(f"  per frame, frames {n + 1}-{2 * n} (the difference of the two runs, no start-up):")
print(f"    ecvo {e / 1e6:.2f}, vors {v / 1e6:.2f}, vors / ecvo {v / e:.3f}")
PY
