#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Reading speed of rosbag2 input (docs/benchmarks.md): `raymap populate` from an uncompressed
# MCAP bag against the same drive as a ray-cloud PLY. The drive is a simulated scene
# (`raymap simulate`; the room's 16 x 1024 lidar hits a wall with every ray, so the PLY holds no
# no-return rays, which a bag cannot carry); the bag is what `raymap record --format mcap` records
# while `raymap replay` publishes that PLY as a lidar driver and odometry would (PointCloud2 with
# per-point time, Odometry at 100 Hz), so populate deskews it back into the same rays (to float
# rounding). The inputs take turns, one run each per round; medians over the rounds.
#   tools/bench/run-bag-benchmarks.sh [SCANS] [OUT_DIR] [SCENE]
# Needs the release build (built here). DDS stays on loopback.
set -euo pipefail
cd "$(dirname "$0")/../.."
scans=${1:-200}
out=${2:-build/bench-results/bag}
scene=${3:-config/scenes/room.yaml}
repeat=${RAYMAP_BENCH_REPEAT:-5}
rm -rf "$out"
mkdir -p "$out"
cmake --preset release >/dev/null
cmake --build --preset release --target raymap >/dev/null
bin=build/release/tools
export CYCLONEDDS_URI="file://$PWD/config/cyclonedds-loopback.xml"
source tools/bench/bench-lib.sh

"$bin/raymap" simulate "$scene" --rays "$out/drive.ply" --scans "$scans" -q
domain=$((120 + $$ % 50))
"$bin/raymap" record --format mcap -o "$out/drive_bag" --domain "$domain" -q \
  -t /points -t /odom -t /tf_static &
recorder=$!
sleep 2
"$bin/raymap" replay "$out/drive.ply" --domain "$domain" --rate 4 -q
sleep 1
kill -INT "$recorder"
wait "$recorder"
"$bin/raymap" info "$out/drive_bag" >"$out/bag-info.txt"

common=(--resolution 0.1 --max-range 20 --threads 1)
for round in $(seq 1 "$repeat"); do
  for input in ply bag; do
    file="$out/drive.ply"
    [ "$input" = bag ] && file="$out/drive_bag"
    "$bin/raymap" populate "$file" "${common[@]}" --stats-json "$out/$input-$round.json" -q
  done
done

median() {  # median KEY INPUT: over the rounds
  for round in $(seq 1 "$repeat"); do value "$1" "$out/$2-$round.json"; done | sort -g |
    awk '{v[NR]=$1} END {print (NR % 2) ? v[(NR+1)/2] : (v[NR/2] + v[NR/2+1]) / 2}'
}
summary="$out/bag-summary.md"
{
  echo "$(machine_line "$(basename "$scene" .yaml), $scans scans, 0.1 m, 20 m, 1 thread, $repeat rounds")"
  echo
  echo "| input | MB | rays integrated | read + decode s | ns/ray reading | total s | rays/s (total) | voxels occupied |"
  echo "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"
  for input in ply bag; do
    file="$out/drive.ply"
    [ "$input" = bag ] && file="$out/drive_bag"
    rays=$(median rays_integrated "$input")
    read=$(median read_seconds "$input")
    total=$(median total_seconds "$input")
    echo "| $input | $(du -sm "$file" | cut -f1) | $rays | $read |" \
      "$(awk -v r="$rays" -v t="$read" 'BEGIN {printf "%.0f", t / r * 1e9}') | $total |" \
      "$(awk -v r="$rays" -v t="$total" 'BEGIN {printf "%.0f", r / t}') |" \
      "$(median voxels_occupied "$input") |"
  done
  ply_rate=$(awk -v r="$(median rays_integrated ply)" -v t="$(median total_seconds ply)" 'BEGIN {print r / t}')
  bag_rate=$(awk -v r="$(median rays_integrated bag)" -v t="$(median total_seconds bag)" 'BEGIN {print r / t}')
  echo
  echo "bag / PLY rays per second (total): $(awk -v a="$bag_rate" -v b="$ply_rate" 'BEGIN {printf "%.3f", a / b}')"
} | tee "$summary"
