#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# What raymapd's height-map cycle costs the bus and the map lock (issue 24): raymapd on each
# backend while `raymap replay` loops the shared Ouster drive at the recorded rate; after a
# warm-up, its `raymapd: height map` diagnostics (p50/p99 over the last window) for bytes each
# cycle's synchronise downloaded and the device generator copied, the publisher's lock hold, the
# generation time, and the integration rate.
#   tools/bench/run-heightmap-copy-benchmarks.sh [DATA_DIR] [OUT_DIR] [SECONDS]
# Backends: cpu, opencl with gpu_memory cache, opencl with gpu_memory shared (PoCL here).
# Needs the release build (built here). DDS stays on loopback.
set -euo pipefail
cd "$(dirname "$0")/../.."
data=${1:-../shared/data}
out=${2:-build/bench-results/heightmap-copy}
seconds=${3:-20}
mkdir -p "$out"
cmake --preset release >/dev/null
cmake --build --preset release --target raymap raymapd >/dev/null
bin=build/release
export CYCLONEDDS_URI="file://$PWD/config/cyclonedds-loopback.xml"
source tools/bench/bench-lib.sh
input="$data/ouster/ouster_os1_lb_n3_raycloud.ply.gz"

run() {  # run NAME BACKEND MEMORY
  local name=$1 backend=$2 memory=$3 domain=$((150 + RANDOM % 50)) config="$out/$1.yaml"
  sed -e "s/^  name: cpu$/  name: $backend\n  gpu_memory: $memory/" \
    -e "s/^  domain: .*/  domain: $domain/" -e "s/^  lock_memory: true/  lock_memory: false/" \
    config/cpu.yaml >"$config"
  "$bin/src/service/raymapd" --config "$config" 2>"$out/$name.log" &
  local daemon=$!
  sleep 2
  timeout "$seconds" "$bin/tools/raymap" replay "$input" --loop --domain "$domain" -q || true
  "$bin/tools/raymap" echo /diagnostics --domain "$domain" --count 1 --json --wait 3 \
    >"$out/$name.json" || true
  kill -TERM "$daemon"
  wait "$daemon" || true
}

run cpu cpu auto
run opencl-cache opencl cache
run opencl-shared opencl shared

summary="$out/summary.md"
{
  echo "$(machine_line "Ouster drive looped at the recorded rate, ${seconds} s per backend")"
  echo
  echo "| backend | sync bytes p50 / p99 | height-map copy bytes p50 / p99 | lock hold p50 / p99 ms | generate p99 ms | rays/s |"
  echo "| --- | ---: | ---: | ---: | ---: | ---: |"
  for name in cpu opencl-cache opencl-shared; do
    f="$out/$name.json"
    pick() { grep -o "\"$1\": *\"[^\"]*\"" "$f" | head -1 | cut -d'"' -f4; }
    echo "| $name | $(pick sync_copy_bytes_p50) / $(pick sync_copy_bytes_p99) |" \
      "$(pick heightmap_copy_bytes_p50) / $(pick heightmap_copy_bytes_p99) |" \
      "$(pick heightmap_lock_hold_p50_ms) / $(pick heightmap_lock_hold_p99_ms) |" \
      "$(pick generate_p99_ms) | $(pick ray_rate_per_s) |"
  done
} | tee "$summary"
