#!/usr/bin/env bash
# Downloads TUM RGB-D sequences from their official site (on a machine with internet), checks
# them, writes their camera.json, and makes the derived copies the project's tests read.
#
#   scripts/datasets/get-tum.sh [--out DIR] [--half] [--gray] [--first N | --first-pairs N] SEQ...
#   scripts/datasets/get-tum.sh --tests DIR
#
# SEQ: a sequence name, `fr1/xyz`, `freiburg1_xyz` or `rgbd_dataset_freiburg1_xyz`, fetched
#      from https://cvg.cit.tum.de/rgbd/dataset/ (the size is said before downloading); or a
#      local folder in the TUM layout (rgb.txt, depth.txt, rgb/, depth/), used as it is.
# --out DIR   where the sequences go (default: ../shared/datasets beside the repository)
# --half      also write the 320x240 copy `tum_<seq>_half`: gray = mean of each 2x2 block;
#             depth = mean of a 2x2 block when all four pixels are valid and agree within
#             3 %, else 0; intrinsics f/2 and (c + 0.5)/2 - 0.5 (as ../shared/datasets/README.md)
# --gray      write the colour images as 8-bit gray (0.299 R + 0.587 G + 0.114 B, rounded)
# --first N   keep only the first N entries of each list
# --first-pairs N  keep only the first N colour/depth pairs (|dt| < 0.02 s)
# --tests DIR the folders the tests look for (then run them: ECVO_DATASETS=DIR scripts/test.sh):
#             tum_fr1_xyz_full300 (fr1/xyz, the first 300 entries of each list, gray),
#             tum_fr1_xyz_half, tum_fr1_desk_clip9 (fr1/desk, first 9 pairs, colour),
#             tum_fr1_desk_half, and
#             phone_tof_samples (two DEPTH16 frames from github.com/remmel/recorder-3d)
#
# Each sequence is checked: the archive unpacks, both lists parse, every listed image exists
# and is a PNG of 640x480 (colour 8-bit RGB, depth 16-bit gray), groundtruth.txt is there.
# The derivations are ecvo_io::derive, run as `cargo run --release -p ecvo-io --example derive`.
set -euo pipefail
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
REPO="$(cd "$HERE/../.." && pwd)"
BASE_URL="${TUM_BASE_URL:-https://cvg.cit.tum.de/rgbd/dataset}"

log() { echo "[get-tum] $*" >&2; }
die() { echo "[get-tum] error: $*" >&2; exit 2; }
usage() { sed -n '2,/^set -euo/p' "$0" | sed '$d' | sed 's/^# \{0,1\}//'; }

OUT="$REPO/../shared/datasets"
HALF=0; GRAY=0; FIRST=""; FIRST_FLAG=--first; TESTS=""; SEQS=()
while [ $# -gt 0 ]; do
  case "$1" in
    --out) OUT="${2:?--out needs a folder}"; shift 2 ;;
    --half) HALF=1; shift ;;
    --gray) GRAY=1; shift ;;
    --first|--first-pairs) FIRST_FLAG="$1"; FIRST="${2:?$1 needs a number}"; shift 2
             [[ "$FIRST" =~ ^[1-9][0-9]*$ ]] || die "$FIRST_FLAG needs a positive number, not '$FIRST'" ;;
    --tests) TESTS="${2:?--tests needs a folder}"; shift 2 ;;
    -h|--help) usage; exit 0 ;;
    -*) die "unknown option '$1' (see --help)" ;;
    *) SEQS+=("$1"); shift ;;
  esac
done
[ -n "$TESTS" ] || [ ${#SEQS[@]} -gt 0 ] || { usage >&2; exit 2; }

derive() { # SRC DST [options]: ecvo_io::derive
  local src="$1" dst="$2"; shift 2
  if [ -e "$dst" ]; then log "$dst exists: left as it is"; return 0; fi
  (cd "$REPO" && nice -n 5 cargo run --release -q -p ecvo-io --example derive -- "$src" "$dst.partial" "$@") \
    || { rm -rf "$dst.partial"; die "deriving $dst failed"; }
  mv "$dst.partial" "$dst"
}

# fr1/xyz -> freiburg1_xyz
seq_name() {
  local s="${1#rgbd_dataset_}"
  s="${s/#fr/freiburg}"; s="${s/\//_}"
  [[ "$s" =~ ^freiburg[123]_[a-z0-9_]+$ ]] || die "'$1' is not a TUM sequence name (e.g. fr1/xyz) nor a folder"
  echo "$s"
}

# The freiburg cameras' published intrinsics (640x480, depth 5000 units per metre).
camera_json() { # freiburgN DIR
  local fx fy cx cy
  case "$1" in
    freiburg1) fx=517.3 fy=516.5 cx=318.6 cy=255.3 ;;
    freiburg2) fx=520.9 fy=521.0 cx=325.1 cy=249.7 ;;
    freiburg3) fx=535.4 fy=539.2 cx=320.1 cy=247.6 ;;
  esac
  printf '{"width": 640, "height": 480, "fx": %s, "fy": %s, "cx": %s, "cy": %s, "depth_scale": 5000.0}\n' \
    "$fx" "$fy" "$cx" "$cy" > "$2/camera.json"
}

# The checks of a TUM-layout folder; prints the number of colour and depth images.
check_sequence() { # DIR
  python3 - "$1" <<'PY'
import os, struct, sys
d = sys.argv[1]
def entries(name):
    out = []
    with open(os.path.join(d, name)) as f:
        for k, line in enumerate(f, 1):
            t = line.split()
            if not t or t[0].startswith('#'):
                continue
            if len(t) != 2:
                sys.exit(f"{d}/{name}:{k}: expected `timestamp filename`")
            float(t[0])
            out.append(t[1])
    return out
def png(path, want):
    with open(path, 'rb') as f:
        head = f.read(26)
    if head[:8] != b'\x89PNG\r\n\x1a\n' or head[12:16] != b'IHDR':
        sys.exit(f"{path}: not a PNG")
    w, h, depth, colour = struct.unpack('>IIBB', head[16:26])
    if (w, h) != (640, 480) or (depth, colour) not in want:
        sys.exit(f"{path}: {w}x{h}, bit depth {depth}, colour type {colour}: not what TUM publishes")
rgb, dep = entries('rgb.txt'), entries('depth.txt')
for f in rgb:
    png(os.path.join(d, f), {(8, 2), (8, 0)})
for f in dep:
    png(os.path.join(d, f), {(16, 0)})
if not rgb or not dep:
    sys.exit(f"{d}: an empty list")
if not os.path.isfile(os.path.join(d, 'groundtruth.txt')):
    sys.exit(f"{d}: no groundtruth.txt")
print(len(rgb), len(dep))
PY
}

# Downloads and unpacks one sequence into $OUT/rgbd_dataset_<name>; prints that folder.
fetch() { # freiburgN_name
  local name="$1" dir="$OUT/rgbd_dataset_$1"
  local url="$BASE_URL/${name%%_*}/rgbd_dataset_$name.tgz"
  if [ -f "$dir/.complete" ]; then log "$dir: already there"; echo "$dir"; return 0; fi
  command -v curl >/dev/null || die "curl is needed to download"
  local size
  size=$(curl -sIL "$url" | tr -d '\r' | awk 'tolower($1)=="content-length:" {n=$2} END {print n}')
  [ -n "$size" ] || die "$url: no answer (is there internet here?)"
  log "downloading $url: $(( size / 1000000 )) MB"
  mkdir -p "$OUT"
  curl -fL --retry 3 -o "$dir.tgz.partial" "$url" || die "downloading $url failed"
  [ "$(stat -c %s "$dir.tgz.partial")" = "$size" ] || die "$url: the download is incomplete"
  tar -xzf "$dir.tgz.partial" -C "$OUT" || die "$dir.tgz: not a complete archive"
  rm -f "$dir.tgz.partial"
  [ -d "$dir" ] || die "$url did not unpack into $dir"
  touch "$dir/.complete"
  echo "$dir"
}

# One SEQ argument: fetched (or the local folder), checked, camera.json; then the copies asked for.
one() {
  local arg="$1" dir short counts opts=()
  if [ -d "$arg" ]; then
    dir="$(cd "$arg" && pwd)"; short="$(basename "$dir")"; short="${short#rgbd_dataset_}"
    [ -f "$dir/camera.json" ] || case "$short" in
      freiburg[123]_*) camera_json "${short%%_*}" "$dir" ;;
      *) die "$dir has no camera.json (and its name does not say which freiburg camera)" ;;
    esac
  else
    short="$(seq_name "$arg")"
    dir="$(fetch "$short")"
    [ -f "$dir/camera.json" ] || camera_json "${short%%_*}" "$dir"
  fi
  counts=$(check_sequence "$dir") || die "$dir failed its checks"
  log "$dir: ${counts% *} colour and ${counts#* } depth images, camera.json written"
  local tag="tum_${short/freiburg/fr}"
  case "$short" in tum_*) tag="$short" ;; esac   # a local copy already named tum_...
  [ -n "$FIRST" ] && opts+=("$FIRST_FLAG" "$FIRST")
  if [ "$GRAY" = 1 ] || [ -n "$FIRST" ]; then
    local name="$tag${FIRST:+_first$FIRST}$([ "$GRAY" = 1 ] && echo _gray)"
    [ "$FIRST_FLAG" = --first-pairs ] && name="${name/_first/_pairs}"
    derive "$dir" "$OUT/$name" ${opts[@]+"${opts[@]}"} $([ "$GRAY" = 1 ] && echo --gray)
  fi
  [ "$HALF" = 1 ] && derive "$dir" "$OUT/${tag}_half" --half ${opts[@]+"${opts[@]}"}
  return 0
}

if [ -n "$TESTS" ]; then
  OUT="$TESTS"
  xyz="$(fetch freiburg1_xyz)"; desk="$(fetch freiburg1_desk)"
  for d in "$xyz" "$desk"; do
    s="$(basename "$d")"; s="${s#rgbd_dataset_}"
    [ -f "$d/camera.json" ] || camera_json "${s%%_*}" "$d"
    check_sequence "$d" >/dev/null || die "$d failed its checks"
  done
  derive "$xyz" "$OUT/tum_fr1_xyz_full300" --first 300 --gray
  derive "$xyz" "$OUT/tum_fr1_xyz_half" --half
  derive "$desk" "$OUT/tum_fr1_desk_clip9" --first-pairs 9
  derive "$desk" "$OUT/tum_fr1_desk_half" --half
  tof="$OUT/phone_tof_samples"
  if [ ! -e "$tof" ]; then
    raw="https://raw.githubusercontent.com/remmel/recorder-3d/ce133688083bf60b73b47534065b90192a813647"
    log "downloading phone_tof_samples from $raw (5 files, about 1 MB)"
    mkdir -p "$tof.partial"
    for f in 00000012_depth16.bin 00000012_depth.png 00000012_image.jpg 00003795_depth16.bin 00003795_depth16.bin.png; do
      curl -fsSL --retry 3 -o "$tof.partial/$f" "$raw/Recorder3D/src/test/resources/$f" || die "downloading $f failed"
    done
    curl -fsSL --retry 3 -o "$tof.partial/LICENSE" "$raw/LICENSE" || die "downloading the licence failed"
    mv "$tof.partial" "$tof"
  fi
  log "done: ECVO_DATASETS=$OUT scripts/test.sh runs the dataset tests"
  exit 0
fi

for s in "${SEQS[@]}"; do one "$s"; done
