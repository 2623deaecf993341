#!/usr/bin/env bash
# Checks :app without the Android SDK, in steps that fail on any error:
#   0. the stub generator's unit tests (test_gen_stubs.py);
#   1. resources: aapt (Debian's, Android 10) compiles the manifest and res/ against
#      Debian's android-framework-res and writes R.java;
#   2. Kotlin: Java stubs of the Android classes :app uses are generated from the npm
#      package @nativescript/types-android (gen_stubs.py), compiled with R.java into a
#      stub jar, and :app's Kotlin is compiled against it plus :tracker and :shared.
#
# Usage: scripts/android-stubs/check-app.sh [--out DIR]
# Environment: ANDROID_TYPES_CACHE (npm cache folder, default ~/.cache/ecvo/android-types),
#   KOTLINC (else the one scripts/kotlin/test-kotlin.sh installs).
# Installs aapt and android-framework-res with apt-get when missing (as root).
set -euo pipefail
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
REPO="$(cd "$HERE/../.." && pwd)"
OUT="$REPO/target/android-check"
TYPES_VERSION=9.1.1
while [ $# -gt 0 ]; do
  case "$1" in
    --out) OUT="${2:?}"; shift 2 ;;
    -h|--help) sed -n '2,13p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "unknown argument $1" >&2; exit 2 ;;
  esac
done
log() { echo "[check-app] $*" >&2; }
die() { echo "[check-app] error: $*" >&2; exit 1; }
APP="$REPO/android-app/app/src/main"
FRAMEWORK=/usr/share/android-framework-res/framework-res.apk

if ! command -v aapt >/dev/null || [ ! -f "$FRAMEWORK" ]; then
  [ "$(id -u)" = 0 ] || die "install aapt and android-framework-res (apt-get)"
  log "installing aapt and android-framework-res"
  apt-get install -y --no-install-recommends aapt android-framework-res >&2 \
    || { apt-get update >&2 && apt-get install -y --no-install-recommends aapt android-framework-res >&2; }
fi
command -v javac >/dev/null || die "javac (JDK 17) is needed"

# --- 0. the generator's own tests ---------------------------------------------------------
log "gen_stubs.py unit tests"
(cd "$HERE" && python3 -m unittest -q test_gen_stubs) >&2 || die "gen_stubs.py tests failed"

rm -rf "$OUT"; mkdir -p "$OUT/res-check" "$OUT/gen" "$OUT/stubs-src" "$OUT/stubs-classes"

# --- 1. resources -------------------------------------------------------------------------
# aapt needs the package attribute, which AGP takes from `namespace`: give a copy of the
# manifest the namespace of app/build.gradle.kts.
NS="$(sed -n 's/^ *namespace *= *"\(.*\)".*/\1/p' "$REPO/android-app/app/build.gradle.kts" | head -1)"
[ -n "$NS" ] || die "no namespace in android-app/app/build.gradle.kts"
sed "0,/<manifest /s|<manifest |<manifest package=\"$NS\" |" "$APP/AndroidManifest.xml" > "$OUT/res-check/AndroidManifest.xml"
# Attributes newer than API 29 (which aapt's framework-res does not know) would be removed
# here by name; the app uses none today.
log "aapt: manifest and resources against $(basename "$FRAMEWORK") (Android 10)"
aapt package -f -m -J "$OUT/gen" -M "$OUT/res-check/AndroidManifest.xml" -S "$APP/res" -I "$FRAMEWORK" \
  -F "$OUT/res-check/resources.ap_" 2>&1 | tee "$OUT/aapt.log" >&2
[ "${PIPESTATUS[0]}" = 0 ] || die "aapt failed (see above)"
grep -qi "error" "$OUT/aapt.log" && die "aapt reported an error"
R_JAVA="$OUT/gen/${NS//.//}/R.java"
[ -f "$R_JAVA" ] || die "aapt wrote no $R_JAVA"
log "resources OK: $(grep -c 'public static final int' "$R_JAVA") resource ids"

# --- 2. Kotlin against generated stubs ----------------------------------------------------
CACHE="${ANDROID_TYPES_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/ecvo/android-types}"
PKG="$CACHE/node_modules/@nativescript/types-android"
if ! grep -q "\"version\": *\"$TYPES_VERSION\"" "$PKG/package.json" 2>/dev/null; then
  command -v npm >/dev/null || die "npm is needed"
  log "downloading @nativescript/types-android@$TYPES_VERSION from npm: 4.3 MB, once, into $CACHE"
  mkdir -p "$CACHE"
  npm install --prefix "$CACHE" --no-audit --no-fund --loglevel=error "@nativescript/types-android@$TYPES_VERSION" >&2
fi
DTS="$PKG/lib/android/android-platform-37.d.ts"
[ -f "$DTS" ] || die "no $DTS"

# Every android.* class :app imports, plus the ones it reaches without an import.
grep -rhoE '^import android\.[A-Za-z0-9_.]+' "$APP/kotlin" | sed 's/^import //' | sort -u > "$OUT/imports.txt"
log "generating stubs for $(wc -l < "$OUT/imports.txt") imported classes + $(grep -vc '^#' "$HERE/classes.txt") listed"
python3 "$HERE/gen_stubs.py" "$DTS" "$OUT/stubs-src" --overrides "$HERE/overrides.txt" \
  --classes "$OUT/imports.txt" --classes "$HERE/classes.txt" >&2
find "$OUT/stubs-src" -name '*.java' > "$OUT/stubs.list"
log "javac: $(wc -l < "$OUT/stubs.list") stub files + R.java"
javac -nowarn -encoding UTF-8 -source 17 -target 17 -d "$OUT/stubs-classes" @"$OUT/stubs.list" "$R_JAVA" 2>"$OUT/javac.log" \
  || { head -60 "$OUT/javac.log" >&2; die "the generated stubs do not compile (a generator bug; see $OUT/javac.log)"; }
(cd "$OUT/stubs-classes" && jar cf "$OUT/android-stubs.jar" .)

# :tracker and :shared, compiled by the JVM test script (no tests run).
KOUT="$REPO/target/kotlin" # the JVM test step's build: up to date when it ran first
bash "$REPO/scripts/kotlin/test-kotlin.sh" --compile-only --out "$KOUT" >&2
KOTLINC="${KOTLINC:-${KOTLINC_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/ecvo/kotlinc}/node_modules/kotlin-compiler/bin/kotlinc}"
[ -x "$KOTLINC" ] || die "no kotlinc at $KOTLINC"
log "kotlinc: :app against the stubs"
set +e
"$KOTLINC" -jvm-target 17 -no-reflect -Werror -cp "$OUT/android-stubs.jar:$KOUT/tracker.jar:$KOUT/shared.jar" \
  -d "$OUT/app-classes" "$APP/kotlin" >"$OUT/kotlinc.log" 2>&1
rc=$?
set -e
cat "$OUT/kotlinc.log" >&2
[ "$rc" = 0 ] || die ":app's Kotlin does not compile against the Android API stubs"
log "OK: resources and :app's Kotlin compile ($(find "$OUT/app-classes" -name '*.class' | wc -l) classes)"
echo "android app check: 3 passed, 0 failed"
