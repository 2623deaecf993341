#!/usr/bin/env bash
# MOTION on aarch64 under qemu-user: the NEON lanes against the portable (plain array)
# lanes of the same code (`--cfg ecvo_portable_lanes`), criterion's `motion/*` bench of
# ecvo-core built twice with Debian's rustc for aarch64-unknown-linux-gnu (the set-up of
# test-core-aarch64.sh) and run in turn, alternating, ROUNDS times.
#
#   scripts/android/bench-core-aarch64.sh [ROUNDS=3] [FILTER=motion/320x180]
#
# Prints criterion's estimate per run and the portable/NEON ratio per round. Under qemu
# these are emulation times: the ratio says how much work the NEON build saves the
# emulator, not what a phone's core would give. Not part of CI (minutes).
set -euo pipefail
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
REPO="$(cd "$HERE/../.." && pwd)"
# shellcheck source=lib.sh
. "$HERE/lib.sh"
ROUNDS="${1:-3}"
FILTER="${2:-motion/320x180}"
[[ $ROUNDS =~ ^[1-9][0-9]*$ ]] || die "ROUNDS: a positive integer, got '$ROUNDS'"

# The toolchain test-core-aarch64.sh installs and checks.
"$HERE/test-core-aarch64.sh" --setup-only

build() { # $1: target dir, $2: extra RUSTFLAGS
  env -u RUSTUP_TOOLCHAIN -u RUSTC_WRAPPER -u CARGO_BUILD_TARGET \
    PATH="/usr/bin:$PATH" RUSTC=/usr/bin/rustc RUSTDOC=/usr/bin/rustdoc \
    RUSTFLAGS="$2" CARGO_TARGET_DIR="$1" \
    CARGO_TARGET_AARCH64_UNKNOWN_LINUX_GNU_LINKER=aarch64-linux-gnu-gcc \
    /usr/bin/cargo bench --target aarch64-unknown-linux-gnu -p ecvo-bench --bench stages \
    --no-run --message-format json 2>/dev/null \
    | python3 -c 'import json,sys
for l in sys.stdin:
    m = json.loads(l)
    if m.get("reason") == "compiler-artifact" and m["target"]["name"] == "stages" and m.get("executable"):
        print(m["executable"])' | tail -1
}
cd "$REPO"
log "building the bench twice for aarch64 (NEON, portable lanes)"
neon=$(build "$REPO/target/aarch64-bench-neon" "")
portable=$(build "$REPO/target/aarch64-bench-portable" "--cfg ecvo_portable_lanes")
[ -x "$neon" ] && [ -x "$portable" ] || die "bench build failed (neon '$neon', portable '$portable')"

run() { # $1: binary; prints criterion's point estimate in ms
  qemu-aarch64 "$1" --bench "$FILTER" --warm-up-time 1 --measurement-time 5 --sample-size 10 2>&1 \
    | python3 -c 'import re,sys
t = sys.stdin.read()
m = re.search(r"time:\s+\[\S+ \S+ (\S+) (\S+) \S+ \S+\]", t)
if not m: sys.exit("no criterion estimate in:\n" + t[-2000:])
v, u = float(m.group(1)), m.group(2)
print(v * {"ns": 1e-6, "µs": 1e-3, "us": 1e-3, "ms": 1.0, "s": 1e3}[u])'
}
ratios=()
for r in $(seq 1 "$ROUNDS"); do
  n=$(run "$neon"); p=$(run "$portable")
  q=$(python3 -c "print(f'{$p / $n:.2f}')")
  ratios+=("$q")
  echo "round $r: $FILTER NEON $n ms, portable $p ms, portable/NEON $q"
done
python3 -c "import statistics,sys; v=[float(x) for x in sys.argv[1:]]; print(f'portable/NEON under qemu: median {statistics.median(v):.2f} (min {min(v):.2f}, max {max(v):.2f}) over {len(v)} rounds')" "${ratios[@]}"
