#!/usr/bin/env bash
# The API-level check (api_levels.py; see docs/android-apk.md) on an APK or dex, with the
# data build-apk.sh installs: the API 23 android.jar (Debian bullseye's libandroid-23-java)
# and @nativescript/types-android's merged 21..37 declarations; minSdk from
# gradle/libs.versions.toml; accepted findings from api-allow.txt. Exit 1 on any finding, or
# when the sources test SDK_INT and the dex never reads it.
#
# Usage: scripts/android/check-api-levels.sh [APK_OR_DEX]
#   (default android-app/app/build/outputs/apk/debug/app-debug.apk)
set -euo pipefail
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
REPO="$(cd "$HERE/../.." && pwd)"
APK="${1:-$REPO/android-app/app/build/outputs/apk/debug/app-debug.apk}"
CACHE="${ECVO_APK_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/ecvo/apk-tools}"
TYPES="${ANDROID_TYPES_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/ecvo/android-types}"
MIN_SDK="$(sed -n 's/^minSdk *= *"\(.*\)".*/\1/p' "$REPO/gradle/libs.versions.toml" | head -1)"
[ -f "$APK" ] || { echo "[check-api-levels] no $APK (run scripts/android/build-apk.sh)" >&2; exit 2; }
# Guards folded away at compile time (a stub SDK_INT that is a constant) leave nothing to check:
# when the sources test SDK_INT, the dex must read it.
if grep -rqs 'SDK_INT' "$REPO"/android-app/*/src/main/kotlin; then
  n="$(dexdump -d "$APK" 2>/dev/null | grep -c 'sget v[0-9]*, Landroid/os/Build\$VERSION;\.SDK_INT:I' || true)"
  if [ "${n:-0}" = 0 ]; then
    echo "the sources test Build.VERSION.SDK_INT but $APK never reads it: the guards were folded at compile time (is the stub's SDK_INT a constant?)"
    exit 1
  fi
fi
exec python3 "$HERE/api_levels.py" "$APK" --min-sdk "${MIN_SDK:?no minSdk in gradle/libs.versions.toml}" \
  --dts "$TYPES/node_modules/@nativescript/types-android/lib/android/android-platform-21-37-merged.d.ts" \
  --android-jar "$CACHE/bullseye/root/usr/share/java/com.android.android-23.jar" \
  --allow "$HERE/api-allow.txt"
