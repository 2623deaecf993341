#!/usr/bin/env bash
# Runs every cargo-fuzz target for SECONDS each (default 600), one after the other,
# niced, one libFuzzer job at a time, and prints a table of executions and findings.
#
#   scripts/fuzz.sh [SECONDS] [TARGET...]
#
# Needs the nightly toolchain and cargo-fuzz (`rustup toolchain install nightly`,
# `cargo install cargo-fuzz`). Seeds: scripts/fuzz/seeds.py (testdata/ and, when
# present, ../shared/datasets). Crashes land in fuzz/artifacts/TARGET/; the exit
# status is non-zero if any target found one. Summary: fuzz/results.md (for a subset of
# targets: fuzz/artifacts/results-TARGETS.md).
set -uo pipefail
cd "$(dirname "$0")/.."
secs=${1:-600}
shift || true
targets=("$@")
out=fuzz/results.md
# A run of some targets only writes its own table, not over the summary of all of them.
[ ${#targets[@]} -gt 0 ] && out="fuzz/artifacts/results-$(IFS=-; echo "${targets[*]}").md"
[ ${#targets[@]} -eq 0 ] && targets=(io_png io_text io_imu levels prepare_motion jni_args depth16)

declare -A max_len=([io_png]=16384 [io_text]=4096 [io_imu]=4096 [levels]=256 [prepare_motion]=40000 [jni_args]=256 [depth16]=86402)

[ -d fuzz/corpus ] || python3 scripts/fuzz/seeds.py
nice -n 19 cargo +nightly fuzz build || exit 1

mkdir -p fuzz/artifacts
{
  echo "| target | seconds | executions | exec/s | corpus | coverage | result |"
  echo "|---|---|---|---|---|---|---|"
} > "$out"
status=0
for t in "${targets[@]}"; do
  mkdir -p "fuzz/corpus/$t" "fuzz/artifacts/$t"
  log="fuzz/artifacts/$t/run.log"
  echo "=== $t: ${secs}s"
  nice -n 19 cargo +nightly fuzz run "$t" "fuzz/corpus/$t" -- \
    -max_total_time="$secs" -timeout=10 -rss_limit_mb=2048 -malloc_limit_mb=512 \
    -max_len="${max_len[$t]:-4096}" -print_final_stats=1 >"$log" 2>&1
  rc=$?
  runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' | tail -1)
  rate=$(grep -o 'stat::average_exec_per_sec: *[0-9]*' "$log" | grep -o '[0-9]*$' | tail -1)
  cov=$(grep -o 'cov: [0-9]*' "$log" | tail -1 | grep -o '[0-9]*')
  corp=$(ls "fuzz/corpus/$t" | wc -l)
  if [ $rc -eq 0 ]; then result="no finding"; else
    result="FINDING (exit $rc): $(grep -m1 -oE 'ERROR: libFuzzer: [a-z-]+|==[0-9]+==ERROR: [A-Za-z]+: [a-z-]+|panicked at [^ ]+' "$log" | head -1)"
    status=1
  fi
  echo "| $t | $secs | ${runs:-?} | ${rate:-?} | $corp | ${cov:-?} | $result |" | tee -a "$out"
done
cat "$out"
exit $status
