#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# The Python module's integration rate against the C++ library's, interleaved: per round and
# data set, raymap-mapper-bench (C++) and tools/bench/python_mapper_bench.py (Python: the scans as
# arrays, and in place) on the same recording, the order rotating by round; prints each run's JSON
# and, per data set and Python way, the median over the rounds of Python's rays/s over C++'s in
# the same round (docs/benchmarks.md, "Python module").
#   tools/bench/run-python-benchmarks.sh BUILD_DIR [ROUNDS] [REPEAT]
set -euo pipefail
cd "$(dirname "$0")/../.."
build=${1:?usage: run-python-benchmarks.sh BUILD_DIR [ROUNDS] [REPEAT]}
rounds=${2:-5}
repeat=${3:-5}
data=../shared/data
sets=("$data/ouster/ouster_os1_lb_n3_raycloud.ply.gz" "$data/3dtk/3dtk_raycloud.ply.gz"
  "$data/octomap/octomap_scan_raycloud.ply.gz")
out=$(mktemp)
trap 'rm -f "$out"' EXIT
cpp() { "$build/tools/raymap-mapper-bench" "$1" --repeat "$repeat"; }
py() { PYTHONPATH="$build/python" /usr/bin/python3 tools/bench/python_mapper_bench.py "$@" --repeat "$repeat"; }
for round in $(seq 1 "$rounds"); do
  for set in "${sets[@]}"; do
    [ -f "$set" ] || { echo "run-python-benchmarks: $set is missing" >&2; exit 1; }
    case $((round % 3)) in
      1) a=$(cpp "$set"); b=$(py "$set"); c=$(py "$set" --in-place) ;;
      2) b=$(py "$set"); c=$(py "$set" --in-place); a=$(cpp "$set") ;;
      0) c=$(py "$set" --in-place); a=$(cpp "$set"); b=$(py "$set") ;;
    esac
    printf '%s\n%s\n%s\n' "$a" "$b" "$c" | tee -a "$out"
  done
done
/usr/bin/python3 - "$out" <<'PY'
import json, statistics, sys
runs = [json.loads(line) for line in open(sys.argv[1])]
for recording in dict.fromkeys(r["recording"] for r in runs):
    def rates(api):
        return [r["rays_per_s"] for r in runs if r["recording"] == recording and r["api"] == api]
    cpp = rates("c++")
    print(f"{recording.split('/')[-1]}: C++ median {statistics.median(cpp):,.0f} rays/s")
    for api in ("python arrays", "python in place"):
        ratios = [p / c for p, c in zip(rates(api), cpp)]
        print(f"  {api}: median {statistics.median(rates(api)):,.0f} rays/s; / C++ per round: "
              f"median {statistics.median(ratios):.3f} (range {min(ratios):.3f} to "
              f"{max(ratios):.3f}, {len(ratios)} rounds)")
PY
