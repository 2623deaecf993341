#!/usr/bin/env bash
# Builds android-app/app/build/outputs/apk/debug/app-debug.apk without the Android SDK or Gradle
# (see docs/android-apk.md). Steps, each timed, any failure fatal:
#   1. tools: aapt, zipalign, apksigner, dexdump, android-framework-res, proguard-cli, libasm-java
#      from the machine's Debian release (apt-get install); dalvik-exchange (dx 10.0.0) and
#      libandroid-23-java from Debian bullseye, through a private apt source (apt-get download +
#      dpkg-deb -x into the cache; the system's apt sources and dpkg are not touched)
#   2. the three ABIs' libecvo_jni.so, stripped (--jni-libs DIR, else target/android/jniLibs as
#      left by ci-cross-check.sh, else built with the stand-in NDK)
#   3. aapt: R.java from the manifest and res/ (against Android 10's framework-res)
#   4. kotlinc: :tracker + :shared + :app (+ R.java) against the API stubs of
#      scripts/android-stubs, with -Xlambdas=class -Xsam-conversions=class
#   5. proguard-cli: the app + kotlin-stdlib shrunk (no obfuscation, no optimisation), then
#      desugar/LambdaDesugar.java rewrites the stdlib's remaining LambdaMetafactory call sites
#   6. dx --min-sdk-version=26 -> classes.dex; fails on any invoke-custom or LambdaMetafactory
#   7. aapt package: manifest (+ uses-sdk, version, debuggable, extractNativeLibs=false), res/,
#      assets = testdata/synth_phone_320x180 (as app/build.gradle.kts does), png stored
#   8. classes.dex + lib/<abi>/libecvo_jni.so (stored), aligned by apkzip.py (.so at 16 KB)
#   9. apksigner with a debug key made by keytool (cached, made once)
#
# Usage: scripts/android/build-apk.sh [--jni-libs DIR] [--out APK]
# Environment: ECVO_APK_CACHE (default ~/.cache/ecvo/apk-tools), KOTLINC, ANDROID_TYPES_CACHE.
set -euo pipefail
# The whole script is one compound command, parsed before it runs.
{
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
REPO="$(cd "$HERE/../.." && pwd)"
ECVO_LOG_TAG=build-apk
# shellcheck source=lib.sh
. "$HERE/lib.sh"

ABIS=(arm64-v8a armeabi-v7a x86_64)
APP_DIR="$REPO/android-app/app"
APK="$APP_DIR/build/outputs/apk/debug/app-debug.apk"
JNI=""
while [ $# -gt 0 ]; do
  case "$1" in
    --jni-libs) JNI="${2:?--jni-libs needs a folder}"; shift 2 ;;
    --out) APK="${2:?--out needs a file}"; shift 2 ;;
    -h|--help) sed -n '2,/^set -euo/p' "$0" | sed '$d' | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) die "unknown argument '$1' (see --help)" ;;
  esac
done
case "$APK" in /*) ;; *) APK="$PWD/$APK" ;; esac
CACHE="${ECVO_APK_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/ecvo/apk-tools}"
W="$APP_DIR/build/apk-work"
TOML="$REPO/gradle/libs.versions.toml"
ver() { sed -n "s/^$1 *= *\"\(.*\)\".*/\1/p" "$TOML" | head -1; }
MIN_SDK="$(ver minSdk)"; TARGET_SDK="$(ver targetSdk)"
NS="$(sed -n 's/^ *applicationId *= *"\(.*\)".*/\1/p' "$APP_DIR/build.gradle.kts" | head -1)"
VCODE="$(sed -n 's/^ *versionCode *= *\([0-9]*\).*/\1/p' "$APP_DIR/build.gradle.kts" | head -1)"
VNAME="$(sed -n 's/^ *versionName *= *"\(.*\)".*/\1/p' "$APP_DIR/build.gradle.kts" | head -1)"
[ -n "$MIN_SDK" ] && [ -n "$TARGET_SDK" ] && [ -n "$NS" ] && [ -n "$VCODE" ] && [ -n "$VNAME" ] \
  || die "could not read minSdk/targetSdk/applicationId/versionCode/versionName from the Gradle files"

trap 'rc=$?; print_times >&2; [ $rc -eq 0 ] || echo "build-apk: FAILED (exit $rc)" >&2' EXIT
T_ALL=$EPOCHREALTIME

# --- 1. tools -------------------------------------------------------------------------------
BULLSEYE="$CACHE/bullseye"
DX_JAR="$BULLSEYE/root/usr/share/java/com.android.dx.jar"
ANDROID23="$BULLSEYE/root/usr/share/java/com.android.android-23.jar"
FRAMEWORK=/usr/share/android-framework-res/framework-res.apk
BULLSEYE_DEBS=(dalvik-exchange=10.0.0+r36-1 libandroid-23-java=6.0.1+r72-6)
tools() {
  ensure_debs aapt zipalign apksigner dexdump android-framework-res proguard-cli libasm-java
  if [ -f "$DX_JAR" ] && [ -f "$ANDROID23" ]; then log "bullseye tools cached in $BULLSEYE"; return 0; fi
  mkdir -p "$BULLSEYE/lists/partial" "$BULLSEYE/archives/partial" "$BULLSEYE/debs" "$BULLSEYE/root"
  echo "deb [signed-by=/usr/share/keyrings/debian-archive-keyring.gpg] http://deb.debian.org/debian bullseye main" \
    > "$BULLSEYE/sources.list"
  local o=(-o "Dir::Etc::sourcelist=$BULLSEYE/sources.list" -o Dir::Etc::sourceparts=- \
    -o "Dir::State::Lists=$BULLSEYE/lists" -o "Dir::Cache::archives=$BULLSEYE/archives" \
    -o "Dir::Cache::pkgcache=" -o "Dir::Cache::srcpkgcache=")
  log "apt-get update (bullseye only, lists in $BULLSEYE/lists)"
  apt-get "${o[@]}" update -qq || die "apt-get update of the bullseye source failed"
  (cd "$BULLSEYE/debs" && apt-get "${o[@]}" download "${BULLSEYE_DEBS[@]}") || die "apt-get download ${BULLSEYE_DEBS[*]} failed"
  local d
  for d in "$BULLSEYE"/debs/*.deb; do dpkg-deb -x "$d" "$BULLSEYE/root"; done
  [ -f "$DX_JAR" ] && [ -f "$ANDROID23" ] || die "the bullseye packages hold no $DX_JAR / $ANDROID23"
}
timed "tools (apt)" tools
for t in aapt zipalign apksigner dexdump proguard keytool javac jar java python3; do
  command -v "$t" >/dev/null || die "$t not found"
done
ASM_CP=/usr/share/java/asm.jar:/usr/share/java/asm-tree.jar
[ -f /usr/share/java/asm-tree.jar ] || die "no /usr/share/java/asm-tree.jar (libasm-java)"

rm -rf "$W"; mkdir -p "$W"

# --- 2. native libraries --------------------------------------------------------------------
jni() {
  local src="$JNI"
  if [ -z "$src" ]; then
    src="${ECVO_ANDROID_TARGET_DIR:-$REPO/target/android}/jniLibs"
    local abi missing=0
    for abi in "${ABIS[@]}"; do [ -f "$src/$abi/libecvo_jni.so" ] || missing=1; done
    if [ $missing = 1 ]; then
      log "no libecvo_jni.so for every ABI in $src: building them with the stand-in NDK"
      local env_file; env_file="$(mktemp)"
      "$HERE/install-standin-ndk.sh" >"$env_file"
      eval "$(cat "$env_file")"; rm -f "$env_file"
      use_rustup_toolchain
      CARGO_TARGET_DIR="${ECVO_ANDROID_TARGET_DIR:-$REPO/target/android}" \
        "$HERE/../build-android.sh" -t "${ABIS[*]}" -o "$src"
    fi
  fi
  local abi strip
  strip="$(command -v llvm-strip-22 || command -v llvm-strip || true)"
  [ -n "$strip" ] || die "llvm-strip not found (apt-get install llvm-22)"
  for abi in "${ABIS[@]}"; do
    [ -f "$src/$abi/libecvo_jni.so" ] || die "no $src/$abi/libecvo_jni.so"
    mkdir -p "$W/apk/lib/$abi"
    "$strip" --strip-unneeded -o "$W/apk/lib/$abi/libecvo_jni.so" "$src/$abi/libecvo_jni.so"
    log "lib/$abi/libecvo_jni.so: $(stat -c %s "$W/apk/lib/$abi/libecvo_jni.so") bytes stripped (from $(stat -c %s "$src/$abi/libecvo_jni.so"))"
  done
}
timed "native libraries (strip ${#ABIS[@]} ABIs)" jni

# --- 3. manifest and R.java -----------------------------------------------------------------
# AGP merges uses-sdk, the version, debuggable (debug build) and extractNativeLibs=false
# (useLegacyPackaging = false) into the manifest; aapt needs the package attribute.
resources() {
  local attrs="package=\"$NS\" android:versionCode=\"$VCODE\" android:versionName=\"$VNAME\" "
  sed -e "0,/<manifest /s|<manifest |<manifest $attrs|" \
      -e "0,/<application/s|<application|<uses-sdk android:minSdkVersion=\"$MIN_SDK\" android:targetSdkVersion=\"$TARGET_SDK\" />\n    <application android:debuggable=\"true\" android:extractNativeLibs=\"false\"|" \
      "$APP_DIR/src/main/AndroidManifest.xml" > "$W/AndroidManifest.xml"
  mkdir -p "$W/gen"
  aapt package -f -m -J "$W/gen" -M "$W/AndroidManifest.xml" -S "$APP_DIR/src/main/res" -I "$FRAMEWORK" \
    >"$W/aapt-r.log" 2>&1 || { cat "$W/aapt-r.log" >&2; die "aapt (R.java) failed"; }
  [ -f "$W/gen/${NS//.//}/R.java" ] || die "aapt wrote no R.java"
}
timed "aapt: R.java" resources

# --- 4. Kotlin ------------------------------------------------------------------------------
TYPES_VERSION=9.1.1
kotlin() {
  local tcache="${ANDROID_TYPES_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/ecvo/android-types}"
  local pkg="$tcache/node_modules/@nativescript/types-android"
  if ! grep -q "\"version\": *\"$TYPES_VERSION\"" "$pkg/package.json" 2>/dev/null; then
    log "downloading @nativescript/types-android@$TYPES_VERSION from npm: 4.3 MB, once, into $tcache"
    mkdir -p "$tcache"
    npm install --prefix "$tcache" --no-audit --no-fund --loglevel=error "@nativescript/types-android@$TYPES_VERSION" >&2
  fi
  local main="$APP_DIR/src/main/kotlin"
  grep -rhoE '^import android\.[A-Za-z0-9_.]+' "$main" | sed 's/^import //' | sort -u > "$W/imports.txt"
  mkdir -p "$W/stubs-src" "$W/stubs-classes" "$W/classes"
  python3 "$REPO/scripts/android-stubs/gen_stubs.py" "$pkg/lib/android/android-platform-37.d.ts" "$W/stubs-src" \
    --overrides "$REPO/scripts/android-stubs/overrides.txt" --classes "$W/imports.txt" \
    --classes "$REPO/scripts/android-stubs/classes.txt" >"$W/gen_stubs.log" 2>&1 \
    || { cat "$W/gen_stubs.log" >&2; die "gen_stubs.py failed"; }
  find "$W/stubs-src" -name '*.java' > "$W/stubs.list"
  javac -nowarn -encoding UTF-8 --release 8 -d "$W/stubs-classes" @"$W/stubs.list" 2>"$W/javac-stubs.log" \
    || { head -40 "$W/javac-stubs.log" >&2; die "the API stubs do not compile"; }
  (cd "$W/stubs-classes" && jar cf "$W/android-stubs.jar" .)
  # --release 8: ProGuard 6.2 reads class files up to Java 13 only.
  # R.java is part of the app (dexed); compiled for Java 8 like the Kotlin.
  javac -nowarn --release 8 -d "$W/classes" "$W/gen/${NS//.//}/R.java" || die "javac R.java failed"
  KOTLINC="${KOTLINC:-}"
  if [ -z "$KOTLINC" ]; then
    local kc="${KOTLINC_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/ecvo/kotlinc}"
    if [ ! -x "$kc/node_modules/kotlin-compiler/bin/kotlinc" ]; then
      log "downloading kotlin-compiler@2.4.20 from npm: 90 MB (94 MB installed), once, into $kc"
      mkdir -p "$kc"
      npm install --prefix "$kc" --no-audit --no-fund --loglevel=error kotlin-compiler@2.4.20 >&2
      chmod +x "$kc"/node_modules/kotlin-compiler/bin/* 2>/dev/null || true
    fi
    KOTLINC="$kc/node_modules/kotlin-compiler/bin/kotlinc"
  fi
  STDLIB="$(cd "$(dirname "$KOTLINC")/.." && pwd)/lib/kotlin-stdlib.jar"
  [ -f "$STDLIB" ] || die "no kotlin-stdlib.jar beside $KOTLINC"
  # One compilation of the three modules; :tracker's and :shared's `internal` stay internal to
  # the app (they are not visible across Gradle modules either, and nothing in :app uses them).
  "$KOTLINC" -jvm-target 1.8 -no-reflect -Xlambdas=class -Xsam-conversions=class -nowarn \
    -cp "$W/android-stubs.jar:$W/classes" -d "$W/classes" \
    "$REPO/android-app/tracker/src/main/kotlin" "$REPO/android-app/shared/src/main/kotlin" "$main" \
    >"$W/kotlinc.log" 2>&1 || { cat "$W/kotlinc.log" >&2; die "kotlinc failed"; }
  log "compiled $(find "$W/classes" -name '*.class' | wc -l) classes"
}
timed "kotlinc :tracker :shared :app" kotlin

# --- 5. shrink + desugar --------------------------------------------------------------------
shrink() {
  # ProGuard needs the Java library the stdlib builds on, as class files it can read: the JDK's
  # Java 8 signatures from lib/ct.sym (javac --release 8).
  python3 "$HERE/ctsym-jar.py" 8 "$W/java8.jar" >&2
  cat > "$W/proguard.pro" <<EOF
-injars $W/classes
-injars $STDLIB(!META-INF/versions/**,!module-info.class,!META-INF/**.kotlin_module)
-outjars $W/shrunk.jar
-libraryjars $W/android-stubs.jar
-libraryjars $W/java8.jar
-libraryjars $ANDROID23
-dontobfuscate
-dontoptimize
-dontpreverify
-keepattributes *
-keep class $NS.** { *; }
-keep class io.ecvo.** { *; }
-dontwarn android.**,java.**,javax.**,org.jetbrains.annotations.**
-dontnote **
EOF
  proguard @"$W/proguard.pro" >"$W/proguard.log" 2>&1 || { tail -40 "$W/proguard.log" >&2; die "proguard failed"; }
  mkdir -p "$W/desugar-classes"
  javac -nowarn -cp "$ASM_CP" -d "$W/desugar-classes" "$HERE/desugar/LambdaDesugar.java" || die "javac LambdaDesugar failed"
  java -cp "$ASM_CP:$W/desugar-classes" LambdaDesugar "$W/shrunk.jar" "$W/desugared.jar" 2>"$W/desugar.log" \
    || { cat "$W/desugar.log" >&2; die "LambdaDesugar failed"; }
  tail -1 "$W/desugar.log" >&2
}
timed "proguard shrink + lambda desugar" shrink

# --- 6. dex ---------------------------------------------------------------------------------
dex() {
  java -jar "$DX_JAR" --dex --min-sdk-version="$MIN_SDK" --output="$W/apk/classes.dex" "$W/desugared.jar" \
    >"$W/dx.log" 2>&1 || { head -40 "$W/dx.log" >&2; die "dx failed"; }
  dexdump -d "$W/apk/classes.dex" > "$W/dexdump.txt" 2>/dev/null || die "dexdump failed"
  if grep -q 'invoke-custom' "$W/dexdump.txt"; then die "classes.dex holds invoke-custom (see $W/dexdump.txt)"; fi
  if grep -q 'LambdaMetafactory' "$W/dexdump.txt"; then die "classes.dex refers to LambdaMetafactory"; fi
  log "classes.dex: $(stat -c %s "$W/apk/classes.dex") bytes, $(grep -c 'Class descriptor' "$W/dexdump.txt") classes"
}
timed "dx classes.dex" dex

# --- 7-9. package, align, sign --------------------------------------------------------------
package() {
  local assets="$REPO/testdata/synth_phone_320x180"
  [ -f "$assets/camera.json" ] || die "no sample stream at $assets"
  aapt package -f -M "$W/AndroidManifest.xml" -S "$APP_DIR/src/main/res" -A "$assets" -I "$FRAMEWORK" \
    -0 png -F "$W/base.apk" >"$W/aapt.log" 2>&1 || { cat "$W/aapt.log" >&2; die "aapt package failed"; }
  python3 "$HERE/apkzip.py" "$W/aligned.apk" "$W/base.apk" --dex "$W/apk/classes.dex" --libs "$W/apk/lib" \
    || die "apkzip.py failed"
  zipalign -c -p 4 "$W/aligned.apk" || die "zipalign -c 4 rejects the package"
  local ks="$CACHE/debug.keystore"
  if [ ! -f "$ks" ]; then
    mkdir -p "$CACHE"
    keytool -genkeypair -keystore "$ks" -storepass android -keypass android -alias androiddebugkey \
      -keyalg RSA -keysize 2048 -validity 10000 -dname "CN=Android Debug,O=Android,C=US" >/dev/null 2>&1 \
      || die "keytool failed"
    log "made a debug key in $ks"
  fi
  mkdir -p "$(dirname "$APK")"
  apksigner sign --ks "$ks" --ks-pass pass:android --key-pass pass:android --ks-key-alias androiddebugkey \
    --min-sdk-version "$MIN_SDK" --out "$APK" "$W/aligned.apk" || die "apksigner sign failed"
  rm -f "$APK.idsig"
  apksigner verify "$APK" || die "apksigner verify failed"
}
timed "aapt package + align + sign" package

STEP_TIMES+=("$(printf '%-44s %7.1f s' "TOTAL" "$(awk -v a="$T_ALL" -v b="$EPOCHREALTIME" 'BEGIN{print b-a}')")")
log "OK: $APK ($(stat -c %s "$APK") bytes)"
exit 0
}
