# SPDX-License-Identifier: BSD-3-Clause
# Section "pipeline" of the device kit (sourced by run.sh): the device plans its own batches
# (--device-planning device, issue 51) against the host planner, on CUDA. On the synthetic scene
# (0.1 m voxels, 20 m, OctoMap's probabilities, steady state): occupancy per ray and per scan
# planned on the host and on the device (median of 3 each), the other map modes planned on the
# device, then the same occupancy runs with the process confined to 2 host cores (taskset -c 0,1:
# the nearest this machine gets to a Jetson Orin's host). Each row gives rays/s, what each ray
# cost the host's processors (process CPU seconds over rays), the batches the host planned
# instead and the region moves that waited. Then the depth camera (640 x 480, every pixel) on the
# device planner, and raymapd at 10 times an OS-1-128 (13.1 M points/s) for 30 s with device
# planning, while the budget lasts. The targets of issue 51 are quoted beside the table.

pipeline_plan=(
  "occupancy ray host all" "occupancy ray device all"
  "occupancy scan host all" "occupancy scan device all"
  "ndt-om ray device all" "ndt-tm ray device all" "decay ray device all" "tsdf ray device all"
  "occupancy ray device 2" "occupancy scan device 2" "occupancy ray host 2" "occupancy scan host 2"
)

# pipeline_reserve: seconds the sections after this one need.
pipeline_reserve() {
  local r=10
  wanted bench && r=$((r + 90))
  wanted scaling && r=$((r + 120))
  wanted heightmap && r=$((r + 25))
  wanted raymapd && r=$((r + 100))
  echo "$r"
}

section_pipeline() {
  if [ "$have_cuda" != 1 ]; then
    note "pipeline: no CUDA device: device planning is proven on PoCL in CI (opencl.device_planning)"
    return 0
  fi
  wait_synthetic || return 0
  : >"$work/pipeline.rows"
  local name=synthetic-yard-$scans reserve entry mode semantics planning cores
  reserve=$(pipeline_reserve)
  for entry in "${pipeline_plan[@]}"; do
    read -r mode semantics planning cores <<<"$entry"
    if [ "$(remaining)" -lt $((reserve + 15)) ]; then
      note "pipeline: $mode ($semantics) planned on the $planning, $cores cores, skipped: out of time"
      continue
    fi
    pipeline_run "$name" "$mode" "$semantics" "$planning" "$cores"
    pipeline_render
    publish_results
  done
  if [ "$(remaining)" -ge $((reserve + 30)) ]; then
    pipeline_depth
  else
    note "pipeline: the depth camera run was skipped: out of time"
  fi
  if wanted raymapd && [ "$(remaining)" -ge $((reserve + 45)) ]; then
    # 10 x an OS-1-128: 128 x 2048 points at 50 Hz = 13.1 M points/s, for 30 s.
    local kept
    kept=$(daemon_run cuda 10 128 2048 50 30 device)
    md pipeline "" "raymapd planned on the device at 10 × an OS-1-128 for 30 s (section raymapd's table, row cuda 10): kept up: $kept."
  else
    note "pipeline: raymapd at 10x with device planning was skipped: out of time or section raymapd not run"
  fi
}

# pipeline_run NAME MODE SEMANTICS PLANNING CORES: one `raymap bench`, one row.
pipeline_run() {
  local name=$1 mode=$2 semantics=$3 planning=$4 cores=$5
  local tag=pipeline-$mode-$semantics-$planning-$cores
  local json=$work/logs/$tag.json
  local repeat=1
  [ "$mode" = occupancy ] && repeat=3
  local pin=()
  if [ "$cores" = 2 ]; then
    if command -v taskset >/dev/null; then
      pin=(taskset -c 0,1)
    else
      note "pipeline: taskset is not installed: the 2-core rows run on every core"
    fi
  fi
  local limit=$(($(remaining) - 10))
  [ "$limit" -gt 90 ] && limit=90
  [ "$limit" -lt 20 ] && limit=20
  local t0=$SECONDS
  timeout "$limit" "${pin[@]}" "$bin/raymap" bench "$synthetic" "${bench_common[@]}" \
    --backend cuda --device-planning "$planning" --mode "$mode" --semantics-list "$semantics" \
    --repeat "$repeat" --json "$json" >"$work/logs/$tag.log" 2>&1
  local rc=$?
  if [ "$rc" = 124 ]; then
    fail "pipeline: raymap bench $mode $semantics (planned on the $planning, $cores cores): still running after $limit s; stopped"
    return
  fi
  if [ "$rc" != 0 ]; then
    fail "pipeline: raymap bench $mode $semantics (planned on the $planning, $cores cores): exit $rc: $(grep -m2 -i 'error\|bench:' "$work/logs/$tag.log" | tr '\n' ' ')"
    return
  fi
  local rate cpu_ns thread_cpu integ rays on_host stalls waits plan dropped
  rate=$(value rays_per_second "$json")
  cpu_ns=$(value host_cpu_ns_per_ray "$json")
  thread_cpu=$(value integrate_thread_cpu_seconds "$json")
  integ=$(value integrate_seconds "$json")
  rays=$(value rays_integrated "$json")
  on_host=$(value plans_on_host "$json")
  stalls=$(value transfer_stalls "$json")
  waits=$(value wait_seconds "$json")
  plan=$(value plan_seconds "$json")
  dropped=$(value updates_dropped "$json")
  printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$name" "$mode" "$semantics" \
    "$planning" "$cores" "$rate" "$cpu_ns" "$thread_cpu" "$integ" "$rays" "$on_host" "$stalls" \
    "$waits" "$plan" >>"$work/pipeline.rows"
  record pipeline "{\"input\": \"$name\", \"mode\": \"$mode\", \"semantics\": \"$semantics\", \"planning\": \"$planning\", \"host_cores\": \"$cores\", \"rays_per_second\": $(json_number "$rate"), \"host_cpu_ns_per_ray\": $(json_number "$cpu_ns"), \"integrate_thread_cpu_seconds\": $(json_number "$thread_cpu"), \"integrate_seconds\": $(json_number "$integ"), \"rays_integrated\": $(json_number "$rays"), \"plans_on_host\": $(json_number "$on_host"), \"transfer_stalls\": $(json_number "$stalls"), \"wait_seconds\": $(json_number "$waits"), \"plan_seconds\": $(json_number "$plan"), \"updates_dropped\": $(json_number "$dropped"), \"wall_seconds\": $((SECONDS - t0))}"
  if [ -n "$dropped" ] && [ "$dropped" != 0 ]; then
    note "pipeline: $dropped updates dropped in $mode ($semantics, planned on the $planning)"
  fi
}

# pipeline_render: the section's table from the rows so far: each row against the host-planned
# row of the same mode, semantics and cores, and a 2-core row against its all-core row.
pipeline_render() {
  : >"$work/md/pipeline.md"
  md pipeline "## Planning on the device (issue 51)" "" \
    "CUDA, $scans scans of the yard (0.1 m, 20 m, OctoMap's probabilities, steady state); occupancy median of 3, other modes 1 run. Host CPU: process CPU seconds over rays; thread: the integrating thread's CPU seconds." "" \
    "Targets: occupancy ≥ 100 M rays/s (both semantics), other modes ≥ 60 M rays/s, host CPU per ray ≤ 1/20 of host planning's, 2 host cores ≥ 80 % of all cores." "" \
    "| mode | semantics | planning | host cores | rays/s | × host planning | × all cores | host CPU ns/ray | thread CPU s | batches planned on the host | region moves that waited | wait s | plan s |" \
    "| --- | --- | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"
  awk -F'\t' '
    { row[NR] = $0; key = $2 "|" $3; if ($4 == "host") host[key "|" $5] = $6; if ($5 == "all") all[key "|" $4] = $6 }
    END {
      for (i = 1; i <= NR; i++) {
        split(row[i], f, "\t")
        key = f[2] "|" f[3]
        xh = (f[4] != "host" && (key "|" f[5]) in host && host[key "|" f[5]] > 0) ? sprintf("%.2f", f[6] / host[key "|" f[5]]) : ""
        xa = (f[5] != "all" && (key "|" f[4]) in all && all[key "|" f[4]] > 0) ? sprintf("%.2f", f[6] / all[key "|" f[4]]) : ""
        printf "| %s | %s | %s | %s | %.0f | %s | %s | %.1f | %.3f | %s | %s | %s | %s |\n", f[2], f[3], f[4], f[5], f[6], xh, xa, f[7], f[8], f[11], f[12], f[13], f[14]
      }
    }' "$work/pipeline.rows" >>"$work/md/pipeline.md"
}

# pipeline_depth: raymap-depth-bench on CUDA, planned on the device (target: 640 x 480 at
# downsample 1, at least 300 frames/s).
pipeline_depth() {
  local json=$work/logs/pipeline-depth.json
  if ! timeout 60 "$bin/raymap-depth-bench" 5 --backend cuda --device-planning device \
    >"$json" 2>"$work/logs/pipeline-depth.log"; then
    fail "pipeline: raymap-depth-bench on CUDA failed: $(tail -2 "$work/logs/pipeline-depth.log" | tr '\n' ' ')"
    return
  fi
  local fps
  # The integration run at downsample 1 per ray: the JSON without white space, one object per
  # line (whatever the layout the bench prints), its frames_per_s to 0.1.
  fps=$(tr -d ' \n' <"$json" | tr '}' '\n' | grep -m1 '"downsample":1,"semantics":"ray",' |
    sed -n 's/.*"frames_per_s":\([0-9.e+-]*\).*/\1/p' | awk '{ printf "%.1f", $1 }')
  md pipeline "" "Depth camera 640 × 480, every pixel, per ray, CUDA planned on the device: ${fps:-?} frames/s (target ≥ 300; raymap-depth-bench, $json)."
  record pipeline "{\"depth_camera_frames_per_s\": $(json_number "$fps"), \"bench\": $(tr -d '\n' <"$json")}"
}
