#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Reproduces the map-representation tables of docs/benchmarks.md: the throughput of several
# --mode values on the same rays and backend (per-ray semantics, 0.1 m, 20 m max range, OctoMap's
# probabilities), on the CPU backend (1 thread and all cores), on OpenCL and on CUDA when
# `raymap devices` lists a device for them, fresh maps and steady state. The modes take turns, one timed run each per round, and
# each rate is the median over the rounds: this VM's speed drifts by 15 % over a minute, and
# back-to-back blocks of runs would carry that drift into the ratios. Ratios are to the first mode.
#   RAYMAP_BENCH_MODES="occupancy ndt-om ndt-tm" tools/bench/run-mode-benchmarks.sh \
#       [DATA_DIR] [OUT_DIR] [extra raymap options...]
# RAYMAP_BENCH_MODES defaults to "occupancy ndt-om ndt-tm"; "occupancy decay tsdf" gives the
# decay-rate and TSDF table. Needs the release build (built here).
set -euo pipefail
cd "$(dirname "$0")/../.."
data=${1:-../shared/data}
out=${2:-build/bench-results}
shift $(($# > 2 ? 2 : $#))
repeat=${RAYMAP_BENCH_REPEAT:-5}
read -r -a modes <<<"${RAYMAP_BENCH_MODES:-occupancy ndt-om ndt-tm}"
tag=$(IFS=-; echo "${modes[*]}")
mkdir -p "$out"
cmake --preset release >/dev/null
cmake --build --preset release --target raymap >/dev/null
bin=build/release/tools
common=(--resolution 0.1 --max-range 20 --hit 0.7 --miss 0.4 --repeat 1 --semantics-list ray)

source tools/bench/bench-lib.sh

summary="$out/modes-$tag-summary.md"
{
  machine_line "$repeat rounds, modes interleaved, median"
  echo
  line="| data | backend | map |"
  rule="| --- | --- | --- |"
  for mode in "${modes[@]}"; do
    line+=" $mode (rays/s) |"
    rule+=" ---: |"
  done
  for mode in "${modes[@]:1}"; do
    line+=" $mode / ${modes[0]} |"
    rule+=" ---: |"
  done
  echo "$line updates dropped |"
  echo "$rule --- |"
} >"$summary"

# row NAME INPUT LABEL MAP_LABEL [raymap options]
row() {
  local name=$1 input=$2 label=$3 map=$4
  shift 4
  local rates=() dropped=()
  for mode in "${modes[@]}"; do
    rm -f "$out/mode-$name-$label-$map-$mode".*.json
  done
  for round in $(seq "$repeat"); do
    for mode in "${modes[@]}"; do
      "$bin/raymap" bench "$input" "${common[@]}" --mode "$mode" "$@" \
        --json "$out/mode-$name-$label-$map-$mode.$round.json" 2>/dev/null
    done
  done
  for mode in "${modes[@]}"; do
    local files=("$out/mode-$name-$label-$map-$mode".*.json)
    rates+=("$(for f in "${files[@]}"; do value rays_per_second "$f"; done | sort -g |
      awk '{ v[NR] = $1 } END { print NR % 2 ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2 }')")
    dropped+=("$(for f in "${files[@]}"; do value updates_dropped "$f" || echo 0; done |
      awk '{ s += $1 } END { print s + 0 }')")
  done
  local line="| $name | $label | $map |"
  for rate in "${rates[@]}"; do
    line+=" $(printf '%.0f' "$rate") |"
  done
  for rate in "${rates[@]:1}"; do
    line+=" $(awk -v a="$rate" -v b="${rates[0]}" 'BEGIN { printf "%.2f", a / b }') |"
  done
  echo "$line $(IFS=/; echo "${dropped[*]}") |" >>"$summary"
}

# has_device API: true when `raymap devices` lists a device under its OpenCL or CUDA heading.
has_device() {
  "$bin/raymap" devices 2>/dev/null |
    awk -v api="$1" '/^(OpenCL|CUDA)$/ { in_api = ($0 == api) } in_api && /^  device [0-9]+:/ { found = 1 }
      END { exit !found }'
}

run() {  # run NAME INPUT [options]
  local name=$1 input=$2
  shift 2
  for map in fresh steady; do
    local steady=()
    if [ "$map" = steady ]; then steady=(--steady-state); fi
    row "$name" "$input" "cpu-1" "$map" "$@" "${steady[@]}" --threads-list 1
    row "$name" "$input" "cpu-$(nproc)" "$map" "$@" "${steady[@]}" --threads-list 0
    if has_device OpenCL; then
      row "$name" "$input" "opencl" "$map" "$@" "${steady[@]}" --backend opencl
    fi
    if has_device CUDA; then
      row "$name" "$input" "cuda" "$map" "$@" "${steady[@]}" --backend cuda
    fi
  done
}

run ouster "$data/ouster/ouster_os1_lb_n3_raycloud.ply.gz" "$@"
cat "$summary"
