# SPDX-License-Identifier: BSD-3-Clause
# Section "sanitizer" of the device kit (sourced by run.sh): compute-sanitizer's memcheck (out of
# bounds and misaligned device accesses, bad API calls) and racecheck (shared-memory hazards) over
# a short integration of every map mode, over both height-map modes and over a map streamed
# through a pool smaller than itself (the tiers of docs/large-maps.md: regions leave the device's
# cache for the compressed tier and the spill file and come back), on 2 scans of the yard
# (65,536 rays). The runs go side by side; run.sh's tests section starts them before its tests
# so that the two overlap.

sanitizer_pids=()
sanitizer_jobs=()

# find_sanitizer: compute-sanitizer's path, from PATH or the CUDA toolkit's usual places.
find_sanitizer() {
  local c
  for c in "$(command -v compute-sanitizer 2>/dev/null)" /usr/local/cuda/bin/compute-sanitizer \
    /usr/local/cuda/compute-sanitizer/compute-sanitizer /opt/nvidia/compute-sanitizer/compute-sanitizer \
    /usr/local/cuda-*/bin/compute-sanitizer; do
    [ -n "$c" ] && [ -x "$c" ] && { echo "$c"; return 0; }
  done
  return 1
}

# sanitizer_start: starts every sanitizer run in the background; false when none can run.
sanitizer_start() {
  : >"$work/sanitizer-started"
  md sanitizer "## compute-sanitizer" ""
  if [ "$have_cuda" != 1 ]; then
    md sanitizer "Skipped: no CUDA device."
    note "compute-sanitizer: skipped (no CUDA device)"
    return 1
  fi
  local cs
  if ! cs=$(find_sanitizer); then
    md sanitizer "Skipped: compute-sanitizer is not installed on this machine (looked on PATH and under /usr/local/cuda)."
    note "compute-sanitizer: not installed here; skipped"
    return 1
  fi
  # A first run on the device listing shows whether the tool accepts this device at all.
  timeout 60 "$cs" --tool memcheck --error-exitcode 99 "$bin/raymap" devices >"$work/logs/sanitizer-probe.log" 2>&1
  local rc=$?
  if [ "$rc" != 0 ] || ! grep -q "ERROR SUMMARY: 0 errors" "$work/logs/sanitizer-probe.log"; then
    md sanitizer "Skipped: compute-sanitizer refuses this device (exit $rc): $(grep -m2 -v '^ *$' "$work/logs/sanitizer-probe.log" | tr '\n' ' ')"
    note "compute-sanitizer refuses this device (exit $rc); skipped"
    return 1
  fi
  md sanitizer "$("$cs" --version 2>/dev/null | grep -m1 -i version)" ""
  "$bin/raymap" simulate "$kit/config/scenes/yard.yaml" --rays "$work/small.ply" --scans 2 -q \
    >"$work/logs/sanitizer-simulate.log" 2>&1 &&
    "$bin/raymap" populate "$work/small.ply" --max-range 20 --output "$work/small.rmap" -q \
      >>"$work/logs/sanitizer-simulate.log" 2>&1 || {
    fail "sanitizer: could not make the small input: $(tail -2 "$work/logs/sanitizer-simulate.log" | tr '\n' ' ')"
    return 1
  }
  local tool job args
  for tool in memcheck racecheck; do
    for job in occupancy:ray occupancy:scan ndt-om:ray ndt-tm:ray decay:ray tsdf:ray \
      occupancy+decay:ray heightmap:planar heightmap:fill tiers:ray; do
      local what=${job%%:*} how=${job#*:}
      if [ "$what" = heightmap ]; then
        args=(heightmap "$work/small.rmap" --backend cuda --mode "$how" --virtual-surfaces -q)
      elif [ "$what" = tiers ]; then
        # A pool of 170 regions for a map of 289, batches of 1,024 rays (CUDA keeps two
        # batches' regions pinned: 64 regions were too few on the H200) and a 64 KiB compressed
        # tier: regions leave the device about 600 times and 118 go to the spill file.
        mkdir -p "$work/tiers-$tool"
        args=(populate "$work/small.ply" --backend cuda --max-range 20 --max-memory 64MiB --batch-rays 1024
          --compressed-memory 64KiB --spill-dir "$work/tiers-$tool"
          --output "$work/tiers-$tool/small.rmap" -q)
      else
        args=(bench "$work/small.ply" --backend cuda --mode "$what" --semantics-list "$how"
          --repeat 1 --resolution 0.1 --max-range 20 --json "$work/logs/sanitizer-$tool-$what-$how.json")
      fi
      timeout 240 "$cs" --tool "$tool" --error-exitcode 99 --print-limit 10 "$bin/raymap" "${args[@]}" \
        >"$work/logs/sanitizer-$tool-$what-$how.log" 2>&1 &
      sanitizer_pids+=($!)
      sanitizer_jobs+=("$tool $what $how")
    done
  done
  return 0
}

# sanitizer_finish: waits for the runs and records one row each.
sanitizer_finish() {
  [ ${#sanitizer_pids[@]} -gt 0 ] || return 0
  md sanitizer "| tool | run | semantics or mode | result | summary |" "| --- | --- | --- | --- | --- |"
  local i rc tool what how logf summary result
  for i in "${!sanitizer_pids[@]}"; do
    wait "${sanitizer_pids[$i]}"
    rc=$?
    read -r tool what how <<<"${sanitizer_jobs[$i]}"
    logf=$work/logs/sanitizer-$tool-$what-$how.log
    summary=$(grep -E -m1 "ERROR SUMMARY|RACECHECK SUMMARY" "$logf" | sed 's/^=* *//')
    if [ "$rc" = 0 ] && grep -Eq "ERROR SUMMARY: 0 errors|RACECHECK SUMMARY: 0 hazards displayed \(0 errors" "$logf"; then
      result=clean
    elif [ "$rc" = 124 ]; then
      result="timed out"
      fail "compute-sanitizer $tool on $what ($how) ran out of time (240 s)"
    else
      result="errors (exit $rc)"
      fail "compute-sanitizer $tool on $what ($how): exit $rc: $(grep -E -m4 '^========= (Invalid|Error|Program hit|Race|Warning|ERROR)|error' "$logf" | tr '\n' ' ')"
    fi
    md sanitizer "| $tool | $what | $how | $result | ${summary:-none} |"
    record sanitizer "{\"tool\": \"$tool\", \"run\": \"$what\", \"variant\": \"$how\", \"exit\": $rc, \"result\": $(json_string "$result"), \"summary\": $(json_string "$summary")}"
  done
  sanitizer_pids=()
}

section_sanitizer() {
  # With the tests section, the runs already went alongside the tests.
  [ -f "$work/sanitizer-started" ] && return 0
  sanitizer_start && sanitizer_finish
}
