# SPDX-License-Identifier: BSD-3-Clause
# Section "bench" of the device kit (sourced by run.sh): `raymap bench` (integration time only,
# the input preloaded, steady state: a first untimed pass creates the regions) on the synthetic
# scene and the Ouster data, every map mode in each semantics it has, on CUDA (occupancy: median
# of 3) and on the CPU backend with every core (1 run). The
# settings of docs/benchmarks.md: 0.1 m voxels, rays clipped at 20 m, OctoMap's probabilities.
# Runs go in priority order (CUDA first, then the CPU occupancy baseline, then the rest) and stop
# when the budget, less what the later sections need, runs out; a skipped run is noted.

bench_modes=("occupancy ray,scan" "ndt-om ray" "ndt-tm ray" "decay ray" "tsdf ray")
bench_common=(--resolution 0.1 --max-range 20 --hit 0.7 --miss 0.4 --steady-state)

# bench_reserve: seconds the sections after this one need.
bench_reserve() {
  local r=10
  wanted scaling && r=$((r + 120))
  wanted heightmap && r=$((r + 25))
  if wanted raymapd; then
    if [ "$have_cuda" = 1 ]; then r=$((r + 100)); else r=$((r + 30)); fi
  fi
  echo "$r"
}

section_bench() {
  wait_synthetic || return 0
  local inputs=("synthetic-yard-$scans $synthetic")
  local ouster=$kit/data/ouster/ouster_os1_lb_n3_raycloud.ply.gz
  if [ -f "$ouster" ]; then
    inputs+=("ouster $ouster")
  else
    note "bench: no Ouster data in the kit; synthetic scene only"
  fi
  : >"$work/bench.rows"
  local plan=() entry name file mode semantics
  # Priority: every CUDA run, the CPU occupancy baseline, OpenCL occupancy, the other CPU runs.
  if [ "$have_cuda" = 1 ]; then
    for entry in "${inputs[@]}"; do
      for mode in "${bench_modes[@]}"; do plan+=("cuda $entry $mode"); done
    done
  fi
  for entry in "${inputs[@]}"; do plan+=("cpu $entry ${bench_modes[0]}"); done
  if [ "$have_opencl" = 1 ]; then
    for entry in "${inputs[@]}"; do plan+=("opencl $entry occupancy ray"); done
  fi
  for entry in "${inputs[@]}"; do
    for mode in "${bench_modes[@]:1}"; do plan+=("cpu $entry $mode"); done
  done
  local reserve backend
  reserve=$(bench_reserve)
  for entry in "${plan[@]}"; do
    read -r backend name file mode semantics <<<"$entry"
    if [ "$(remaining)" -lt $((reserve + 10)) ]; then
      note "bench: $backend $mode ($semantics) on $name skipped: out of time"
      continue
    fi
    bench_run "$backend" "$name" "$file" "$mode" "$semantics"
    bench_render
    publish_results
  done
}

# bench_run BACKEND NAME FILE MODE SEMANTICS_LIST: one `raymap bench` and a row per semantics.
bench_run() {
  local backend=$1 name=$2 file=$3 mode=$4 semantics=$5
  local json=$work/logs/bench-$name-$mode-$backend.json
  # Median of 3 for the device's occupancy, the headline figure; 1 run otherwise, so that every
  # mode's CPU baseline fits the budget (on an H200 machine a 16.4 M-ray pass takes 3 to 5 s on
  # either backend).
  local extra=(--repeat 1)
  [ "$backend" != cpu ] && [ "$mode" = occupancy ] && extra=(--repeat 3)
  [ "$backend" = cpu ] && extra+=(--threads-list 0)
  local t0=$SECONDS
  # A run that hangs (a kernel that never ends) costs at most 90 s of the budget.
  local limit=$(($(remaining) - 10))
  [ "$limit" -gt 90 ] && limit=90
  [ "$limit" -lt 20 ] && limit=20
  timeout "$limit" "$bin/raymap" bench "$file" \
    "${bench_common[@]}" --backend "$backend" --mode "$mode" --semantics-list "$semantics" \
    "${extra[@]}" --json "$json" >"$work/logs/bench-$name-$mode-$backend.log" 2>&1
  local rc=$?
  if [ "$rc" = 124 ]; then
    fail "raymap bench --backend $backend --mode $mode on $name: still running after $limit s; stopped"
    return
  fi
  if [ "$rc" != 0 ]; then
    fail "raymap bench --backend $backend --mode $mode on $name: exit $rc: $(grep -m2 -i 'error\|bench:' "$work/logs/bench-$name-$mode-$backend.log" | tr '\n' ' ')"
    return
  fi
  local n=1 s
  for s in ${semantics//,/ }; do
    local rate dropped skipped waits integ rays device threads plan
    rate=$(value rays_per_second "$json" $n)
    dropped=$(value updates_dropped "$json" $n)
    skipped=$(value rays_skipped "$json" $n)
    waits=$(value wait_seconds "$json" $n)
    integ=$(value integrate_seconds "$json" $n)
    rays=$(value rays_integrated "$json" $n)
    threads=$(value threads "$json" $n)
    plan=$(value plan_seconds "$json" $n)
    device=$(text device "$json")
    printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$name" "$mode" "$s" \
      "$backend" "$rate" "${dropped:-}" "${skipped:-}" "${waits:-}" "$integ" "$rays" \
      "${threads:-}" "${plan:-}" >>"$work/bench.rows"
    record bench "{\"input\": \"$name\", \"mode\": \"$mode\", \"semantics\": \"$s\", \"backend\": \"$backend\", \"threads\": $(json_number "$threads"), \"rays_integrated\": $(json_number "$rays"), \"integrate_seconds\": $(json_number "$integ"), \"rays_per_second\": $(json_number "$rate"), \"updates_dropped\": $(json_number "$dropped"), \"rays_skipped\": $(json_number "$skipped"), \"wait_seconds\": $(json_number "$waits"), \"plan_seconds\": $(json_number "$plan"), \"device\": $(json_string "$device"), \"wall_seconds\": $((SECONDS - t0))}"
    if [ "$backend" != cpu ] && [ -n "$dropped" ] && [ "$dropped" != 0 ]; then
      note "bench: $backend dropped $dropped updates in $mode ($s) on $name"
    fi
    n=$((n + 1))
  done
}

# bench_render: the section's table, from the rows so far (x CPU: against the CPU row of the same
# input, mode and semantics).
bench_render() {
  : >"$work/md/bench.md"
  md bench "## Integration throughput (raymap bench)" "" \
    "0.1 m voxels, 20 m range, OctoMap's probabilities, steady state; CUDA occupancy: median of 3, other runs: 1; CPU: every core ($(nproc))." "" \
    "Host planning: rays over the seconds the host spent planning batches (device backends); wait: seconds the host waited for the device." "" \
    "| input | mode | semantics | backend | rays/s | × CPU | rays | s | host planning rays/s | wait s | updates dropped | rays skipped |" \
    "| --- | --- | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"
  awk -F'\t' '
    { key = $1 "|" $2 "|" $3; row[NR] = $0; if ($4 == "cpu") cpu[key] = $5 }
    END {
      for (i = 1; i <= NR; i++) {
        split(row[i], f, "\t")
        key = f[1] "|" f[2] "|" f[3]
        x = (key in cpu && cpu[key] > 0) ? sprintf("%.2f", f[5] / cpu[key]) : ""
        b = f[4] == "cpu" ? "cpu (" f[11] " threads)" : f[4]
        plan = (f[4] != "cpu" && f[12] > 0) ? sprintf("%.0f", f[10] / f[12]) : ""
        printf "| %s | %s | %s | %s | %.0f | %s | %.0f | %.3f | %s | %s | %s | %s |\n", f[1], f[2], f[3], b, f[5], x, f[10], f[9], plan, f[8], f[6], f[7]
      }
    }' <(sort -s -t"$(printf '\t')" -k1,1 -k2,2 -k3,3 "$work/bench.rows") >>"$work/md/bench.md"
}
