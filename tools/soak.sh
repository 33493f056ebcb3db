#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Soak test: raymapd (config/cpu.yaml) fed by `raymap replay --loop` of a simulated Ouster-like
# drive through the yard scene for MINUTES, on loopback DDS. tools/soak_monitor.py samples
# raymapd's RSS, the GridMap period seen by a subscriber (`raymap echo`), its latency and its drop
# counters every second and writes soak.csv, soak.png and summary.json.
#
#   tools/soak.sh MINUTES [BUILD_DIR (default build/release)]
#
# Environment: SOAK_OUT (output folder, default soak-results/<UTC time>), SOAK_BEAMS (lidar beams,
# default 128: an OS-1-128 at 1024 columns and 10 Hz, 1.31 M points/s), SOAK_CONFIG (raymapd
# configuration, default config/cpu.yaml), SOAK_DOMAIN (DDS domain, default 43), SOAK_COLOAD=1
# (a second process keeps one core busy for the whole soak, as other software on a robot does),
# SOAK_INTRUDER=1 (from the first minute, a second robot joins for 20 s every 2 minutes:
# raymap-load publishing its own clouds and odometry on the same topics; the monitor checks that
# every report in between says so: two pose sources, ERROR, and nothing of it once it left).
# Needs python3 with matplotlib for the plot (apt-get install python3-matplotlib); without it the
# CSV and the summary are still written.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ $# -lt 1 ]; then
  echo "usage: tools/soak.sh MINUTES [BUILD_DIR]" >&2
  exit 2
fi
minutes=$1
build=${2:-build/release}
out=${SOAK_OUT:-$PWD/soak-results/$(date -u +%Y%m%dT%H%M%SZ)}
beams=${SOAK_BEAMS:-128}
config=${SOAK_CONFIG:-config/cpu.yaml}
domain=${SOAK_DOMAIN:-43}
export CYCLONEDDS_URI="file://$PWD/config/cyclonedds-loopback.xml"
for program in "$build/src/service/raymapd" "$build/tools/raymap"; do
  [ -x "$program" ] || { echo "soak: $program is missing: build first (cmake --build $build)" >&2; exit 2; }
done
mkdir -p "$out"
work=$(mktemp -d)
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill -TERM "$p" 2>/dev/null || true; done
  pkill -TERM -f "raymap-load --domain $domain " 2>/dev/null || true
  wait 2>/dev/null || true
  rm -rf "$work"
}
trap cleanup EXIT
if [ "${SOAK_COLOAD:-0}" = 1 ]; then
  (while :; do :; done) &
  pids+=($!)
fi

# The recording: the yard drive with a 128 x 1024 lidar (2.5 s, 25 scans), replayed in a loop.
sed -e "s/^  beams: .*/  beams: $beams/" config/scenes/yard.yaml > "$work/scene.yaml"
"$build/tools/raymap" simulate "$work/scene.yaml" --rays "$work/drive.ply" -q
sed -e "s/^  domain: 0 /  domain: $domain /" "$config" > "$work/raymapd.yaml"

"$build/src/service/raymapd" --config "$work/raymapd.yaml" 2> "$out/raymapd.log" &
raymapd=$!
pids+=("$raymapd")
"$build/tools/raymap" echo /height_map --domain "$domain" --wait 30 --json > "$out/maps.jsonl" 2> "$out/echo-maps.log" &
pids+=($!)
"$build/tools/raymap" echo /diagnostics --domain "$domain" --wait 30 --json > "$out/diagnostics.jsonl" 2> "$out/echo-diagnostics.log" &
pids+=($!)
"$build/tools/raymap" replay "$work/drive.ply" --loop --domain "$domain" 2> "$out/replay.log" &
pids+=($!)

intruder=()
if [ "${SOAK_INTRUDER:-0}" = 1 ]; then
  : > "$out/intruder.log"
  (
    sleep 60
    while :; do
      echo "join $(date +%s.%N)" >> "$out/intruder.log"
      "$build/tools/raymap-load" --domain "$domain" --beams 16 --columns 512 --warmup 0 \
        --duration 20 > /dev/null 2>> "$out/intruder-errors.log" || true
      echo "leave $(date +%s.%N)" >> "$out/intruder.log"
      sleep 100
    done
  ) &
  pids+=($!)
  intruder=(--intruder-log "$out/intruder.log")
fi

echo "soak: $minutes min, ${beams}-beam lidar at 10 Hz into raymapd ($config); results in $out"
# Debian's python3 has python3-matplotlib; another python3 first on the PATH may not.
python=${SOAK_PYTHON:-python3}
if ! "$python" -c 'import matplotlib' 2>/dev/null && [ -x /usr/bin/python3 ]; then
  python=/usr/bin/python3
fi
"$python" tools/soak_monitor.py --pid "$raymapd" --maps "$out/maps.jsonl" \
  --diagnostics "$out/diagnostics.jsonl" --seconds "$(awk "BEGIN {print int($minutes * 60)}")" \
  "${intruder[@]}" \
  --out "$out" --label "${beams}x1024 lidar at 10 Hz, $(basename "$config"), $(git rev-parse --short HEAD)"
