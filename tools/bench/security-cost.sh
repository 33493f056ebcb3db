#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# What DDS Security costs raymapd (docs/benchmarks.md, "DDS Security"): raymap-load's simulated
# Ouster OS-1-128 (128 x 1024 points at 10 Hz, and at RATES x that) into raymapd with and without
# encryption, interleaved (open, secure, open, secure, ...), on loopback. Per run: the map period
# and latency raymap-load measures, and raymapd's CPU time per second of the run (/proc).
#   tools/bench/security-cost.sh BUILD_DIR [ROUNDS] [SECONDS]    (RATES="10 40" by default)
set -euo pipefail
build=${1:?usage: $0 BUILD_DIR [ROUNDS] [SECONDS]}
rounds=${2:-3}
seconds=${3:-8}
rates=${RATES:-"10 40"}
src=$(cd "$(dirname "$0")/../.." && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
export CYCLONEDDS_URI="file://$src/config/cyclonedds-loopback.xml"
domain=$((150 + $$ % 50))
"$build/tools/raymap" security create-keystore "$work/keystore" --domain $domain >/dev/null
for enclave in /raymap/raymapd /raymap/tools; do
  "$build/tools/raymap" security create-enclave "$work/keystore" "$enclave" --domain $domain >/dev/null
done
config() {  # $1: "" or a dds.security section
  cat <<YAML
map: {resolution: 0.1, window: [12, 12, 4]}
backend: {name: cpu, threads: 2}
pose: {source: odometry, topic: rt/odom, world_frame: odom, base_frame: base_link}
sensors:
  - {name: lidar, topic: rt/points, frame: lidar, min_range: 0.3, max_range: 60, max_points: 131072}
heightmap: {rate_hz: 5, size: 20, base_height: 1.2}
dds:
  domain: $domain
$1
YAML
}
config "" >"$work/open.yaml"
config "  security: {keystore: $work/keystore}" >"$work/secure.yaml"
cpu_ticks() { awk '{print $14 + $15}' "/proc/$1/stat"; }
hz=$(getconf CLK_TCK)
for round in $(seq "$rounds"); do
  for rate in $rates; do
    for mode in open secure; do
      "$build/src/service/raymapd" --config "$work/$mode.yaml" 2>"$work/raymapd.log" &
      pid=$!
      sleep 1.5
      before=$(cpu_ticks $pid)
      env_vars=()
      if [ "$mode" = secure ]; then
        env_vars=(ROS_SECURITY_ENABLE=true ROS_SECURITY_STRATEGY=Enforce
                  "ROS_SECURITY_KEYSTORE=$work/keystore")
      fi
      env "${env_vars[@]}" "$build/tools/raymap-load" --domain $domain --beams 128 --columns 1024 \
        --scan-rate "$rate" --warmup 2 --duration "$seconds" >"$work/load.json" 2>/dev/null
      after=$(cpu_ticks $pid)
      kill -TERM $pid; wait $pid || true
      python3 - "$work/load.json" "$mode" "$rate" "$round" "$before" "$after" "$hz" "$seconds" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
mode, rate, rnd = sys.argv[2], float(sys.argv[3]), int(sys.argv[4])
cpu = (int(sys.argv[6]) - int(sys.argv[5])) / int(sys.argv[7]) / (float(sys.argv[8]) + 2)
print(json.dumps({"round": rnd, "mode": mode, "load": rate / 10, "maps": r["maps_received"],
  "period_mean_ms": r["map_period_mean_ms"], "period_p99_ms": r["map_period_ms"]["p99"],
  "latency_p50_ms": r["raymapd"]["latency_p50_ms"], "latency_p99_ms": r["raymapd"]["latency_p99_ms"],
  "scans_integrated": r["raymapd"]["scans_integrated"], "clouds_received": r["raymapd"]["clouds_received"],
  "raymapd_cpu_cores": round(cpu, 3)}))
PY
    done
  done
done
