#!/usr/bin/env bash
# The JVM tests of libecvo_jni: the Kotlin modules' tests plus the JNI boundary tests of
# rust/ecvo-jni/tests/kotlin (NativeBridgeTest and others), on a real JVM with -Xcheck:jni,
# against a host build of the library with the `test-hooks` feature (fault injection).
# Not part of `cargo test` (it needs a JDK and kotlinc, and builds the library a second
# time with another feature); .ci/run calls it.
#
#   scripts/jni-jvm-tests.sh [--filter TEXT]
#
# 1. builds libecvo_jni with `--features test-hooks` (release) and copies it to
#    <target>/jni-hooks (the next plain build of ecvo-jni recompiles that one crate);
# 2. replays testdata/synth_phone_320x180 through ecvo-pipeline and writes the frames
#    and the expected poses (`--example jvm_test_data`) to <target>/ecvo-jni-jvm-data;
# 3. runs scripts/kotlin/test-kotlin.sh with that library (on first use it downloads
#    kotlinc from npm, 90 MB, announced) and requires `N passed, 0 failed` with N >= 29,
#    no skipped NativeBridgeTest and no JNI warning.
# Niced: the machine is shared.
set -euo pipefail
cd "$(dirname "$0")/.."
REPO="$PWD"
FILTER=()
while [ $# -gt 0 ]; do
  case "$1" in
    --filter) FILTER=(--filter "${2:?--filter needs a value}"); shift 2 ;;
    -h|--help) sed -n '2,/^set -euo/p' "$0" | sed '$d' | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "[jni-jvm-tests] unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
command -v java >/dev/null || { echo "[jni-jvm-tests] java (JDK 17) is needed" >&2; exit 2; }

target=$(cargo metadata --format-version 1 --no-deps | python3 -c 'import json,sys; print(json.load(sys.stdin)["target_directory"])')
nice -n 5 cargo build --release -q -p ecvo-jni --lib --features test-hooks
lib="$target/jni-hooks"
mkdir -p "$lib"
cp "$target"/release/libecvo_jni.* "$lib"/ 2>/dev/null || true
ls "$lib"/libecvo_jni.so >/dev/null 2>&1 || ls "$lib"/libecvo_jni.dylib >/dev/null
data="$target/ecvo-jni-jvm-data"
nice -n 5 cargo run --release -q -p ecvo-jni --example jvm_test_data -- "$data"

log=$(mktemp)
trap 'rm -f "$log"' EXIT
set +e
ECVO_JNI_TEST_DATA="$data" ECVO_JNI_TEST_HOOKS=1 nice -n 5 bash scripts/kotlin/test-kotlin.sh \
  --native-lib "$lib" --extra-tests "$REPO/rust/ecvo-jni/tests/kotlin" --out "$target/ecvo-jni-kotlin" \
  ${FILTER[@]+"${FILTER[@]}"} 2>&1 | tee "$log"
rc=${PIPESTATUS[0]}
set -e
fail() { echo "[jni-jvm-tests] FAILED: $*" >&2; exit 1; }
[ "$rc" = 0 ] || fail "test-kotlin.sh exited $rc"
last=$(grep -E '^[0-9]+ passed, [0-9]+ failed$' "$log" | tail -1)
[ -n "$last" ] || fail "no 'N passed, N failed' line"
[[ "$last" == *" 0 failed" ]] || fail "$last"
! grep -q "WARNING in native method" "$log" || fail "-Xcheck:jni warned"
if [ ${#FILTER[@]} = 0 ]; then
  # The Kotlin API tests plus the 29 of NativeBridgeTest.
  [ "${last%% *}" -ge 29 ] || fail "$last: fewer than the 29 tests of NativeBridgeTest"
  ! grep -qE "SKIP io.ecvo.NativeBridgeTest|NativeBridgeTest\) \(assumption" "$log" \
    || fail "a NativeBridgeTest was skipped"
fi
echo "[jni-jvm-tests] ok: $last"
