#!/usr/bin/env bash
# Builds libecvo_jni (release) and the Java drivers of rust/ecvo-jni/tests/drivers, then
# runs one of them on a JVM with -Xcheck:jni, on testdata/synth_phone_320x180:
#
#   scripts/jni-drivers.sh soak   [FRAMES=100000] [RATE=300] [REPORT=5000] [WARMUP=auto: cloud and pose window full]
#   scripts/jni-drivers.sh stress [SECONDS=120] [THREADS=8]
#   scripts/jni-drivers.sh faults
#
# Not part of the default test run (the soak takes minutes). Any JNI warning fails the
# run. Niced: the machine is shared.
set -euo pipefail
cd "$(dirname "$0")/.."
what=${1:?soak, stress or faults}; shift
command -v javac >/dev/null || { echo "javac (JDK 17) is needed" >&2; exit 2; }
nice -n 10 cargo build --release -q -p ecvo-jni --lib
lib=$(cargo metadata --format-version 1 --no-deps | python3 -c 'import json,sys; print(json.load(sys.stdin)["target_directory"])')/release
classes=target/jni-drivers
mkdir -p "$classes"
javac -d "$classes" rust/ecvo-jni/tests/drivers/io/ecvo/*.java
case "$what" in
  soak) main=io.ecvo.Soak; jvm=(-Xms96m -Xmx96m -XX:+AlwaysPreTouch -XX:+UseSerialGC) ;;
  stress) main=io.ecvo.Stress; jvm=(-Xmx512m) ;;
  faults) main=io.ecvo.JniFaults; jvm=() ;;
  *) echo "unknown driver $what" >&2; exit 2 ;;
esac
log=$(mktemp)
set +e
# The outer watchdog: the drivers have their own; this catches a hang in the JVM itself.
timeout --signal=KILL 3600 nice -n 10 java -Xcheck:jni "${jvm[@]}" -Djava.library.path="$lib" -cp "$classes" \
  "$main" testdata/synth_phone_320x180 "$@" 2>&1 | tee "$log"
rc=${PIPESTATUS[0]}
set -e
if grep -q "WARNING in native method" "$log"; then echo "-Xcheck:jni warned" >&2; rc=1; fi
rm -f "$log"
exit "$rc"
