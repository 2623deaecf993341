#!/usr/bin/env bash
# Self-test of LambdaDesugar.java: desugars the whole kotlin-stdlib.jar, checks that no
# invokedynamic is left (javap), then runs DesugarProbe.kt (compareBy, split, joinToString,
# AbstractCollection.toString, Regex, copyRecursively, ...) on the JVM with the original and with
# the desugared stdlib; the outputs must be identical and non-empty.
# Usage: scripts/android/desugar/test-desugar.sh   (needs kotlinc and libasm-java, as build-apk.sh)
set -euo pipefail
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
REPO="$(cd "$HERE/../../.." && pwd)"
log() { echo "[test-desugar] $*" >&2; }
die() { echo "[test-desugar] error: $*" >&2; exit 1; }
KOTLINC="${KOTLINC:-${KOTLINC_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/ecvo/kotlinc}/node_modules/kotlin-compiler/bin/kotlinc}"
STDLIB="$(cd "$(dirname "$KOTLINC")/.." && pwd)/lib/kotlin-stdlib.jar"
ASM_CP=/usr/share/java/asm.jar:/usr/share/java/asm-tree.jar
[ -f "$STDLIB" ] || die "no $STDLIB (run scripts/android/build-apk.sh first)"
[ -f /usr/share/java/asm-tree.jar ] || die "no libasm-java (run scripts/android/build-apk.sh first)"
W="$REPO/target/desugar-test"
rm -rf "$W"; mkdir -p "$W/tool" "$W/probe" "$W/x"
javac -nowarn -cp "$ASM_CP" -d "$W/tool" "$HERE/LambdaDesugar.java"
# META-INF/versions (Java 9+ variants) stays out, as in build-apk.sh.
(cd "$W/x" && unzip -q "$STDLIB" -x 'META-INF/versions/*' && jar cf "$W/stdlib-8.jar" .)
before="$(cd "$W/x" && find . -name '*.class' -print0 | xargs -0 javap -c -p 2>/dev/null | grep -c invokedynamic || true)"
java -cp "$ASM_CP:$W/tool" LambdaDesugar "$W/stdlib-8.jar" "$W/stdlib-desugared.jar" 2>"$W/desugar.log" \
  || { cat "$W/desugar.log" >&2; die "LambdaDesugar failed on kotlin-stdlib"; }
rm -rf "$W/x"; mkdir -p "$W/x"
(cd "$W/x" && unzip -q "$W/stdlib-desugared.jar")
after="$(cd "$W/x" && find . -name '*.class' -print0 | xargs -0 javap -c -p 2>/dev/null | grep -c invokedynamic || true)"
log "invokedynamic in kotlin-stdlib: $before before, $after after ($(tail -1 "$W/desugar.log"))"
[ "$before" -gt 0 ] || die "the stdlib had no invokedynamic: the test proves nothing"
[ "$after" = 0 ] || die "$after invokedynamic left after desugaring"
"$KOTLINC" -jvm-target 1.8 -Xlambdas=class -Xsam-conversions=class -nowarn -d "$W/probe" "$HERE/DesugarProbe.kt" \
  >"$W/kotlinc.log" 2>&1 || { cat "$W/kotlinc.log" >&2; die "kotlinc failed"; }
java -cp "$W/probe:$W/stdlib-8.jar" desugarprobe.DesugarProbeKt > "$W/original.txt"
java -cp "$W/probe:$W/stdlib-desugared.jar" desugarprobe.DesugarProbeKt > "$W/desugared.txt"
[ -s "$W/original.txt" ] || die "the probe printed nothing"
diff "$W/original.txt" "$W/desugared.txt" >&2 || die "the desugared stdlib behaves differently (diff above)"
log "same output ($(wc -l < "$W/original.txt") lines) with the original and the desugared stdlib"
echo "desugar self-test: 1 passed, 0 failed"
