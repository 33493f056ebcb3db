#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Reproduces the tables of docs/benchmarks.md: raymap (1 thread and all cores, per-ray and
# per-scan) and OctoMap on the shared data sets, at 0.1 m with a 20 m max range and OctoMap's
# probabilities, plus the voxel-by-voxel agreement of the two maps.
#   tools/bench/run-benchmarks.sh [DATA_DIR] [OUT_DIR]
# DATA_DIR defaults to ../shared/data; results (JSON per run and summary.md) go to OUT_DIR
# (default build/bench-results). Needs the release build with liboctomap-dev installed.
set -euo pipefail
cd "$(dirname "$0")/../.."
data=${1:-../shared/data}
out=${2:-build/bench-results}
repeat=${RAYMAP_BENCH_REPEAT:-5}
mkdir -p "$out"
cmake --preset release >/dev/null
cmake --build --preset release --target raymap raymap-octomap raymap-microbench >/dev/null
bin=build/release/tools
common=(--resolution 0.1 --max-range 20 --hit 0.7 --miss 0.4)

source tools/bench/bench-lib.sh

summary="$out/summary.md"
{
  machine_line "repeat $repeat"
  echo
  echo "| data | semantics | raymap 1 thread (rays/s) | raymap $(nproc) threads (rays/s) | OctoMap (rays/s) | speed-up vs OctoMap | free raymap / OctoMap | occupied raymap / OctoMap | agreement |"
  echo "| --- | --- | ---: | ---: | ---: | ---: | --- | --- | ---: |"
} >"$summary"

run() {  # run NAME INPUT [extra options]
  local name=$1 input=$2
  shift 2
  for semantics in ray scan; do
    local tag="$name-$semantics"
    "$bin/raymap" bench "$input" "${common[@]}" "$@" --semantics-list "$semantics" \
      --threads-list 1,0 --repeat "$repeat" --json "$out/$tag-raymap.json" 2>/dev/null
    "$bin/raymap" populate "$input" "${common[@]}" "$@" --semantics "$semantics" -q \
      --output "$out/$tag.rmap"
    "$bin/raymap-octomap" "$input" "${common[@]}" "$@" --semantics "$semantics" \
      --compare "$out/$tag.rmap" >"$out/$tag-octomap.json"
    local st mt oc
    st=$(value rays_per_second "$out/$tag-raymap.json" 1)
    mt=$(value rays_per_second "$out/$tag-raymap.json" 2)
    oc=$(value rays_per_second "$out/$tag-octomap.json")
    printf '| %s | %s | %.0f | %.0f | %.0f | %.0fx | %s / %s | %s / %s | %.4f %% |\n' \
      "$name" "$semantics" "$st" "$mt" "$oc" "$(awk -v a="$st" -v b="$oc" 'BEGIN { print a / b }')" \
      "$(value voxels_free "$out/$tag-raymap.json")" "$(value voxels_free "$out/$tag-octomap.json")" \
      "$(value voxels_occupied "$out/$tag-raymap.json")" \
      "$(value voxels_occupied "$out/$tag-octomap.json")" \
      "$(awk -v a="$(value agreement "$out/$tag-octomap.json")" 'BEGIN { print a * 100 }')" >>"$summary"
  done
}

run_data_sets run "$data"

"$bin/raymap-microbench" --benchmark_repetitions=5 --benchmark_report_aggregates_only=true \
  --benchmark_format=json >"$out/microbench.json" 2>/dev/null
cat "$summary"
