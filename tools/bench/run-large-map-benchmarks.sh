#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# The large-map benchmark of docs/benchmarks.md (issue 28): a long synthetic drive made on the fly
# (tools/bench/make-town-drive.py: a street lined with buildings, driven out and back, so every
# region of the way out is needed again on the way back), populated with unlimited memory and
# through pools of 1/2 and 1/8 of the map (the last also with a small compressed tier, so that
# most of the map goes to the spill file). The configurations take turns, one run each per round;
# each rate is the median over the rounds. Every tiered map file must equal the unlimited one.
#   tools/bench/run-large-map-benchmarks.sh [KM] [OUT_DIR] [extra raymap populate options...]
# KM: kilometres driven (default 3: about 25 million rays). Needs the release build (built here)
# and about 2 GB of disk per km for the ray cloud, beside the maps.
set -euo pipefail
cd "$(dirname "$0")/../.."
km=${1:-3}
out=${2:-build/bench-results/large-map}
shift $(($# > 2 ? 2 : $#))
repeat=${RAYMAP_BENCH_REPEAT:-3}
mkdir -p "$out"
cmake --preset release >/dev/null
cmake --build --preset release --target raymap >/dev/null
bin=build/release/tools
source tools/bench/bench-lib.sh

scene="$out/town-${km}km.yaml"
rays="$out/town-${km}km.ply"
if [ ! -f "$rays" ]; then
  tools/bench/make-town-drive.py "$km" >"$scene"
  "$bin/raymap" simulate "$scene" --rays "$rays" -q
fi
common=(--threads 0 --max-range 30 "$@")

# The unlimited run first, alone: its region count sizes the pools.
"$bin/raymap" populate "$rays" "${common[@]}" --max-memory 64GiB --no-tiers -q \
  -o "$out/unlimited.rmap" --stats-json "$out/unlimited.0.json"
regions=$(value regions "$out/unlimited.0.json")
region_bytes=$(( 32 * 32 * 32 * 12 ))  # occupancy + voxel mean at 32^3 voxels
half=$(( regions / 2 * region_bytes ))
eighth=$(( regions / 8 * region_bytes ))
configs=(unlimited half eighth eighth-spill)
options_of() {
  case $1 in
    unlimited) echo "--max-memory 64GiB --no-tiers" ;;
    half) echo "--max-memory $half" ;;
    eighth) echo "--max-memory $eighth" ;;
    eighth-spill) echo "--max-memory $eighth --compressed-memory 32MiB" ;;
  esac
}

for round in $(seq "$repeat"); do
  for c in "${configs[@]}"; do
    # shellcheck disable=SC2046
    "$bin/raymap" populate "$rays" "${common[@]}" $(options_of "$c") --spill-dir "$out" -q \
      -o "$out/$c.rmap" --stats-json "$out/$c.$round.json"
  done
done

tvalue() {  # tvalue KEY FILE: a number of the memory_tiers object (wait_seconds is also a top-level key)
  sed -n '/"memory_tiers": *{/,/}/p' "$2" | grep -o "\"$1\": *[0-9.e+-]*" | head -1 | sed 's/.*: *//'
}
median() { sort -g | awk '{a[NR]=$1} END {print (NR % 2) ? a[(NR+1)/2] : (a[NR/2] + a[NR/2+1]) / 2}'; }
base=$(for r in $(seq "$repeat"); do value rays_per_second "$out/unlimited.$r.json"; done | median)
summary="$out/large-map-summary.md"
{
  machine_line "$repeat rounds, configurations interleaved, median"
  echo
  echo "drive: $km km, $(value rays_in "$out/unlimited.0.json") rays, $regions regions of 32^3 at 0.1 m ($(( regions * region_bytes >> 20 )) MiB of pool when unlimited)"
  echo
  echo "| pool | compressed tier | rays/s | / unlimited | peak RSS (MiB) | regions compressed / spilled at the end | spill file (MiB) | restores | waits (time) | ratio | file equal |"
  echo "| --- | --- | ---: | ---: | ---: | --- | ---: | ---: | ---: | ---: | --- |"
  for c in "${configs[@]}"; do
    rate=$(for r in $(seq "$repeat"); do value rays_per_second "$out/$c.$r.json"; done | median)
    rss=$(for r in $(seq "$repeat"); do value peak_rss_bytes "$out/$c.$r.json"; done | median)
    last="$out/$c.$repeat.json"
    equal=yes
    cmp -s "$out/$c.rmap" "$out/unlimited.rmap" || equal=NO
    if [ "$c" = unlimited ]; then
      tiers="| - | - | - | - | - "
    else
      tiers="| $(tvalue regions_compressed "$last") / $(tvalue regions_spilled "$last") | $(awk -v b="$(tvalue spill_file_bytes "$last")" 'BEGIN{printf "%.0f", b/1048576}') | $(tvalue restores "$last") | $(tvalue waits "$last") ($(awk -v w="$(tvalue wait_seconds "$last")" 'BEGIN{printf "%.1f", w}') s) | $(awk -v r="$(tvalue compression_ratio "$last")" 'BEGIN{printf "%.1f", r}') "
    fi
    printf "| %s | %s | %.0f | %.2f | %.0f %s| %s |\n" "$c" \
      "$(case $c in eighth-spill) echo 32MiB ;; unlimited) echo - ;; *) echo 1GiB ;; esac)" \
      "$rate" "$(awk -v a="$rate" -v b="$base" 'BEGIN{print a/b}')" \
      "$(awk -v b="$rss" 'BEGIN{print b/1048576}')" "$tiers" "$equal"
  done
} >"$summary"
cat "$summary"
