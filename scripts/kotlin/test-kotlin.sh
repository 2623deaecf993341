#!/usr/bin/env bash
# Compiles the plain-Kotlin modules of the Android app (:tracker, :shared) on the JVM and runs
# their tests; the Android-only :app module cannot be compiled on a machine without the SDK.
#
# Usage: scripts/kotlin/test-kotlin.sh [options]
#   --native-lib DIR   folder holding a host build of libecvo_jni (e.g. target/debug); the tests
#                      then run with -Xcheck:jni -Djava.library.path=DIR and any JNI warning
#                      fails the run (default: $ECVO_NATIVE_LIB_DIR)
#   --extra-tests P    extra test sources, a .kt file or a folder (repeatable; default: the
#                      colon-separated $ECVO_EXTRA_KOTLIN_TESTS), e.g. the JNI boundary tests
#   --filter TEXT      run only tests whose name contains TEXT
#   --out DIR          build folder (default: target/kotlin in the repo)
#   --compile-only     compile main and test sources, run nothing
#   -h, --help
# Environment:
#   KOTLINC_CACHE      where kotlin-compiler@2.4.20 is installed with npm
#                      (default: ${XDG_CACHE_HOME:-~/.cache}/ecvo/kotlinc); KOTLINC overrides the binary
#   JUNIT_JAR, HAMCREST_JAR  JUnit 4 and Hamcrest jars (default: Debian's junit4 package,
#                      installed with apt-get when missing and running as root)
#
# The last line of a test run is `N passed, N failed`; the exit status is non-zero when a test
# failed, none ran, or something did not compile.
set -euo pipefail
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
REPO="$(cd "$HERE/../.." && pwd)"
KOTLIN_VERSION=2.4.20

log() { echo "[test-kotlin] $*" >&2; }
die() { echo "[test-kotlin] error: $*" >&2; exit 2; }
usage() { sed -n '2,/^set -euo/p' "$0" | sed '$d' | sed 's/^# \{0,1\}//'; }

NATIVE="${ECVO_NATIVE_LIB_DIR:-}"
EXTRA=()
if [ -n "${ECVO_EXTRA_KOTLIN_TESTS:-}" ]; then IFS=: read -r -a EXTRA <<<"$ECVO_EXTRA_KOTLIN_TESTS"; fi
FILTER=""
OUT="$REPO/target/kotlin"
COMPILE_ONLY=0
while [ $# -gt 0 ]; do
  case "$1" in
    --native-lib) NATIVE="${2:?--native-lib needs a folder}"; shift 2 ;;
    --extra-tests) EXTRA+=("${2:?--extra-tests needs a path}"); shift 2 ;;
    --filter) FILTER="${2:?--filter needs a value}"; shift 2 ;;
    --out) OUT="${2:?--out needs a folder}"; shift 2 ;;
    --compile-only) COMPILE_ONLY=1; shift ;;
    -h|--help) usage; exit 0 ;;
    *) die "unknown argument '$1' (see --help)" ;;
  esac
done
case "$OUT" in /*) ;; *) OUT="$PWD/$OUT" ;; esac
if [ -n "$NATIVE" ]; then
  case "$NATIVE" in /*) ;; *) NATIVE="$PWD/$NATIVE" ;; esac
  [ -d "$NATIVE" ] || die "--native-lib $NATIVE is not a folder"
  ls "$NATIVE"/libecvo_jni.* >/dev/null 2>&1 || die "no libecvo_jni.so (or .dylib) in $NATIVE"
fi
for p in ${EXTRA[@]+"${EXTRA[@]}"}; do [ -e "$p" ] || die "extra test source $p does not exist"; done

command -v java >/dev/null || die "java is not installed (JDK 17 expected)"

# --- kotlinc (npm package kotlin-compiler, the full compiler) ---
if [ -n "${KOTLINC:-}" ]; then
  [ -x "$KOTLINC" ] || die "KOTLINC=$KOTLINC is not executable"
else
  CACHE="${KOTLINC_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/ecvo/kotlinc}"
  PKG="$CACHE/node_modules/kotlin-compiler"
  if ! grep -q "\"version\": *\"$KOTLIN_VERSION\"" "$PKG/package.json" 2>/dev/null || [ ! -x "$PKG/bin/kotlinc" ]; then
    command -v npm >/dev/null || die "npm is needed to install kotlinc"
    log "downloading kotlin-compiler@$KOTLIN_VERSION from npm: 90 MB (94 MB installed), once, into $CACHE"
    mkdir -p "$CACHE"
    npm install --prefix "$CACHE" --no-audit --no-fund --loglevel=error "kotlin-compiler@$KOTLIN_VERSION" >&2
    chmod +x "$PKG"/bin/* 2>/dev/null || true
  fi
  KOTLINC="$PKG/bin/kotlinc"
fi
KOTLIN_HOME="$(cd "$(dirname "$KOTLINC")/.." && pwd)"
STDLIB="$KOTLIN_HOME/lib/kotlin-stdlib.jar"
[ -f "$STDLIB" ] || die "no kotlin-stdlib.jar beside $KOTLINC"

# --- JUnit 4 ---
JUNIT_JAR="${JUNIT_JAR:-/usr/share/java/junit4.jar}"
HAMCREST_JAR="${HAMCREST_JAR:-/usr/share/java/hamcrest.jar}"
if [ ! -f "$JUNIT_JAR" ]; then
  if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
    log "installing Debian's junit4"
    apt-get install -y --no-install-recommends junit4 >&2 \
      || { apt-get update >&2 && apt-get install -y --no-install-recommends junit4 >&2; }
  fi
  [ -f "$JUNIT_JAR" ] || die "no JUnit 4 jar at $JUNIT_JAR: apt-get install junit4, or set JUNIT_JAR and HAMCREST_JAR"
fi
[ -f "$HAMCREST_JAR" ] || die "no Hamcrest jar at $HAMCREST_JAR (set HAMCREST_JAR)"

APP="$REPO/android-app"
mkdir -p "$OUT"

# Compiles sources ($3...) into jar/folder $1 with classpath $2, unless nothing changed since the
# last run (same sources, classpath and compiler). Warnings are errors in main sources ($WERROR).
WERROR=-Werror
compile() {
  local dest="$1" cp="$2"; shift 2
  local stamp="$dest.stamp" sum
  sum="$( { echo "$KOTLINC $cp"; find "$@" -name '*.kt' -type f -print0 | sort -z | xargs -0 sha256sum; \
            for j in ${cp//:/ }; do [ -f "$j" ] && sha256sum "$j"; done; } | sha256sum | cut -d' ' -f1)"
  if [ -e "$dest" ] && [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$sum" ]; then
    log "up to date: ${dest#"$REPO"/}"
    return 0
  fi
  rm -rf "$dest" "$stamp"
  log "compiling ${dest#"$REPO"/}"
  local friends=""
  for j in ${cp//:/ }; do case "$j" in "$OUT"/*.jar) friends="${friends:+$friends,}$j" ;; esac; done
  local rc=0
  "$KOTLINC" -jvm-target 17 -no-reflect $WERROR -progressive \
    ${cp:+-cp "$cp"} ${friends:+-Xfriend-paths="$friends"} \
    -d "$dest" "$@" >"$dest.log" 2>&1 || rc=$?
  cat "$dest.log" >&2
  if [ "$rc" != 0 ] || [ ! -e "$dest" ]; then
    rm -rf "$dest"
    echo "0 passed, 1 failed"
    die "compilation of ${dest#"$REPO"/} failed (exit $rc)"
  fi
  echo "$sum" >"$stamp"
}

compile "$OUT/tracker.jar" "" "$APP/tracker/src/main/kotlin"
compile "$OUT/shared.jar" "$OUT/tracker.jar" "$APP/shared/src/main/kotlin"

TEST_SRC=("$HERE/TestMain.kt")
for m in tracker shared; do
  [ -d "$APP/$m/src/test/kotlin" ] && TEST_SRC+=("$APP/$m/src/test/kotlin")
done
TEST_SRC+=(${EXTRA[@]+"${EXTRA[@]}"})
TEST_CP="$OUT/tracker.jar:$OUT/shared.jar:$JUNIT_JAR:$HAMCREST_JAR"
WERROR="" # tests (including ones added from elsewhere) may warn
compile "$OUT/test-classes" "$TEST_CP" "${TEST_SRC[@]}"
[ "$COMPILE_ONLY" = 1 ] && { log "compiled (not run)"; exit 0; }

JAVA_ARGS=(-ea -cp "$TEST_CP:$OUT/test-classes:$STDLIB" "-Decvo.repo=$REPO")
[ -n "$NATIVE" ] && JAVA_ARGS+=(-Xcheck:jni "-Djava.library.path=$NATIVE" "-Decvo.native=$NATIVE")
RUN_ARGS=("$OUT/test-classes")
[ -n "$FILTER" ] && RUN_ARGS+=(--filter "$FILTER")

LOG="$OUT/test.log"
set +e
java "${JAVA_ARGS[@]}" io.ecvo.testmain.TestMainKt "${RUN_ARGS[@]}" 2>&1 | tee "$LOG"
status=${PIPESTATUS[0]}
set -e
if [ -n "$NATIVE" ] && grep -q 'WARNING in native method' "$LOG"; then
  # -Xcheck:jni only warns; a warning fails the run, counted as one more failure.
  log "JNI warnings under -Xcheck:jni (see $LOG): failing the run"
  last="$(grep -E '^[0-9]+ passed, [0-9]+ failed$' "$LOG" | tail -1)"
  p="${last%% passed*}"; f="${last#*, }"; f="${f%% failed}"
  echo "${p:-0} passed, $(( ${f:-0} + 1 )) failed"
  status=1
fi
exit "$status"
