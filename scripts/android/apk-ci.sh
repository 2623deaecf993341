#!/usr/bin/env bash
# CI entry for the APK (issue 25), run after ci-cross-check.sh (which leaves the three ABIs'
# libecvo_jni.so in target/android/jniLibs; build-apk.sh reuses them):
#   1. build-apk.sh                   android-app/app/build/outputs/apk/debug/app-debug.apk
#   2. check-apk.sh                   structural checks of that APK
#   3. check-apk.sh --selftest        each check rejects a broken copy, an intact copy passes
#   4. test-api-levels.sh             the API-level check's self-tests (fails on Cleaner.create())
#   5. desugar/test-desugar.sh        LambdaDesugar on the whole kotlin-stdlib, same JVM output
#   6. check-api-levels.sh            the API-level check on the APK's dex (minSdk 26)
# Every step runs even when an earlier check failed (except after a failed build); the times
# are printed at the end; the exit status is non-zero when any step failed.
#
# Usage: scripts/android/apk-ci.sh [--jni-libs DIR]
set -euo pipefail
{
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
REPO="$(cd "$HERE/../.." && pwd)"
ECVO_LOG_TAG=apk-ci
# shellcheck source=lib.sh
. "$HERE/lib.sh"
BUILD_ARGS=()
while [ $# -gt 0 ]; do
  case "$1" in
    --jni-libs) BUILD_ARGS+=(--jni-libs "${2:?--jni-libs needs a folder}"); shift 2 ;;
    -h|--help) sed -n '2,/^set -euo/p' "$0" | sed '$d' | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) die "unknown argument '$1' (see --help)" ;;
  esac
done
APK="$REPO/android-app/app/build/outputs/apk/debug/app-debug.apk"
trap 'rc=$?; print_times >&2; [ $rc -eq 0 ] || echo "apk-ci: FAILED (exit $rc)" >&2' EXIT
T_ALL=$EPOCHREALTIME
failed=()
step() { local label="$1"; shift; timed "$label" "$@" || failed+=("$label"); }

timed "build-apk.sh" bash "$HERE/build-apk.sh" ${BUILD_ARGS[@]+"${BUILD_ARGS[@]}"} --out "$APK"
step "check-apk.sh" bash "$HERE/check-apk.sh" "$APK"
step "check-apk.sh --selftest" bash "$HERE/check-apk.sh" --selftest "$APK"
step "test-api-levels.sh (probes)" bash "$HERE/test-api-levels.sh"
step "desugar/test-desugar.sh" bash "$HERE/desugar/test-desugar.sh"
step "check-api-levels.sh (the APK)" bash "$HERE/check-api-levels.sh" "$APK"

STEP_TIMES+=("$(printf '%-44s %7.1f s' "TOTAL" "$(awk -v a="$T_ALL" -v b="$EPOCHREALTIME" 'BEGIN{print b-a}')")")
if [ ${#failed[@]} -gt 0 ]; then die "failed: ${failed[*]}"; fi
log "OK: $APK ($(stat -c %s "$APK") bytes) built and checked"
exit 0
}
