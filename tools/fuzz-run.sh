#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Runs one libFuzzer target for a bounded time: tools/fuzz-run.sh EXE NAME SECONDS WORKDIR
# (CTest in a fuzz build calls it; tools/fuzz.sh for longer runs). The corpus grows in
# WORKDIR/corpus, read together with the checked-in seeds (tests/fuzz/corpus/NAME) and the
# regression inputs (tests/fuzz/regressions/NAME). Exit status: libFuzzer's (non-zero on a crash,
# a leak, a timeout or running out of memory); the input that failed is saved in
# WORKDIR/artifacts and named on stderr. The last line is the run's statistics as JSON.
set -euo pipefail
if [ $# -ne 4 ]; then
  echo "usage: tools/fuzz-run.sh EXE NAME SECONDS WORKDIR" >&2
  exit 2
fi
exe=$1 name=$2 seconds=$3 work=$4
# libFuzzer's per-input timeout is wall-clock time: a long run at `nice` on a busy machine can be
# starved past 10 s on an input that runs in a fraction of a second. FUZZ_TIMEOUT_S raises it
# for such runs (CI keeps 10).
timeout=${FUZZ_TIMEOUT_S:-10}
source_dir="$(cd "$(dirname "$0")/.." && pwd)"
seeds="$source_dir/tests/fuzz/corpus/$name"
regressions="$source_dir/tests/fuzz/regressions/$name"
dict="$source_dir/tests/fuzz/dict/$name.dict"
mkdir -p "$work/corpus" "$work/artifacts"
dirs=("$work/corpus" "$seeds")
[ -d "$regressions" ] && dirs+=("$regressions")
args=(
  -max_total_time="$seconds"
  -timeout="$timeout"         # seconds per input: anything slower is a bug (quadratic parsing)
  -rss_limit_mb=2560          # a header that makes a reader allocate gigabytes is a bug
  -malloc_limit_mb=2048
  -max_len=262144
  -print_final_stats=1
  -artifact_prefix="$work/artifacts/"
)
[ -f "$dict" ] && args+=(-dict="$dict")
# One process; every sanitizer report is fatal (halt_on_error) and leaks count as failures.
export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
log="$work/last-run.log"
status=0
"$exe" "${args[@]}" "${dirs[@]}" >"$log" 2>&1 || status=$?
# The final statistics: executions, their rate, edges (cov) and features (ft) reached.
runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -1)
last=$(grep -E '^#[0-9]+' "$log" | tail -1 || true)
cov=$(sed -n 's/.* cov: \([0-9]*\).*/\1/p' <<<"$last")
ft=$(sed -n 's/.* ft: \([0-9]*\).*/\1/p' <<<"$last")
corpus=$(find "$work/corpus" -type f | wc -l)
if [ "$status" -ne 0 ]; then
  tail -60 "$log" >&2
  echo "fuzz $name: FAILED (exit $status); the input is in $work/artifacts/:" >&2
  ls -l "$work/artifacts/" >&2
  echo "Fix the bug, then keep the input as a regression test:" \
    "cp $work/artifacts/<file> tests/fuzz/regressions/$name/" >&2
fi
printf '{"target":"%s","seconds":%s,"status":%d,"executions":%s,"exec_per_s":%s,"cov":%s,"ft":%s,"corpus_files":%s}\n' \
  "$name" "$seconds" "$status" "${runs:-0}" "${rate:-0}" "${cov:-0}" "${ft:-0}" "$corpus"
exit "$status"
