#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Shared by the benchmark scripts (sourced): reading numbers out of the JSON that `raymap bench`
# and `raymap-octomap` print, the machine line of a summary, and the list of shared data sets.

value() {  # value KEY FILE [occurrence]: the number after "KEY": in a JSON file
  # Not inside a memory_tiers object: its wait_seconds is the tiers', not the run's (and would
  # shift the occurrences of the runs' own). The tiers' keys: tvalue, run-large-map-benchmarks.sh.
  sed '/"memory_tiers": {/,/}/d' "$2" | grep -o "\"$1\": [0-9.e+-]*" | sed -n "${3:-1}p" |
    awk '{print $2}'
}

text() {  # text KEY FILE: the first string value of KEY
  grep -o "\"$1\": \"[^\"]*\"" "$2" | head -1 | cut -d'"' -f4
}

machine_line() {  # machine_line EXTRA: commit, CPU model and cores, for a summary's first line
  echo "commit $(git rev-parse --short HEAD), $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $(nproc) cores, $*"
}

run_data_sets() {  # run_data_sets FUNCTION DATA_DIR: FUNCTION NAME INPUT [options] per data set
  "$1" ouster "$2/ouster/ouster_os1_lb_n3_raycloud.ply.gz"
  "$1" 3dtk "$2/3dtk/3dtk_raycloud.ply.gz"
  "$1" 3dtk-points "$2/3dtk/3dtk_points.ply.gz" --trajectory "$2/3dtk/3dtk_trajectory.txt"
  "$1" octomap "$2/octomap/octomap_scan_raycloud.ply.gz"
}

daemon_under_load() {  # daemon_under_load BUILD CONFIG DOMAIN RATE SECONDS: raymap-load's JSON
  # raymapd on CONFIG, driven by raymap-load (an OS-1-128, 128 x 1024 points) at RATE scans/s for
  # SECONDS after a 3 s warm-up (SUBSCRIBER_PRIORITY: see below); prints raymap-load's JSON on
  # one line, with a "service" object added: what systemd sees of the service (tools/bench/notify_listener.py on its NOTIFY_SOCKET):
  # ready_ms (start to READY=1), watchdog_pings and watchdog_gap_max_ms / _p99_ms (READY=1 to
  # STOPPING=1), and stop_ms (SIGTERM to exit); and "thread_cpu_s": the CPU seconds (user +
  # system) each of raymapd's threads used over the whole run, by thread name (raymap-ingest,
  # raymap-integr, raymap-publish, Cyclone's recv threads, ...; "all" is the process). The tests
  # check only that these happen, with generous bounds; the figures are recorded here
  # (docs/testing.md).
  local build=$1 config=$2 domain=$3 rate=$4 seconds=$5 pid out
  local notify="${config%.yaml}.notify" listener started ready stop_from stopped
  python3 tools/bench/notify_listener.py "$notify" > "$notify.json" &
  listener=$!
  for _ in $(seq 100); do
    [ -S "$notify" ] && break
    sleep 0.05
  done
  started=$(date +%s%N)
  NOTIFY_SOCKET="$notify" "$build/src/service/raymapd" --config "$config" 2> "${config%.yaml}.log" &
  pid=$!
  sleep 2
  # SUBSCRIBER_PRIORITY > 0: a real-time subscriber, its thread and its DDS receive path
  # (config/cyclonedds-realtime-receive.xml) at real-time priority, as a planner's would run.
  local load_dds=$CYCLONEDDS_URI
  if [ "${SUBSCRIBER_PRIORITY:-0}" -gt 0 ]; then
    load_dds="$CYCLONEDDS_URI,file://$PWD/config/cyclonedds-realtime-receive.xml"
  fi
  out=$(CYCLONEDDS_URI="$load_dds" "$build/tools/raymap-load" --domain "$domain" --beams 128 --columns 1024 \
    --scan-rate "$rate" --duration "$seconds" --warmup 3 \
    --subscriber-priority "${SUBSCRIBER_PRIORITY:-0}")
  local cpu
  cpu=$(thread_cpu "$pid")
  stop_from=$(date +%s%N)
  kill -TERM "$pid"
  wait "$pid" || true
  stopped=$(date +%s%N)
  kill -TERM "$listener" 2>/dev/null || true  # it ends by itself at STOPPING=1
  wait "$listener" || true
  ready=$(value ready_unix_ns "$notify.json")
  # raymap-load's object, its closing brace replaced by the service's figures.
  echo "$out" | tr -d '\n' | sed 's/}[[:space:]]*$//'
  awk -v started="$started" -v ready="${ready:--1}" -v stop_from="$stop_from" \
    -v stopped="$stopped" -v pings="$(value watchdog_pings "$notify.json")" \
    -v gap_max="$(value watchdog_gap_max_ms "$notify.json")" \
    -v gap_p99="$(value watchdog_gap_p99_ms "$notify.json")" 'BEGIN {
      ready_ms = -1
      if (ready > 0) ready_ms = (ready - started) / 1e6
      printf ", \"service\": {\"ready_ms\": %.1f, \"watchdog_pings\": %d, ", ready_ms, pings
      printf "\"watchdog_gap_max_ms\": %.1f, \"watchdog_gap_p99_ms\": %.1f, ", gap_max, gap_p99
      printf "\"stop_ms\": %.1f}", (stopped - stop_from) / 1e6
    }'
  printf ', "thread_cpu_s": {%s}}\n' "$cpu"
}

thread_cpu() {  # thread_cpu PID: '"name": seconds, ...' per thread name of PID, and "all"
  local hz task
  hz=$(getconf CLK_TCK)
  for task in /proc/"$1"/task/*; do
    # comm is field 2 in parentheses; utime and stime are fields 14 and 15 after it.
    printf '%s %s\n' "$(cat "$task/comm" 2>/dev/null | tr -d ' ')" \
      "$(sed 's/^.*) //' "$task/stat" 2>/dev/null | awk '{print $12 + $13}')"
  done | awk -v hz="$hz" 'NF == 2 { t[$1] += $2; all += $2 }
    END { for (n in t) printf "\"%s\": %.2f, ", n, t[n] / hz; printf "\"all\": %.2f", all / hz }'
}
