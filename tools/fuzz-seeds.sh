#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Regenerates the fuzz targets' seed corpora (tests/fuzz/corpus) with raymap's own writers:
#   tools/fuzz-seeds.sh [BUILD_DIR]   (default build/release; needs fuzz_make_seeds and raymap)
# PLY, trajectory, CDR messages, record log and bags from fuzz_make_seeds; map files of every map
# mode from `raymap populate`; raymapd's shipped configurations and the simulator's scenes.
# Review the diff before committing: seeds are test inputs.
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build/release}
export CYCLONEDDS_URI="file://$PWD/config/cyclonedds-loopback.xml"  # Cyclone stays on lo
cmake --build "$build" --target fuzz_make_seeds raymap >/dev/null
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
"$build/tests/fuzz/fuzz_make_seeds" "$out"

# Map files: small regions and coarse voxels keep them a few kilobytes.
mkdir -p "$out/map_file"
rays="$out/ply/rays_le.ply"
populate() {
  local name=$1
  shift
  "$build/tools/raymap" populate "$rays" -o "$out/map_file/$name.rmap" --resolution 0.5 \
    --region-voxels 4 --quiet "$@"
}
populate occupancy
populate occupancy_scan --semantics scan
populate ndt_om --mode ndt-om
populate ndt_tm_decay --mode ndt-tm+decay
populate decay --mode decay
populate tsdf --mode tsdf

mkdir -p "$out/daemon_config" "$out/scene_file"
cp config/*.yaml "$out/daemon_config/"
cp config/scenes/*.yaml "$out/scene_file/"

rm -rf tests/fuzz/corpus
mkdir -p tests/fuzz/corpus
cp -r "$out"/* tests/fuzz/corpus/
du -sh tests/fuzz/corpus
find tests/fuzz/corpus -type f | sed 's|tests/fuzz/corpus/||' | cut -d/ -f1 | sort | uniq -c
