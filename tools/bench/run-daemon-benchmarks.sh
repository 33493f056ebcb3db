#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# raymapd under load on this machine: starts raymapd (loopback DDS) and drives it with
# raymap-load (a simulated lidar publishing PointCloud2 + odometry, GridMap subscriber), once per
# backend and input rate. Prints one JSON object per run (raymap-load's output plus the backend
# and the rate) to stdout.
#   tools/bench/run-daemon-benchmarks.sh [BUILD_DIR] [BACKENDS] [RATES]
#   defaults: build/release "cpu opencl" "10 12 14 16"
# Each run: an Ouster OS-1-128 (128 x 1024 points per scan) at RATE scans/s for 20 s after a 3 s
# warm-up, the robot standing in the yard scene.
set -euo pipefail
cd "$(dirname "$0")/../.."
build=${1:-build/release}
backends=${2:-"cpu opencl"}
rates=${3:-"10 12 14 16"}
duration=${DURATION:-20}
export CYCLONEDDS_URI="file://$PWD/config/cyclonedds-loopback.xml"
source tools/bench/bench-lib.sh
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
domain=60
for backend in $backends; do
  for rate in $rates; do
    domain=$((domain + 1))
    # cpu.yaml with the backend, a private domain and no voxel output; the device generators
    # of PoCL take ~20 ms per map, so they get a longer publish lead.
    lead=0.015
    [ "$backend" = cpu ] || lead=0.05
    sed -e "s/^  name: cpu/  name: $backend/" -e "s/^  domain: 0 /  domain: $domain /" \
      -e "s/^  voxels_topic: .*/  voxels_topic: \"\"/" \
      -e "s/^  publish_lead_s: [0-9.]*/  publish_lead_s: $lead/" config/cpu.yaml > "$work/raymapd.yaml"
    printf '{"backend": "%s", "scan_rate_hz": %s, "result": %s}\n' "$backend" "$rate" \
      "$(daemon_under_load "$build" "$work/raymapd.yaml" "$domain" "$rate" "$duration")"
  done
done
