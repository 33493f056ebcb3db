# SPDX-License-Identifier: BSD-3-Clause
# Section "scaling" of the device kit (sourced by run.sh): the CPU backend's throughput against its
# thread count (issue 29: how far past 2 cores the parallel integrator goes), occupancy at the
# settings of docs/benchmarks.md, both semantics, 1, 2, 4, 8 and 16 threads (those the machine
# has), `raymap bench --steady-state`, median of 5, on the Ouster data (322,536 rays) and on 32
# scans of the yard (1 M rays, simulated here): about 100 s on a 16-core host. A GPU machine is where a 16-core host is lent;
# the GPU itself is idle in this section.

scaling_threads() {
  local n t list=""
  n=$(nproc)
  for t in 1 2 4 8 16; do
    [ "$t" -le "$n" ] && list+="${list:+,}$t"
  done
  echo "$list"
}

section_scaling() {
  local threads inputs=() entry name file
  # A curve of this machine's CPU is what a GPU machine's host is lent for; without a CUDA device
  # (a workstation, CI's bare chroot) it runs only when asked for by name (--only scaling).
  if [ "$have_cuda" != 1 ] && [[ ",$only," != *",scaling,"* ]]; then
    note "scaling: skipped without a CUDA device (run.sh --only scaling measures this host)"
    return 0
  fi
  threads=$(scaling_threads)
  md scaling "## CPU scaling (raymap bench --backend cpu)" "" \
    "Occupancy, 0.1 m voxels, 20 m range, OctoMap's probabilities, steady state, median of 5; $cpu_model, $(nproc) cores; × 1 thread: against the same input and semantics on one thread." "" \
    "| input | semantics | threads | rays/s | × 1 thread | efficiency |" \
    "| --- | --- | ---: | ---: | ---: | ---: |"
  local ouster=$kit/data/ouster/ouster_os1_lb_n3_raycloud.ply.gz
  [ -f "$ouster" ] && inputs+=("ouster $ouster")
  local yard=$work/scaling-yard.ply
  if "$bin/raymap" simulate "$kit/config/scenes/yard.yaml" --rays "$yard" --scans 32 -q \
    >"$work/logs/scaling-simulate.log" 2>&1; then
    inputs+=("synthetic-yard-32 $yard")
  else
    fail "scaling: raymap simulate (32 scans of the yard) failed: $(tail -2 "$work/logs/scaling-simulate.log" | tr '\n' ' ')"
  fi
  local reserve=10
  wanted heightmap && reserve=$((reserve + 25))
  wanted raymapd && reserve=$((reserve + 100))
  for entry in "${inputs[@]}"; do
    read -r name file <<<"$entry"
    if [ "$(remaining)" -lt $((reserve + 30)) ]; then
      note "scaling: $name skipped: out of time"
      continue
    fi
    local json=$work/logs/scaling-$name.json limit
    limit=$(($(remaining) - reserve))
    [ "$limit" -gt 200 ] && limit=200
    timeout "$limit" "$bin/raymap" bench "$file" "${bench_common[@]}" --backend cpu \
      --mode occupancy --semantics-list ray,scan --threads-list "$threads" --repeat 5 \
      --json "$json" >"$work/logs/scaling-$name.log" 2>&1
    local rc=$?
    if [ "$rc" != 0 ]; then
      fail "scaling: raymap bench on $name: exit $rc$([ "$rc" = 124 ] && echo " (stopped after $limit s)"): $(grep -m2 -i 'error' "$work/logs/scaling-$name.log" | tr '\n' ' ')"
      continue
    fi
    # The runs come in the order semantics × thread count.
    local n=1 s t one rate
    for s in ray scan; do
      one=""
      for t in ${threads//,/ }; do
        rate=$(value rays_per_second "$json" $n)
        [ "$t" = 1 ] && one=$rate
        local x eff
        x=$(ratio "$rate" "$one")
        eff=$(awk -v x="$x" -v t="$t" 'BEGIN { if (x != "") printf "%.0f %%", 100 * x / t }')
        md scaling "| $name | $s | $t | $(printf '%.0f' "${rate:-0}") | ${x:-} | $eff |"
        record scaling "{\"input\": \"$name\", \"semantics\": \"$s\", \"threads\": $t, \"rays_per_second\": $(json_number "$rate"), \"speedup\": $(json_number "$x")}"
        n=$((n + 1))
      done
    done
    publish_results
  done
  scaling_identical
}

# Every thread count must give the map file of one thread byte for byte (the parallel integrator
# gives each region to one worker and keeps ray order), in every map mode: checked here where 16
# cores are lent, beyond the 2 to 5 threads of the unit tests on a development machine.
scaling_identical() {
  local input mode semantics t list
  input=$kit/data/ouster/ouster_os1_lb_n3_raycloud.ply.gz
  [ -f "$input" ] || input=$work/scaling-yard.ply
  [ -f "$input" ] || return 0
  # Even and odd counts (an odd one splits the regions unevenly), and every core.
  list=$(printf '%s\n' 2 3 7 "$(nproc)" | awk '$1 > 1' | sort -nu | tr '\n' ' ')
  md scaling "" "### The same map on every thread count ($(basename "$input"): raymap populate, map files compared byte for byte)" "" \
    "| mode | semantics | threads compared with 1 | identical |" "| --- | --- | --- | --- |"
  for entry in occupancy:ray occupancy:scan ndt-om:ray ndt-tm+decay:ray decay:ray tsdf:ray; do
    mode=${entry%%:*}
    semantics=${entry##*:}
    if [ "$(remaining)" -lt 40 ]; then
      note "scaling: identical maps, $mode ($semantics) skipped: out of time"
      continue
    fi
    local base=$work/tmp/identical-$mode-$semantics same=yes differ=""
    for t in 1 $list; do
      if ! "$bin/raymap" populate "$input" -o "$base-$t.rmap" --resolution 0.1 --max-range 20 \
        --hit 0.7 --miss 0.4 --mode "$mode" --semantics "$semantics" --threads "$t" -q \
        >"$work/logs/identical-$mode-$semantics-$t.log" 2>&1; then
        fail "scaling: raymap populate $mode ($semantics) on $t threads failed: $(tail -2 "$work/logs/identical-$mode-$semantics-$t.log" | tr '\n' ' ')"
        same=""
        break
      fi
      if [ "$t" != 1 ] && ! cmp -s "$base-1.rmap" "$base-$t.rmap"; then
        same=no
        differ+="${differ:+, }$t"
      fi
      [ "$t" = 1 ] || rm -f "$base-$t.rmap"
    done
    rm -f "$base-1.rmap"
    [ -n "$same" ] || continue
    [ "$same" = no ] && fail "scaling: $mode ($semantics): the map on $differ threads differs from the map on 1 thread"
    md scaling "| $mode | $semantics | ${list% } | $same |"
    record scaling "{\"identical\": \"$mode\", \"semantics\": \"$semantics\", \"threads\": \"${list% }\", \"same\": $([ "$same" = yes ] && echo true || echo false)}"
    publish_results
  done
}
