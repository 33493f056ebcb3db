#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# What raymapd's height-map cycle costs the bus and the map lock (issue 24): raymapd on each
# backend while `raymap replay` loops the shared Ouster drive at the recorded rate; after a
# warm-up, its `raymapd: height map` diagnostics (p50/p99 over the last window) for bytes each
# cycle downloaded (sync) and copied of the map for the height map, the publisher's lock hold,
# the generation time, the period and latency, and the integration rate.
#   tools/bench/run-heightmap-copy-benchmarks.sh [DATA_DIR] [OUT_DIR] [SECONDS] [ROUNDS]
# Backends: cpu, opencl with gpu_memory cache, opencl with gpu_memory shared (PoCL here).
# BASELINE=DIR (a build directory of an earlier commit, with tools/raymap and
# src/service/raymapd built): the opencl runs of that build alternate with this build's, round by
# round (A B A B ...), and the summary gives medians over the rounds and this/baseline ratios.
# Needs the release build (built here). DDS stays on loopback.
set -euo pipefail
cd "$(dirname "$0")/../.."
data=${1:-../shared/data}
out=${2:-build/bench-results/heightmap-copy}
seconds=${3:-20}
rounds=${4:-5}
baseline=${BASELINE:-}
mkdir -p "$out"
cmake --preset release >/dev/null
cmake --build --preset release --target raymap raymapd >/dev/null
export CYCLONEDDS_URI="file://$PWD/config/cyclonedds-loopback.xml"
source tools/bench/bench-lib.sh
input="$data/ouster/ouster_os1_lb_n3_raycloud.ply.gz"

run() {  # run NAME BUILD_DIR BACKEND MEMORY ROUND
  local name=$1 bin=$2 backend=$3 memory=$4 round=$5 domain=$((150 + RANDOM % 50))
  local config="$out/$name.yaml"
  sed -e "s/^  name: cpu$/  name: $backend\n  gpu_memory: $memory/" \
    -e "s/^  domain: .*/  domain: $domain/" -e "s/^  lock_memory: true/  lock_memory: false/" \
    config/cpu.yaml >"$config"
  "$bin/src/service/raymapd" --config "$config" 2>"$out/$name-$round.log" &
  local daemon=$!
  sleep 2
  timeout "$seconds" "$bin/tools/raymap" replay "$input" --loop --domain "$domain" -q || true
  "$bin/tools/raymap" echo /diagnostics --domain "$domain" --count 1 --json --wait 3 \
    >"$out/$name-$round.json" || true
  kill -TERM "$daemon"
  wait "$daemon" || true
}

names=(cpu opencl-cache opencl-shared)
[ -n "$baseline" ] && names+=(baseline-opencl-cache baseline-opencl-shared)
for round in $(seq 1 "$rounds"); do
  run cpu build/release cpu auto "$round"
  for memory in cache shared; do
    run "opencl-$memory" build/release opencl "$memory" "$round"
    [ -n "$baseline" ] && run "baseline-opencl-$memory" "$baseline" opencl "$memory" "$round"
  done
done

pick() {  # pick KEY FILE: a diagnostics value (they are strings in the JSON)
  grep -o "\"$1\": *\"[^\"]*\"" "$2" | head -1 | cut -d'"' -f4
}
median() {  # median KEY NAME: the median over the rounds
  for f in "$out/$2"-*.json; do pick "$1" "$f"; done | grep -v '^$' | sort -g |
    awk '{v[NR]=$1} END {if (NR) print v[int((NR+1)/2)]; else print "-"}'
}

summary="$out/summary.md"
{
  echo "$(machine_line "Ouster drive looped at the recorded rate, ${seconds} s per run, medians of $rounds rounds")"
  echo
  echo "| run | sync bytes p99 | map bytes copied p99 | transfer bytes p99 | lock hold p50 / p99 ms | generate p99 ms | period error p99 ms | latency p99 ms | rays/s |"
  echo "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"
  for name in "${names[@]}"; do
    echo "| $name | $(median sync_copy_bytes_p99 "$name") | $(median heightmap_copy_bytes_p99 "$name") |" \
      "$(median heightmap_transfer_bytes_p99 "$name") |" \
      "$(median heightmap_lock_hold_p50_ms "$name") / $(median heightmap_lock_hold_p99_ms "$name") |" \
      "$(median generate_p99_ms "$name") | $(median period_error_p99_ms "$name") |" \
      "$(median latency_p99_ms "$name") | $(median ray_rate_per_s "$name") |"
  done
  if [ -n "$baseline" ]; then
    echo
    for memory in cache shared; do
      now=$(median ray_rate_per_s "opencl-$memory")
      before=$(median ray_rate_per_s "baseline-opencl-$memory")
      echo "opencl $memory: rays/s this build / baseline = $(awk -v a="$now" -v b="$before" 'BEGIN {if (b > 0) printf "%.2f", a / b; else print "-"}')"
    done
  fi
} | tee "$summary"
