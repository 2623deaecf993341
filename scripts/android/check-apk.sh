#!/usr/bin/env bash
# Structural checks of an APK (the one build-apk.sh makes, or Gradle's). Each check prints
# "ok: ..." or "FAIL[<check>]: ..."; the exit status is 1 when any check failed.
#   signature   apksigner verify (v2 or v3 scheme verified)
#   badging     aapt dump badging: package io.ecvo.*, sdkVersion = minSdk and targetSdkVersion =
#               targetSdk of gradle/libs.versions.toml, a launchable activity, and every
#               <uses-permission> of the source manifest
#   libs        lib/<abi>/libecvo_jni.so for arm64-v8a, armeabi-v7a and x86_64: stored
#               (uncompressed), data 16 KB aligned, ELF machine of that ABI
#   dex         no invoke-custom and no java.lang.invoke.LambdaMetafactory in any classes*.dex
#               (dexdump -d)
#   manifest    every class the manifest names (application, activity, service, receiver,
#               provider) is defined in a dex
#   assets      the bundled sample stream (assets/camera.json, rgb.txt, depth.txt)
#
# Usage: scripts/android/check-apk.sh [APK]   (default: the app-debug.apk of build-apk.sh)
#        scripts/android/check-apk.sh --selftest [APK]
#   --selftest  makes broken copies of APK (re-signed with a throw-away key) and requires that
#               each is rejected by the check it breaks, and that an intact re-signed copy passes
set -euo pipefail
{
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
REPO="$(cd "$HERE/../.." && pwd)"
ECVO_LOG_TAG=check-apk
# shellcheck source=lib.sh
. "$HERE/lib.sh"

SELFTEST=0
if [ "${1:-}" = "--selftest" ]; then SELFTEST=1; shift; fi
case "${1:-}" in -h|--help) sed -n '2,/^set -euo/p' "$0" | sed '$d' | sed 's/^# \{0,1\}//'; exit 0 ;; esac
APK="${1:-$REPO/android-app/app/build/outputs/apk/debug/app-debug.apk}"
[ -f "$APK" ] || die "no APK at $APK (run scripts/android/build-apk.sh)"
for t in apksigner aapt dexdump readelf unzip python3; do command -v "$t" >/dev/null || die "$t not found"; done
ABIS=(arm64-v8a armeabi-v7a x86_64)
TOML="$REPO/gradle/libs.versions.toml"
ver() { sed -n "s/^$1 *= *\"\(.*\)\".*/\1/p" "$TOML" | head -1; }
MIN_SDK="$(ver minSdk)"; TARGET_SDK="$(ver targetSdk)"
SRC_MANIFEST="$REPO/android-app/app/src/main/AndroidManifest.xml"

# Runs every check on $1; prints the FAIL lines; returns the number of failed checks.
check_apk() {
  local apk="$1" fails=0 tmp out
  tmp="$(mktemp -d)"
  fail() { echo "FAIL[$1]: $2"; fails=$((fails + 1)); }
  ok() { echo "ok: $*"; }

  # signature
  if out="$(apksigner verify --verbose "$apk" 2>&1)"; then
    if grep -qE 'Verified using v(2|3) scheme.*: true' <<<"$out"; then ok "signature ($(grep -E 'v[23] scheme.*true' <<<"$out" | sed 's/Verified using //;s/ (APK Signature Scheme v[23])//' | tr '\n' ' '))"
    else fail signature "no v2/v3 signature"; fi
  else
    fail signature "apksigner verify: $(head -3 <<<"$out" | tr '\n' ' ')"
  fi

  # badging
  if out="$(aapt dump badging "$apk" 2>&1)"; then
    local pkg sdk tsdk act p
    pkg="$(sed -n "s/^package: name='\([^']*\)'.*/\1/p" <<<"$out")"
    sdk="$(sed -n "s/^sdkVersion:'\([^']*\)'/\1/p" <<<"$out")"
    tsdk="$(sed -n "s/^targetSdkVersion:'\([^']*\)'/\1/p" <<<"$out")"
    act="$(sed -n "s/^launchable-activity: name='\([^']*\)'.*/\1/p" <<<"$out")"
    case "$pkg" in io.ecvo.*) ;; *) fail badging "package '$pkg' is not io.ecvo.*" ;; esac
    [ "$sdk" = "$MIN_SDK" ] || fail badging "sdkVersion '$sdk', expected minSdk $MIN_SDK"
    [ "$tsdk" = "$TARGET_SDK" ] || fail badging "targetSdkVersion '$tsdk', expected $TARGET_SDK"
    [ -n "$act" ] || fail badging "no launchable activity"
    for p in $(grep -o '<uses-permission[^>]*android:name="[^"]*"' "$SRC_MANIFEST" | sed 's/.*android:name="//;s/"$//'); do
      grep -qx "uses-permission: name='$p'" <<<"$out" || fail badging "permission $p missing"
    done
    ok "badging: package $pkg, minSdk $sdk, targetSdk $tsdk, launchable $act, permissions: $(sed -n "s/^uses-permission: name='\(.*\)'/\1/p" <<<"$out" | tr '\n' ' ')"
  else
    fail badging "aapt dump badging failed: $(head -2 <<<"$out")"
  fi

  # libs
  if out="$(python3 - "$apk" "${ABIS[@]}" <<'EOF'
import struct, sys, zipfile
apk, abis = sys.argv[1], sys.argv[2:]
bad = 0
with zipfile.ZipFile(apk) as z, open(apk, "rb") as f:
    names = {i.filename: i for i in z.infolist()}
    for abi in abis:
        n = f"lib/{abi}/libecvo_jni.so"
        i = names.get(n)
        if i is None:
            print(f"missing {n}"); bad += 1; continue
        if i.compress_type != zipfile.ZIP_STORED:
            print(f"{n} is compressed (must be stored)"); bad += 1; continue
        f.seek(i.header_offset); h = f.read(30)
        off = i.header_offset + 30 + struct.unpack("<H", h[26:28])[0] + struct.unpack("<H", h[28:30])[0]
        if off % 16384:
            print(f"{n}: data at offset {off}, not 16 KB aligned"); bad += 1
sys.exit(1 if bad else 0)
EOF
)"; then
    local abi m
    for abi in "${ABIS[@]}"; do
      unzip -p "$apk" "lib/$abi/libecvo_jni.so" > "$tmp/lib.so"
      m="$(readelf -h "$tmp/lib.so" 2>/dev/null | sed -n 's/^ *Machine: *//p')"
      [ "$m" = "$(abi_elf_machine "$abi")" ] || fail libs "lib/$abi/libecvo_jni.so: ELF machine '$m', expected $(abi_elf_machine "$abi")"
    done
    ok "libs: lib/{${ABIS[*]}}/libecvo_jni.so stored, 16 KB aligned, ELF machines match"
  else
    while IFS= read -r l; do fail libs "$l"; done <<<"$out"
  fi

  # dex
  local dexes=() d
  mapfile -t dexes < <(unzip -Z1 "$apk" | grep -E '^classes[0-9]*\.dex$')
  : > "$tmp/dexdump.txt"
  if [ ${#dexes[@]} = 0 ]; then fail dex "no classes.dex"; fi
  for d in "${dexes[@]}"; do
    unzip -p "$apk" "$d" > "$tmp/$d"
    dexdump -d "$tmp/$d" >> "$tmp/dexdump.txt" 2>/dev/null || fail dex "dexdump cannot read $d"
  done
  local ic lmf
  ic="$(grep -c 'invoke-custom' "$tmp/dexdump.txt" || true)"
  lmf="$(grep -c 'LambdaMetafactory' "$tmp/dexdump.txt" || true)"
  [ "$ic" = 0 ] || fail dex "$ic invoke-custom instructions ($(grep -B40 invoke-custom "$tmp/dexdump.txt" | sed -n "s/.*(in L\(.*\);)/\1/p" | sort -u | head -3 | tr '\n' ' '))"
  [ "$lmf" = 0 ] || fail dex "$lmf references to LambdaMetafactory"
  [ "$ic$lmf" = 00 ] && ok "dex: ${dexes[*]}, $(grep -c 'Class descriptor' "$tmp/dexdump.txt") classes, no invoke-custom, no LambdaMetafactory"

  # manifest
  local pkg2 names=() n cls missing=0
  pkg2="$(aapt dump xmltree "$apk" AndroidManifest.xml 2>/dev/null | sed -n 's/^ *A: package="\([^"]*\)".*/\1/p' | head -1)"
  mapfile -t names < <(aapt dump xmltree "$apk" AndroidManifest.xml 2>/dev/null | awk '
    /^ *E: / { el = $2 }
    /^ *A: android:name\(/ && (el == "application" || el == "activity" || el == "activity-alias" || el == "service" || el == "receiver" || el == "provider") {
      s = $0; sub(/.*=\"/, "", s); sub(/\".*/, "", s); print s }')
  [ ${#names[@]} -gt 0 ] || fail manifest "the manifest names no component"
  for n in "${names[@]}"; do
    case "$n" in .*) cls="$pkg2$n" ;; *.*) cls="$n" ;; *) cls="$pkg2.$n" ;; esac
    if ! grep -qF "Class descriptor  : 'L${cls//.//};'" "$tmp/dexdump.txt"; then
      fail manifest "$cls (manifest) is not in the dex"; missing=1
    fi
  done
  [ $missing = 0 ] && [ ${#names[@]} -gt 0 ] && ok "manifest: ${names[*]} all in the dex"

  # assets
  local a amiss=0 list
  list="$(unzip -Z1 "$apk")"
  for a in assets/camera.json assets/rgb.txt assets/depth.txt; do
    grep -qx "$a" <<<"$list" || { fail assets "$a missing"; amiss=1; }
  done
  [ $amiss = 0 ] && ok "assets: sample stream ($(grep -c '^assets/' <<<"$list") files)"

  rm -rf "$tmp"
  return $fails
}

if [ $SELFTEST = 0 ]; then
  log "checking $APK ($(stat -c %s "$APK") bytes)"
  rc=0; check_apk "$APK" || rc=$?
  [ $rc = 0 ] || die "$rc check(s) failed on $APK"
  log "OK: every structural check passed"
  exit 0
fi

# --- self-test ------------------------------------------------------------------------------
. "$HERE/selftest-apk.sh"
exit 0
}
