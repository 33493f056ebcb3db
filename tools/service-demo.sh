#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# The service on built-in data: raymapd (config/cpu.yaml, Cyclone DDS pinned to loopback) is
# driven for a few seconds by raymap-load, a simulated 32-beam lidar driving through the yard
# scene that publishes PointCloud2 + nav_msgs/Odometry like a ROS 2 driver; raymap-load
# subscribes to the GridMaps and diagnostics and prints what it measured. Fails when no GridMap
# arrives.   tools/service-demo.sh [BUILD_DIR (default build/release)] [SECONDS (default 8)]
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build/release}
seconds=${2:-8}
export CYCLONEDDS_URI="file://$PWD/config/cyclonedds-loopback.xml"
domain=${RAYMAP_DEMO_DOMAIN:-42}
work=$(mktemp -d)
trap 'kill "$pid" 2>/dev/null || true; rm -rf "$work"' EXIT
sed -e "s/^  domain: 0 /  domain: $domain /" config/cpu.yaml > "$work/raymapd.yaml"
"$build/src/service/raymapd" --config "$work/raymapd.yaml" 2> "$work/raymapd.log" &
pid=$!
sleep 1
"$build/tools/raymap-load" --domain "$domain" --beams 32 --columns 1024 --moving \
  --warmup 2 --duration "$seconds" | tee "$work/load.json"
kill -TERM "$pid"
wait "$pid"
echo "raymapd's log:"
sed 's/^/  /' "$work/raymapd.log"
maps=$(sed -n 's/.*"maps_received": \([0-9]*\).*/\1/p' "$work/load.json")
if [ "${maps:-0}" -lt 1 ]; then
  echo "service demo: no GridMap received" >&2
  exit 1
fi
echo "service demo: $maps GridMaps received in ${seconds} s"
