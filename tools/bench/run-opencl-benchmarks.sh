#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Reproduces the OpenCL table of docs/benchmarks.md: the OpenCL backend against the CPU backend
# (all cores) on the shared data sets, at 0.1 m with a 20 m max range and OctoMap's
# probabilities, both semantics, with the device statistics (transfers, cache, dropped updates).
#   tools/bench/run-opencl-benchmarks.sh [DATA_DIR] [OUT_DIR] [extra raymap options...]
# e.g. extra options --opencl-device 1 or --gpu-cache 256MiB. Needs an OpenCL platform (PoCL
# runs on the CPU) and the release build.
set -euo pipefail
cd "$(dirname "$0")/../.."
data=${1:-../shared/data}
out=${2:-build/bench-results}
shift $(($# > 2 ? 2 : $#))
repeat=${RAYMAP_BENCH_REPEAT:-5}
# RAYMAP_BENCH_STEADY=1: time a second pass into the same map and backend (--steady-state).
steady=()
if [ "${RAYMAP_BENCH_STEADY:-0}" = 1 ]; then
  steady=(--steady-state)
fi
mkdir -p "$out"
cmake --preset release >/dev/null
cmake --build --preset release --target raymap >/dev/null
bin=build/release/tools
common=(--resolution 0.1 --max-range 20 --hit 0.7 --miss 0.4 --repeat "$repeat" "${steady[@]}")

source tools/bench/bench-lib.sh

summary="$out/opencl-summary${steady:+-steady}.md"
{
  machine_line "repeat $repeat ${steady[*]}"
  echo
  echo "| data | semantics | CPU $(nproc) threads (rays/s) | OpenCL (rays/s) | OpenCL / CPU | device memory | to device (MB) | from device (MB) | cache hit rate | updates dropped | plan / wait / sync (s) |"
  echo "| --- | --- | ---: | ---: | ---: | --- | ---: | ---: | ---: | ---: | --- |"
} >"$summary"

run() {  # run NAME INPUT [extra options]
  local name=$1 input=$2
  shift 2
  for semantics in ray scan; do
    local tag="$name-$semantics"
    "$bin/raymap" bench "$input" "${common[@]}" "$@" --semantics-list "$semantics" \
      --threads-list 0 --json "$out/$tag-cpu.json" 2>/dev/null
    "$bin/raymap" bench "$input" "${common[@]}" "$@" --semantics-list "$semantics" \
      --backend opencl "${extra[@]}" --json "$out/$tag-opencl.json" 2>/dev/null
    local cpu ocl f="$out/$tag-opencl.json"
    cpu=$(value rays_per_second "$out/$tag-cpu.json")
    ocl=$(value rays_per_second "$f")
    local memory=cache
    case "$(text device "$f")" in *"shared memory"*) memory=shared ;; esac
    printf '| %s | %s | %.0f | %.0f | %.2f | %s | %.0f | %.0f | %.4f | %s | %.3f / %.3f / %.3f |\n' \
      "$name" "$semantics" "$cpu" "$ocl" "$(awk -v a="$ocl" -v b="$cpu" 'BEGIN { print a / b }')" "$memory" \
      "$(awk -v a="$(value bytes_to_device "$f")" 'BEGIN { print a / 1e6 }')" \
      "$(awk -v a="$(value bytes_from_device "$f")" 'BEGIN { print a / 1e6 }')" \
      "$(value cache_hit_rate "$f")" "$(value updates_dropped "$f")" \
      "$(value plan_seconds "$f")" "$(value wait_seconds "$f")" "$(value sync_seconds "$f")" \
      >>"$summary"
  done
  echo "device: $(text device "$out/$name-ray-opencl.json")" >"$out/opencl-device.txt"
}

extra=("$@")
run_data_sets run "$data"
cat "$out/opencl-device.txt" >>"$summary"
cat "$summary"
