#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# raymap on arm64 (a Jetson Orin's CPU), from this x86-64 Debian 12 (docs/arm64.md):
#  1. an arm64 Debian 12 root with the dependencies (tools/arm64-root.sh, cached),
#  2. the cross build (cmake --preset arm64: warnings as errors, no CUDA or OpenCL),
#  3. its tests under qemu-user-static (ctest --preset arm64; the subset below, raymapd's end-to-end
#     tests among them),
#  4. the maps: `raymap populate` of the arm64 build (emulated) against the x86-64 build's on the
#     same rays, byte for byte: per ray and per scan in occupancy, and NDT-OM (per ray: NDT has
#     no per-scan mode) — on the shared data sets when ../shared/data has them, and always on the
#     generated room and yard scenes.
#
#   tools/check-arm64.sh X86_BUILD_DIR     everything above (about 25 minutes on 2 cores)
#   tools/check-arm64.sh --ci              CI's subset, to fit its time budget: the map library
#                                          alone (no DDS, CLI11 or libsystemd, as the library
#                                          preset; in build/arm64-library) and its unit tests
#                                          under qemu, MapperBytes among them (maps whose
#                                          SHA-256 the x86-64 build recorded); no command
#                                          line, no raymapd, no step 4
#
# The unit tests run under emulation except WriteIntent.APageReadThenWrittenFaultsOnce…: it
# counts page faults, and under qemu those are the emulator's own (an atomic add is a load and
# a compare-and-swap there), not an arm64 CPU's. Needs root (tools/arm64-root.sh registers qemu
# with binfmt_misc).
set -euo pipefail
cd "$(dirname "$0")/.."
ci=0
if [ "${1:-}" = "--ci" ]; then
  ci=1
elif [ $# -ne 1 ] || [ ! -x "$1/tools/raymap" ]; then
  echo "usage: tools/check-arm64.sh X86_BUILD_DIR | --ci  (X86_BUILD_DIR: a built x86-64 build)" >&2
  exit 2
else
  x86=$(cd "$1" && pwd)
fi

root=${RAYMAP_ARM64_ROOT:-$PWD/build/arm64-root}
if [ ! -d "$root/usr/lib/aarch64-linux-gnu" ]; then
  if [ $ci -eq 1 ]; then
    tools/arm64-root.sh --library "$root"
  else
    tools/arm64-root.sh "$root"
  fi
fi
export RAYMAP_ARM64_ROOT=$root
# An arm64 program started by a test (the command line, raymapd) runs under qemu through
# binfmt_misc and finds its loader and libraries in the root.
export QEMU_LD_PREFIX=$root
emulated_out='WriteIntent.APageReadThenWrittenFaultsOnceWhenFirstTouchedForWrite'
ci_left_out='DecayMap.AMapOfDecayRatesOnlyMatchesTheOccupancyMapsDecayRates'
emulated_slow='^SecureRaymapd\.OnlyAuthorisedEnclavesReadAndWriteAndNothingIsReadableOnTheWire$'

if [ $ci -eq 1 ]; then
  echo "== cross build of the map library alone (cmake --preset arm64) ($(date +%T))"
  lib=build/arm64-library
  # At -O1 (a third less compile time): with contraction off and no fast-math, the optimisation
  # level changes no floating-point result, so MapperBytes holds at every level.
  cmake --preset arm64 -B "$lib" -DRAYMAP_BUILD_SERVICE=OFF -DRAYMAP_BUILD_TOOLS=OFF \
    -DCMAKE_DISABLE_FIND_PACKAGE_CycloneDDS=ON -DCMAKE_DISABLE_FIND_PACKAGE_CLI11=ON \
    -DCMAKE_DISABLE_FIND_PACKAGE_octomap=ON "-DCMAKE_CXX_FLAGS_RELEASE=-O1 -DNDEBUG" \
    "-DCMAKE_C_FLAGS_RELEASE=-O1 -DNDEBUG" >/dev/null
  cmake --build "$lib"
  test -f "$lib/src/bag/libraymap_bag.a"  # the rosbag2 reader, without DDS
  if grep -qiE 'ddsc|CLI11|libsystemd' "$lib/build.ninja"; then
    echo "the library-only build links or includes a service/tools dependency" >&2
    exit 1
  fi
  file "$lib/tests/test_unit_mapper" | grep -q "ARM aarch64" || {
    echo "check-arm64: $lib/tests/test_unit_mapper is not an arm64 program" >&2
    exit 1
  }
  echo "== unit tests under qemu-aarch64 ($(date +%T))"
  # CI's time budget: also without one of the slowest tests under emulation (22 s: a map of decay
  # rates only against a combined map's, voxel by voxel, for 9,000 rays at 1 and 3 threads; the
  # rest of DecayMap.* runs), as the ThreadSanitizer run leaves it out. The whole subset runs by
  # hand with tools/check-arm64.sh X86_BUILD_DIR.
  ctest --test-dir "$lib" -L unit -E "$emulated_out|$ci_left_out" --timeout 900 -j2 \
    --output-on-failure
  exit 0
fi

[ -e /proc/sys/fs/binfmt_misc/qemu-aarch64 ] || {
  echo "check-arm64: qemu-aarch64 is not registered with binfmt_misc: the tests that start the" \
    "command line or raymapd cannot run (tools/arm64-root.sh registers it where it can)" >&2
  exit 1
}
echo "== cross build (cmake --preset arm64) ($(date +%T))"
cmake --preset arm64 >/dev/null
cmake --build --preset arm64
file build/arm64/tools/raymap | grep -q "ARM aarch64" || {
  echo "check-arm64: build/arm64/tools/raymap is not an arm64 program" >&2
  exit 1
}
build/arm64/tools/raymap --version

echo "== tests under qemu-aarch64 ($(date +%T))"
ctest --preset arm64 -L 'unit|rosbag|replay|heightmap|data' -E "$emulated_out" --timeout 900
# raymapd end to end (arm64 raymapd, its arm64 test drivers, loopback DDS), one at a time as in
# every build. Left out: the secure map comparison, which needs raymapd to keep up with 10 Hz
# clouds (emulated, it sheds points by its latency bound, so two runs' maps differ in a few
# cells; the ThreadSanitizer build leaves it out for the same reason).
ctest --preset arm64 -L service -E "$emulated_slow" --timeout 900

echo "== maps: arm64 against x86-64, byte for byte ($(date +%T))"
work=$(mktemp -d /var/tmp/raymap-arm64-maps.XXXXXX)
trap 'rm -rf "$work"' EXIT
inputs=()
for scene in room yard; do
  "$x86/tools/raymap" simulate "config/scenes/$scene.yaml" --rays "$work/$scene.ply" --quiet
  inputs+=("$work/$scene.ply")
done
shared=../shared/data
for data in ouster/ouster_os1_lb_n3_raycloud.ply.gz 3dtk/3dtk_raycloud.ply.gz \
  octomap/octomap_scan_raycloud.ply.gz; do
  if [ -f "$shared/$data" ]; then
    inputs+=("$(cd "$shared" && pwd)/$data")
  else
    echo "(no $shared/$data: that data set is left out)"
  fi
done
compared=0
for input in "${inputs[@]}"; do
  for case in occupancy:ray occupancy:scan ndt-om:ray; do
    mode=${case%:*}
    semantics=${case#*:}
    name=$(basename "$input" | cut -d. -f1)-$mode-$semantics
    # NDT keeps 40 bytes a voxel: the Ouster data set needs more than the default 4 GiB.
    flags=(populate "$input" --mode "$mode" --semantics "$semantics" --max-memory 8GiB --quiet)
    "$x86/tools/raymap" "${flags[@]}" -o "$work/$name-x86_64.rmap"
    build/arm64/tools/raymap "${flags[@]}" -o "$work/$name-arm64.rmap"
    if ! cmp "$work/$name-x86_64.rmap" "$work/$name-arm64.rmap"; then
      echo "check-arm64: $name: the arm64 map differs from the x86-64 map" >&2
      exit 1
    fi
    echo "$name: identical ($(stat -c %s "$work/$name-arm64.rmap") bytes)"
    compared=$((compared + 1))
  done
done
echo "check-arm64: $compared maps byte for byte the same on arm64 and x86-64"
