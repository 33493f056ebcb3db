#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Height-map timings for docs/benchmarks.md: the Google Benchmark (a 20 m x 20 m x 20 m box at
# 0.1 m, 200 x 200 columns, over the simulated yard; planar and fill; every generator this build
# and machine have), then `raymap heightmap --repeat` on maps of the shipped yard scene and, when
# present, the shared Ouster data.
#   tools/bench/run-heightmap-benchmarks.sh [DATA_DIR] [OUT_DIR] [BUILD_DIR]
# BUILD_DIR: an existing build to use (a CUDA build, say); default: the
# release preset, configured and built here.
set -euo pipefail
cd "$(dirname "$0")/../.."
data=${1:-../shared/data}
out=${2:-build/bench-results}
build=${3:-}
repeat=${RAYMAP_BENCH_REPEAT:-5}
mkdir -p "$out"
if [ -z "$build" ]; then
  build=build/release
  cmake --preset release >/dev/null
fi
cmake --build "$build" --target raymap raymap-heightmap-bench >/dev/null
bin=$build/tools
source tools/bench/bench-lib.sh

echo "== $(machine_line "repeat $repeat")"
"$bin/raymap-heightmap-bench" --benchmark_repetitions="$repeat" \
  --benchmark_report_aggregates_only=true --benchmark_format=json \
  --benchmark_out="$out/heightmap-bench.json" --benchmark_out_format=json \
  --benchmark_format=console 2>&1 | grep -E "median|ERROR" || true

map_run() {  # map_run NAME MAP CENTRE: every generator that starts here, both modes
  local name=$1 map=$2 centre=$3
  for backend in cpu opencl cuda; do
    if ! "$bin/raymap" heightmap "$map" --center "$centre" --backend "$backend" -q 2>/dev/null; then
      echo "$name $backend: not available"
      continue
    fi
    for mode in planar fill; do
      local f="$out/heightmap-$name-$backend-$mode.json"
      "$bin/raymap" heightmap "$map" --center "$centre" --size 20 --mode "$mode" \
        --virtual-surfaces --backend "$backend" --repeat "$repeat" --json >"$f"
      echo "$name $backend $mode: median $(value seconds_median "$f") s," \
        "$(value surface_cells "$f") surface cells"
    done
  done
}

"$bin/raymap" simulate config/scenes/yard.yaml --rays "$out/yard.ply" -q
"$bin/raymap" populate "$out/yard.ply" --output "$out/yard.rmap" -q
map_run yard "$out/yard.rmap" 0,0,0
ouster="$data/ouster/ouster_os1_lb_n3_raycloud.ply.gz"
if [ -f "$ouster" ]; then
  "$bin/raymap" populate "$ouster" --max-range 20 --output "$out/ouster.rmap" -q
  # The sensor started near the origin, about 1.9 m above the ground (the map's lowest voxels).
  map_run ouster "$out/ouster.rmap" 0,0,-1.9
fi
