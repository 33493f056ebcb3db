#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Soak test: raymapd (config/cpu.yaml) fed by `raymap replay --loop` of a simulated Ouster-like
# drive through the yard scene for MINUTES, on loopback DDS. tools/soak_monitor.py samples
# raymapd's RSS, the GridMap period seen by a subscriber (`raymap echo`), its latency and its drop
# counters every second and writes soak.csv, soak.png and summary.json; at the end it stops the
# inputs, lets raymapd drain, and checks (summary.json "checks", exit status 1 if one fails):
# every cloud published reached raymapd and every cloud received is integrated or counted as
# dropped for a reason; no heap allocation in raymapd's real-time loops after warm-up (with the
# counting build, build/tests/raymapd_counted, used when it exists); RSS flat after warm-up; every
# report true to what happened (a second robot, time going back).
#
#   tools/soak.sh MINUTES [BUILD_DIR (default build/release)]
#
# Environment: SOAK_OUT (output folder, default soak-results/<UTC time>), SOAK_BEAMS (lidar beams,
# default 128: an OS-1-128 at 1024 columns and 10 Hz, 1.31 M points/s), SOAK_CONFIG (raymapd
# configuration, default config/cpu.yaml), SOAK_DOMAIN (DDS domain, default 43), SOAK_COLOAD=1
# (a second process keeps one core busy for the whole soak, as other software on a robot does),
# SOAK_INTRUDER=1 (from the first minute, a second robot joins for 20 s every 2 minutes:
# raymap-load publishing its own clouds and odometry on the same topics; the monitor checks that
# every report in between says so: two pose sources, ERROR, and nothing of it once it left),
# SOAK_BAG=1 (the drive is first recorded into a rosbag2 MCAP bag with `raymap record`, and the
# bag is replayed in the loop: its recorded stamps come again every lap, so time goes back at
# each lap as with `ros2 bag play --loop`; the monitor checks each lap reset the pose history and
# was reported), SOAK_ALL=1 (all three: the issue-52 soak). SOAK_RAYMAPD names the raymapd to run.
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
if [ "${SOAK_ALL:-0}" = 1 ]; then
  SOAK_COLOAD=1 SOAK_INTRUDER=1 SOAK_BAG=1
fi
bag=${SOAK_BAG:-0}
# The counting build reports realtime_allocations; the plain one cannot (the check says so).
raymapd_program=${SOAK_RAYMAPD:-$build/tests/raymapd_counted}
[ -x "$raymapd_program" ] || raymapd_program=$build/src/service/raymapd
export CYCLONEDDS_URI="file://$PWD/config/cyclonedds-loopback.xml"
for program in "$raymapd_program" "$build/tools/raymap" "$build/tools/raymap-load"; do
  [ -x "$program" ] || { echo "soak: $program is missing: build first (cmake --build $build)" >&2; exit 2; }
done
mkdir -p "$out"
# A folder used before (SOAK_OUT given twice) holds an earlier run's files; its markers
# (sampled, inputs-stopped) and counts (replay.json, intruder-N.json) would stop this run's inputs
# at once and be counted as this run's: start from none of them.
rm -f "$out"/{sampled,inputs-stopped,replay.json,replay.log,summary.json,soak.csv,soak.png} \
  "$out"/{diagnostics.jsonl,maps.jsonl,raymapd.log,record.log,echo-maps.log,echo-diagnostics.log} \
  "$out"/intruder*
work=$(mktemp -d)
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill -TERM "$p" 2>/dev/null || true; done
  pkill -TERM -f "raymap-load --domain $domain " 2>/dev/null || true
  pkill -TERM -f "raymap record -o $work/" 2>/dev/null || true
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
recording=$work/drive.ply
bag_flag=()
if [ "$bag" = 1 ]; then
  # Recorded on a domain of its own, before raymapd starts, at the drive's own pace.
  "$build/tools/raymap" record -o "$work/drive-bag" --format mcap --domain $((domain + 1)) -q \
    2> "$out/record.log" &
  recorder=$!
  "$build/tools/raymap" replay "$work/drive.ply" --domain $((domain + 1)) --wait 30 -q
  sleep 1
  kill -INT "$recorder"
  wait "$recorder"
  recording=$work/drive-bag
  bag_flag=(--bag)
fi
sed -e "s/^  domain: 0 /  domain: $domain /" "$config" > "$work/raymapd.yaml"

"$raymapd_program" --config "$work/raymapd.yaml" 2> "$out/raymapd.log" &
raymapd=$!
pids+=("$raymapd")
"$build/tools/raymap" echo /height_map --domain "$domain" --wait 30 --json > "$out/maps.jsonl" 2> "$out/echo-maps.log" &
pids+=($!)
"$build/tools/raymap" echo /diagnostics --domain "$domain" --wait 30 --json > "$out/diagnostics.jsonl" 2> "$out/echo-diagnostics.log" &
pids+=($!)
"$build/tools/raymap" replay "$recording" --loop --domain "$domain" \
  --stats-json "$out/replay.json" 2> "$out/replay.log" &
replay=$!
pids+=("$replay")

intruder=()
intruder_loop=
if [ "${SOAK_INTRUDER:-0}" = 1 ]; then
  : > "$out/intruder.log"
  (
    # Stops between visits once the monitor is done sampling (a visit under way finishes and
    # prints how many clouds it published, for the final count).
    n=0
    sleep 60
    while [ ! -e "$out/sampled" ]; do
      n=$((n + 1))
      echo "join $(date +%s.%N)" >> "$out/intruder.log"
      "$build/tools/raymap-load" --domain "$domain" --beams 16 --columns 512 --warmup 0 \
        --duration 20 > "$out/intruder-$n.json" 2>> "$out/intruder-errors.log" || true
      echo "leave $(date +%s.%N)" >> "$out/intruder.log"
      for _ in $(seq 100); do
        [ -e "$out/sampled" ] && break
        sleep 1
      done
    done
  ) &
  intruder_loop=$!
  pids+=("$intruder_loop")
  intruder=(--intruder-log "$out/intruder.log")
fi

# Once the monitor has sampled MINUTES, the inputs stop (the replay writes replay.json, the
# second robot finishes its visit) and the monitor takes raymapd's last reports for the count.
(
  while [ ! -e "$out/sampled" ]; do
    kill -0 "$raymapd" 2>/dev/null || exit 0
    sleep 1
  done
  kill -INT "$replay" 2>/dev/null || true
  while kill -0 "$replay" 2>/dev/null; do sleep 0.2; done
  if [ -n "$intruder_loop" ]; then
    while kill -0 "$intruder_loop" 2>/dev/null; do sleep 0.2; done
  fi
  touch "$out/inputs-stopped"
) &
pids+=($!)

modes=
[ "${SOAK_COLOAD:-0}" = 1 ] && modes="$modes, one core busy"
[ "${SOAK_INTRUDER:-0}" = 1 ] && modes="$modes, a second robot every 2 min"
[ "$bag" = 1 ] && modes="$modes, a bag in a loop"
echo "soak: $minutes min, ${beams}-beam lidar at 10 Hz into $raymapd_program ($config$modes); results in $out"
# Debian's python3 has python3-matplotlib; another python3 first on the PATH may not.
python=${SOAK_PYTHON:-python3}
if ! "$python" -c 'import matplotlib' 2>/dev/null && [ -x /usr/bin/python3 ]; then
  python=/usr/bin/python3
fi
"$python" tools/soak_monitor.py --pid "$raymapd" --maps "$out/maps.jsonl" \
  --diagnostics "$out/diagnostics.jsonl" --seconds "$(awk "BEGIN {print int($minutes * 60)}")" \
  "${intruder[@]}" --replay-stats "$out/replay.json" --inputs-stopped "$out/inputs-stopped" \
  --sampled "$out/sampled" "${bag_flag[@]}" --out "$out" --label "${beams}x1024 lidar at 10 Hz, $(basename "$config")$modes, $(basename "$raymapd_program"), $(git rev-parse --short HEAD)"
