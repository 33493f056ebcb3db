#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# raymapd's GridMaps at an independent Fast DDS 2.9 subscriber (issue 53): a measurement, not a
# test. raymapd runs config/cpu.yaml (5 Hz, 20 m: 640 KB GridMaps) on a private domain over
# loopback Cyclone DDS, raymap-load feeds it a simulated lidar (and takes the maps itself with
# Cyclone, 4 MB receive buffer), and after a warm-up raymap-fastdds-peer subscribes for SECONDS
# from the match with raymapd's GridMap writer, with each UDP buffer size of BUFFERS (0: the OS
# default, what rmw_fastrtps leaves). One JSON line per run: the maps the Fast DDS subscriber
# received of the SECONDS x 5 published and those it never got (gaps in the writer's sequence
# numbers), the datagrams the kernel dropped on its sockets, their period p50/p99/max at the subscriber, the longest
# time without a map in the window (the first counted from the match), when it matched and its
# first map's delay after the match, and raymap-load's period p99; then a summary per buffer
# size.
#   tools/bench/fastdds-maps.sh [BUILD_DIR] [BUFFERS]
#   defaults: build/release "0 4194304"
# Environment: REPAIRS (raymapd's dds.repair_burst_kb values to compare, each run with every buffer
# size; default "64", e.g. "0 64": Cyclone's own repairs against raymapd's), RUNS (rounds, each
# buffer size and repair value once per round, interleaved; default 3), MEASURE_SECONDS (the
# subscriber's SECONDS, default 10), LIDAR_BEAMS x LIDAR_COLUMNS at SCAN_RATE scans/s (raymap-load's
# lidar; default 32 x 1024 at 10).
set -euo pipefail
cd "$(dirname "$0")/../.."
build=${1:-build/release}
buffers=${2:-"0 4194304"}
runs=${RUNS:-3}
repairs=${REPAIRS:-64}
seconds=${MEASURE_SECONDS:-10}
beams=${LIDAR_BEAMS:-32}
columns=${LIDAR_COLUMNS:-1024}
scan_rate=${SCAN_RATE:-10}
peer="$build/tests/fastdds/raymap-fastdds-peer"
for program in "$build/src/service/raymapd" "$build/tools/raymap-load" "$peer"; do
  if [ ! -x "$program" ]; then
    echo "error: $program is not built (cmake --build $build --target raymapd raymap-load" \
      "raymap-fastdds-peer; the peer needs libfastrtps-dev and fastddsgen)" >&2
    exit 1
  fi
done
export CYCLONEDDS_URI="file://$PWD/config/cyclonedds-loopback.xml"
work=$(mktemp -d)
daemon=""
load=""
cleanup() {
  for pid in $load $daemon; do
    kill -TERM "$pid" 2>/dev/null || true
  done
  rm -rf "$work"
}
trap cleanup EXIT

# one_run RUN BUFFER REPAIR DOMAIN: one JSON line
one_run() {
  local run=$1 buffer=$2 repair=$3 domain=$4
  sed -e "s/^  domain: 0 /  domain: $domain /" -e 's/^  voxels_topic: .*/  voxels_topic: ""/' \
    -e "s/^  repair_burst_kb: .*/  repair_burst_kb: $repair/" config/cpu.yaml > "$work/raymapd.yaml"
  "$build/src/service/raymapd" --config "$work/raymapd.yaml" 2> "$work/raymapd.log" &
  daemon=$!
  sleep 2
  "$build/tools/raymap-load" --domain "$domain" --beams "$beams" --columns "$columns" \
    --scan-rate "$scan_rate" --warmup 0 --duration $((seconds + 10)) \
    > "$work/load.json" 2> "$work/load.log" &
  load=$!
  sleep 3  # raymapd publishes once scans go in: the subscriber starts into a steady stream
  # SECONDS from the match with raymapd's GridMap writer: discovery is not the buffer's doing.
  "$peer" --domain "$domain" --buffer-bytes "$buffer" subscribe --seconds "$seconds" --from-match \
    > "$work/peer.json" 2> "$work/peer.log"
  wait "$load" || true
  load=""
  kill -TERM "$daemon"
  wait "$daemon" || true
  daemon=""
  python3 - "$run" "$buffer" "$repair" "$seconds" "$work/peer.json" "$work/load.json" <<'PY'
import json, sys
run, buffer, repair, seconds, peer_path, load_path = sys.argv[1:7]
peer = json.load(open(peer_path))
try:
    load = json.load(open(load_path))
except ValueError:
    load = {}
print(json.dumps({
    "run": int(run), "buffer_bytes": int(buffer), "repair_burst_kb": int(repair),
    "seconds": float(seconds), "maps_published": int(float(seconds) * 5),
    "fastdds_maps": peer["maps"], "fastdds_maps_skipped": peer["maps_skipped"],
    "fastdds_datagrams_dropped": peer["socket_datagrams_dropped"],
    "fastdds_period_ms": {"p50": peer["map_period_p50_ms"], "p99": peer["map_period_p99_ms"],
                          "max": peer["map_period_max_ms"]},
    "fastdds_gap_max_ms": peer["map_gap_max_ms"],
    "fastdds_matched_after_ms": peer["grid_map_writer_matched_after_ms"],
    "fastdds_first_map_after_match_ms": peer["first_map_after_match_ms"],
    "raymapd_level": peer["pipeline_level"],
    "cyclone_period_p99_ms": load.get("map_period_ms", {}).get("p99"),
}))
PY
}

results="$work/results.jsonl"
domain=90
for run in $(seq "$runs"); do
  for buffer in $buffers; do
    for repair in $repairs; do
      domain=$((domain + 1))
      one_run "$run" "$buffer" "$repair" "$domain" | tee -a "$results"
    done
  done
done
python3 - "$results" <<'PY'
import json, sys
rows = [json.loads(line) for line in open(sys.argv[1])]
for buffer, repair in sorted({(r["buffer_bytes"], r["repair_burst_kb"]) for r in rows}):
    mine = [r for r in rows if r["buffer_bytes"] == buffer and r["repair_burst_kb"] == repair]
    maps = " ".join(str(r["fastdds_maps"]) for r in mine)
    p99 = " ".join("%.0f" % (r["fastdds_period_ms"]["p99"] or 0) for r in mine)
    gap = " ".join("%.0f" % r["fastdds_gap_max_ms"] for r in mine)
    cyclone = " ".join("%.1f" % (r["cyclone_period_p99_ms"] or 0) for r in mine)
    label = "OS default" if buffer == 0 else "%d bytes" % buffer
    print("buffer %s, repair_burst_kb %d: maps %s of %d each; period p99 %s ms; longest gap %s "
          "ms; raymap-load's Cyclone period p99 %s ms"
          % (label, repair, maps, mine[0]["maps_published"], p99, gap, cyclone))
PY
