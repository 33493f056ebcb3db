#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Fuzzes one target (or all, one after another) for longer than CI does:
#   tools/fuzz.sh TARGET|all MINUTES
# TARGET is a name from tests/fuzz/CMakeLists.txt (ply_header, map_file, cdr_point_cloud, ...).
# Builds the fuzz preset (Clang, libFuzzer, ASan + UBSan), keeps each target's growing corpus in
# build/fuzz/long/TARGET/corpus between runs, and appends each run's statistics (executions,
# executions per second, edges and features covered) to build/fuzz/fuzz-stats.jsonl. A crash
# stops with the input saved and the command to keep it as a regression test.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ $# -ne 2 ]; then
  echo "usage: tools/fuzz.sh TARGET|all MINUTES" >&2
  exit 2
fi
target=$1 minutes=$2
cmake --preset fuzz >/dev/null
if [ "$target" = all ]; then
  # Every fuzz program the build defines (CMake: raymap_add_fuzzer in tests/fuzz).
  targets=$(ninja -C build/fuzz -t targets all | sed -n 's/^tests\/fuzz\/fuzz_\([a-z0-9_]*\): .*/\1/p')
else
  targets=$target
fi
status=0
for name in $targets; do
  cmake --build --preset fuzz --target "fuzz_$name" >/dev/null
  echo "== fuzz_$name for $minutes min ($(date +%T))"
  tools/fuzz-run.sh "build/fuzz/tests/fuzz/fuzz_$name" "$name" $((minutes * 60)) \
    "build/fuzz/long/$name" | tee -a build/fuzz/fuzz-stats.jsonl || status=1
done
exit $status
