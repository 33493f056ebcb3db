# SPDX-License-Identifier: BSD-3-Clause
# Section "raymapd" of the device kit (sourced by run.sh): raymapd as a robot runs it, driven by
# raymap-load (a simulated 128-beam lidar in the yard publishing PointCloud2 and odometry over
# loopback DDS, and a GridMap and diagnostics subscriber). On CUDA: 30 s at an Ouster OS-1-128's
# rate (128 x 1024 points at 10 Hz, 1.31 M points/s), then 8 s steps at 2, 4, 8, 16 and 32 times
# that rate (128 x 2048 points at 10 to 160 Hz) up to the first it does not keep up with, then
# the highest it kept up with for 30 s again. Keeping up: no cloud dropped, every published scan
# integrated, no late height-map cycle. Without CUDA: the CPU backend at 1x for 10 s, recorded.

section_raymapd() {
  md raymapd "## raymapd under load (loopback DDS)" "" \
    "| backend | × OS-1-128 | points/scan | scans/s | points/s | seconds | keeps up | scans published | integrated | dropped | late cycles | map period mean ms | period error p99 ms | latency p50 / p99 / max ms | cycle lock hold p99 ms | map bytes synced / copied per cycle p99 |" \
    "| --- | ---: | ---: | ---: | ---: | ---: | --- | ---: | ---: | ---: | ---: | ---: | ---: | --- | ---: | --- |"
  if [ "$have_cuda" != 1 ]; then
    daemon_run cpu 1 128 1024 10 10 >/dev/null
    return 0
  fi
  daemon_run cuda 1 128 1024 10 30 >/dev/null
  local step best="" best_spec="" multiple columns rate
  for step in "2 2048 10" "4 2048 20" "8 2048 40" "16 2048 80" "32 2048 160"; do
    read -r multiple columns rate <<<"$step"
    if [ "$(remaining)" -lt 30 ]; then
      note "raymapd: the rate steps from ${multiple}x on were skipped: out of time"
      break
    fi
    if [ "$(daemon_run cuda "$multiple" 128 "$columns" "$rate" 8)" = yes ]; then
      best=$multiple
      best_spec="$columns $rate"
    else
      break
    fi
  done
  if [ -n "$best" ]; then
    read -r columns rate <<<"$best_spec"
    if [ "$(remaining)" -ge 45 ]; then
      daemon_run cuda "$best" 128 "$columns" "$rate" 30 >/dev/null
    else
      note "raymapd: no time left to hold ${best}x for 30 s (its 8 s step kept up)"
    fi
  fi
  md raymapd "" "Highest rate kept up with: ${best:-1 or less}× an OS-1-128 (steps of 8 s, then 30 s)."
  record raymapd "{\"highest_multiple_kept_up\": $(json_number "$best")}"
}

# daemon_run BACKEND MULTIPLE BEAMS COLUMNS RATE SECONDS [PLANNING]: one run (PLANNING: where
# device batches are planned, host by default); prints yes when it kept up.
daemon_run() {
  local backend=$1 multiple=$2 beams=$3 columns=$4 rate=$5 seconds=$6 planning=${7:-host}
  # A private DDS domain per run (runs are called in subshells: the count lives in a file).
  local domain
  domain=$(($(cat "$work/daemon-domain" 2>/dev/null || echo 70) + 1))
  echo "$domain" >"$work/daemon-domain"
  local tag=raymapd-$backend-${multiple}x-${seconds}s-$planning
  local config=$work/$tag.yaml lead=0.015
  [ "$backend" = cpu ] || lead=0.05
  sed -e "s/^  name: cpu/  name: $backend\n  device_planning: $planning/" \
    -e "s/^  domain: 0 /  domain: $domain /" \
    -e "s/^  voxels_topic: .*/  voxels_topic: \"\"/" \
    -e "s/^  publish_lead_s: [0-9.]*/  publish_lead_s: $lead/" "$kit/config/cpu.yaml" >"$config"
  "$bin/raymapd" --config "$config" >"$work/logs/$tag.log" 2>&1 &
  local pid=$!
  sleep 2
  if ! kill -0 "$pid" 2>/dev/null; then
    fail "raymapd ($backend) did not start: $(tail -3 "$work/logs/$tag.log" | tr '\n' ' ')"
    wait "$pid" 2>/dev/null
    echo no
    return
  fi
  # raymap-load reads its scene from config/scenes, relative to where it runs.
  (cd "$kit" && timeout $((seconds + 30)) "$bin/raymap-load" --domain "$domain" \
    --beams "$beams" --columns "$columns" --scan-rate "$rate" --duration "$seconds" --warmup 2) \
    >"$work/logs/$tag.json" 2>>"$work/logs/$tag.log"
  local load_rc=$?
  stop_daemon "$pid"
  local daemon_rc=$stopped_rc
  local f=$work/logs/$tag.json
  if [ "$load_rc" != 0 ] || [ ! -s "$f" ]; then
    fail "raymap-load against raymapd ($backend, ${multiple}x) failed (exit $load_rc): $(tail -2 "$work/logs/$tag.log" | tr '\n' ' ')"
    echo no
    return
  fi
  [ "$daemon_rc" = 0 ] || fail "raymapd ($backend, ${multiple}x) exited $daemon_rc after SIGTERM"
  # raymap-load's JSON: the first number after each key.
  local -A r
  local key
  for key in scans_published_total scans_integrated clouds_dropped_overflow scans_dropped_no_pose \
    cycles_late maps_received map_period_mean_ms p99 latency_p50_ms latency_p99_ms latency_max_ms \
    points_per_s heightmap_lock_hold_p99_ms sync_copy_bytes_p99 heightmap_copy_bytes_p99; do
    r[$key]=$(value "$key" "$f")
  done
  local published=${r[scans_published_total]} integrated=${r[scans_integrated]}
  local overflow=${r[clouds_dropped_overflow]} nopose=${r[scans_dropped_no_pose]}
  local late=${r[cycles_late]} maps=${r[maps_received]}
  local keeps=no
  if awk -v p="$published" -v i="$integrated" -v o="$overflow" -v n="$nopose" -v l="$late" \
    -v m="$maps" -v s="$seconds" \
    'BEGIN { exit !(p > 0 && i >= 0.99 * p && o == 0 && n == 0 && l == 0 && m >= 0.9 * 5 * s) }'; then
    keeps=yes
  fi
  if [ "$backend" = cpu ] && awk -v m="$maps" 'BEGIN { exit !(m + 0 < 1) }'; then
    fail "raymapd (cpu) published no height map in $seconds s"
  fi
  local label=$backend
  [ "$planning" = device ] && label="$backend, planned on the device"
  md raymapd "| $label | $multiple | $((beams * columns)) | $rate | ${r[points_per_s]} | $seconds | $keeps | $published | $integrated | $(awk -v o="$overflow" -v n="$nopose" 'BEGIN { print o + n }') | $late | ${r[map_period_mean_ms]} | ${r[p99]} | ${r[latency_p50_ms]} / ${r[latency_p99_ms]} / ${r[latency_max_ms]} | ${r[heightmap_lock_hold_p99_ms]} | ${r[sync_copy_bytes_p99]} / ${r[heightmap_copy_bytes_p99]} |"
  record raymapd "{\"backend\": \"$backend\", \"planning\": \"$planning\", \"multiple\": $multiple, \"beams\": $beams, \"columns\": $columns, \"scan_rate_hz\": $rate, \"seconds\": $seconds, \"keeps_up\": $([ $keeps = yes ] && echo true || echo false), \"daemon_exit\": $daemon_rc, \"load\": $(tr -d '\n' <"$f")}"
  echo "$keeps"
}

# stop_daemon PID: SIGTERM, then up to 15 s for raymapd to shut down cleanly, then SIGKILL; its
# exit status goes to stopped_rc (137 when it had to be killed). Not in a subshell: only the
# shell that started raymapd can wait for it.
stop_daemon() {
  local pid=$1 i
  kill -TERM "$pid" 2>/dev/null
  for ((i = 0; i < 150; i++)); do
    kill -0 "$pid" 2>/dev/null || break
    sleep 0.1
  done
  kill -KILL "$pid" 2>/dev/null
  wait "$pid" 2>/dev/null
  stopped_rc=$?
}
