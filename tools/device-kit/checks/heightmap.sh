# SPDX-License-Identifier: BSD-3-Clause
# Section "heightmap" of the device kit (sourced by run.sh): `raymap heightmap` on maps of the
# yard scene and, when the kit has it, the Ouster data (20 m x 20 m, 0.1 m cells, virtual
# surfaces), planar and fill: the CUDA generator must give the CPU generator's cells exactly
# (every cell of the CSV export the same), and each generator's median time of 20 is recorded.

section_heightmap() {
  md heightmap "## Height maps (CUDA generator against the CPU one)" "" \
    "| map | mode | cells | CUDA cells equal to CPU | CPU median ms | CUDA median ms | × CPU |" \
    "| --- | --- | ---: | --- | ---: | ---: | ---: |"
  local maps=()
  if "$bin/raymap" simulate "$kit/config/scenes/yard.yaml" --rays "$work/yard.ply" -q \
    >"$work/logs/heightmap-maps.log" 2>&1 &&
    "$bin/raymap" populate "$work/yard.ply" --output "$work/yard.rmap" -q \
      >>"$work/logs/heightmap-maps.log" 2>&1; then
    maps+=("yard $work/yard.rmap 0,0,0")
  else
    fail "heightmap: could not map the yard scene: $(tail -2 "$work/logs/heightmap-maps.log" | tr '\n' ' ')"
  fi
  local ouster=$kit/data/ouster/ouster_os1_lb_n3_raycloud.ply.gz
  if [ -f "$ouster" ] && [ "$(remaining)" -gt 60 ]; then
    if "$bin/raymap" populate "$ouster" --max-range 20 --output "$work/ouster.rmap" -q \
      >>"$work/logs/heightmap-maps.log" 2>&1; then
      # The sensor started near the origin, about 1.9 m above the ground.
      maps+=("ouster $work/ouster.rmap 0,0,-1.9")
    else
      fail "heightmap: could not map the Ouster data: $(tail -2 "$work/logs/heightmap-maps.log" | tr '\n' ' ')"
    fi
  fi
  local entry name map centre mode
  for entry in "${maps[@]}"; do
    read -r name map centre <<<"$entry"
    for mode in planar fill; do
      heightmap_compare "$name" "$map" "$centre" "$mode"
    done
  done
}

# heightmap_compare NAME MAP CENTRE MODE: one row.
heightmap_compare() {
  local name=$1 map=$2 centre=$3 mode=$4 backend
  local args=("$map" --center "$centre" --size 20 --mode "$mode" --virtual-surfaces)
  local backends=(cpu)
  [ "$have_cuda" = 1 ] && backends+=(cuda)
  for backend in "${backends[@]}"; do
    local base=$work/logs/heightmap-$name-$mode-$backend
    if ! "$bin/raymap" heightmap "${args[@]}" --backend "$backend" --csv "$base.csv" -q \
      >"$base.log" 2>&1 ||
      ! "$bin/raymap" heightmap "${args[@]}" --backend "$backend" --repeat 20 --json \
        >"$base.json" 2>>"$base.log"; then
      fail "raymap heightmap --backend $backend --mode $mode on $name: $(tail -2 "$base.log" | tr '\n' ' ')"
      return
    fi
  done
  local cpu=$work/logs/heightmap-$name-$mode-cpu cuda=$work/logs/heightmap-$name-$mode-cuda
  local cells equal="skipped (no CUDA device)" cpu_ms cuda_ms="" differ=""
  cells=$(($(wc -l <"$cpu.csv") - 1))
  cpu_ms=$(awk -v s="$(value seconds_median "$cpu.json")" 'BEGIN { printf "%.3f", s * 1000 }')
  if [ "$have_cuda" = 1 ]; then
    cuda_ms=$(awk -v s="$(value seconds_median "$cuda.json")" 'BEGIN { printf "%.3f", s * 1000 }')
    differ=$(awk 'NR == FNR { a[FNR] = $0; next } a[FNR] != $0 { d++ } END { print d + 0 }' \
      "$cpu.csv" "$cuda.csv")
    if cmp -s "$cpu.csv" "$cuda.csv"; then
      equal="yes"
    else
      equal="no: $differ cells differ"
      fail "heightmap: CUDA $mode on $name differs from the CPU in $differ of $cells cells"
    fi
  fi
  md heightmap "| $name | $mode | $cells | $equal | $cpu_ms | $cuda_ms | $(ratio "$cpu_ms" "$cuda_ms") |"
  record heightmap "{\"map\": \"$name\", \"mode\": \"$mode\", \"cells\": $cells, \"cells_differing\": $(json_number "$differ"), \"cpu_median_ms\": $(json_number "$cpu_ms"), \"cuda_median_ms\": $(json_number "$cuda_ms")}"
}
