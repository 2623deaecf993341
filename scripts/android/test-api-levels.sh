#!/usr/bin/env bash
# Self-tests of the API-level check (api_levels.py), on real dex files made here:
#   0. test_api_levels.py (unit tests: descriptors, type matching, the guard dataflow)
#   1. api-probes/cleaner: one line calling java.lang.ref.Cleaner.create() -> the check must FAIL
#   2. api-probes/guarded: the same call under `SDK_INT >= 33`             -> the check must PASS
#   3. api-probes/cases: a finding in every function named bad*, none in the ones named ok*
# The probes are compiled like the app in build-apk.sh (kotlinc -jvm-target 1.8
# -Xlambdas=class, dx --min-sdk-version=26), against a stand-in android.os.Build.
#
# Usage: scripts/android/test-api-levels.sh
# Needs what build-apk.sh installs (run it first; apk-ci.sh does): kotlinc, the bullseye dx and
# API 23 jar in ECVO_APK_CACHE, @nativescript/types-android in ANDROID_TYPES_CACHE.
set -euo pipefail
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
REPO="$(cd "$HERE/../.." && pwd)"
ECVO_LOG_TAG=test-api-levels
# shellcheck source=lib.sh
. "$HERE/lib.sh"
CACHE="${ECVO_APK_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/ecvo/apk-tools}"
DX_JAR="$CACHE/bullseye/root/usr/share/java/com.android.dx.jar"
ANDROID23="$CACHE/bullseye/root/usr/share/java/com.android.android-23.jar"
TYPES="${ANDROID_TYPES_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/ecvo/android-types}"
DTS="$TYPES/node_modules/@nativescript/types-android/lib/android/android-platform-21-37-merged.d.ts"
KOTLINC="${KOTLINC:-${KOTLINC_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/ecvo/kotlinc}/node_modules/kotlin-compiler/bin/kotlinc}"
for f in "$DX_JAR" "$ANDROID23" "$DTS" "$KOTLINC"; do
  [ -e "$f" ] || die "missing $f (run scripts/android/build-apk.sh first)"
done
W="$REPO/target/api-probes"
rm -rf "$W"; mkdir -p "$W/fake" "$W/classes"
P="$HERE/api-probes"
fails=0; passes=0
ok() { passes=$((passes + 1)); log "ok: $*"; }
bad() { fails=$((fails + 1)); log "FAILED: $*"; }

log "unit tests (test_api_levels.py)"
if (cd "$HERE" && python3 -m unittest -q test_api_levels); then ok "unit tests"; else bad "unit tests"; fi

javac -nowarn --release 8 -d "$W/fake" "$P/fake-sdk/android/os/Build.java" || die "javac Build.java failed"
log "kotlinc: the probes"
"$KOTLINC" -jvm-target 1.8 -no-reflect -Xlambdas=class -Xsam-conversions=class -nowarn -cp "$W/fake" \
  -d "$W/classes" "$P/cleaner" "$P/guarded" "$P/cases" >"$W/kotlinc.log" 2>&1 \
  || { cat "$W/kotlinc.log" >&2; die "kotlinc failed on the probes"; }

# dex one probe package (kotlin-stdlib stays outside: its references are resolved as missing
# classes, so the probes avoid the stdlib beyond Intrinsics, which is allowed below).
dex() {
  local name="$1"
  jar cf "$W/$name.jar" -C "$W/classes" "probe/$name" || die "jar failed"
  java -jar "$DX_JAR" --dex --min-sdk-version=26 --output="$W/$name.dex" "$W/$name.jar" \
    >"$W/dx-$name.log" 2>&1 || { cat "$W/dx-$name.log" >&2; die "dx failed on probe/$name"; }
}
check() { # dex -> findings file; returns the check's exit status
  local name="$1" rc=0
  printf 'Lkotlin/\n' > "$W/allow.txt"
  python3 "$HERE/api_levels.py" "$W/$name.dex" --dts "$DTS" --android-jar "$ANDROID23" --min-sdk 26 \
    --allow "$W/allow.txt" >"$W/$name.findings" 2>"$W/$name.log" || rc=$?
  return $rc
}
for name in cleaner guarded cases; do dex "$name"; done

rc=0; check cleaner || rc=$?
if [ $rc = 1 ] && grep -q 'Ljava/lang/ref/Cleaner;.create:()Ljava/lang/ref/Cleaner; needs API 33, guaranteed here: 26' "$W/cleaner.findings"; then
  ok "the one-line Cleaner.create() probe fails the check: $(head -1 "$W/cleaner.findings")"
else
  bad "the Cleaner.create() probe did not fail the check as expected (exit $rc): $(cat "$W/cleaner.findings" "$W/cleaner.log")"
fi
rc=0; check guarded || rc=$?
if [ $rc = 0 ] && [ ! -s "$W/guarded.findings" ]; then
  ok "the guarded probe (SDK_INT >= 33) passes"
else
  bad "the guarded probe did not pass (exit $rc): $(cat "$W/guarded.findings" "$W/guarded.log")"
fi
rc=0; check cases || rc=$?
[ $rc = 1 ] || bad "the cases probe should have findings (exit $rc)"
fns="$(grep -oE '^fun (ok|bad)[A-Za-z0-9]+' "$P/cases/Cases.kt" | cut -d' ' -f2)"
[ "$(echo "$fns" | wc -l)" -ge 10 ] || die "too few cases found in Cases.kt"
for fn in $fns; do
  if grep -q "^probe/cases/CasesKt\.$fn @" "$W/cases.findings"; then flagged=1; else flagged=0; fi
  case "$fn" in
    ok*) [ $flagged = 0 ] && ok "$fn: no finding" || bad "$fn: unexpected finding: $(grep "CasesKt\.$fn @" "$W/cases.findings")" ;;
    bad*) [ $flagged = 1 ] && ok "$fn: $(grep "CasesKt\.$fn @" "$W/cases.findings" | head -1 | cut -d' ' -f3-)" || bad "$fn: not flagged" ;;
  esac
done
# Api33Impl.make itself is checked at 33: no finding inside it.
if grep -q '^probe/cases/Api33Impl' "$W/cases.findings"; then bad "a finding inside Api33Impl"; else ok "Api33Impl is checked at 33"; fi

echo "api-level check self-tests: $passes passed, $fails failed"
[ $fails = 0 ]
