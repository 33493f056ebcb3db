#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Proves the installed CMake package: `cmake --install BUILD_DIR --prefix` a fresh prefix, copy
# examples/ out of the source tree, build each example there with only find_package(raymap) and
# run it. map_ray_cloud must give the voxel counts `raymap populate` gives on the same ray cloud
# (per ray and per scan); heightmap_from_scans must find its step 0.3 m above the floor.
#   tools/check-install.sh BUILD_DIR   (a built raymap build directory with the tools)
set -euo pipefail
cd "$(dirname "$0")/.."
if [ $# -ne 1 ] || [ ! -x "$1/tools/raymap" ]; then
  echo "usage: tools/check-install.sh BUILD_DIR  (a built raymap build directory)" >&2
  exit 2
fi
build=$(cd "$1" && pwd)
source_dir=$(pwd)
work=$(mktemp -d /tmp/raymap-install-check.XXXXXX)
trap 'rm -rf "$work"' EXIT
prefix=$work/prefix

echo "== cmake --install $build --prefix $prefix"
cmake --install "$build" --prefix "$prefix" >"$work/install.log"
[ -f "$prefix/lib/cmake/raymap/raymapConfig.cmake" ] ||
  { echo "check-install: no raymapConfig.cmake installed" >&2; exit 1; }
if find "$prefix/include" -name '*.hpp' -exec grep -lE '#include "(src|platform|kernels)/' {} + |
  grep .; then
  echo "check-install: an installed header includes an internal one (above)" >&2
  exit 1
fi

cp -r examples "$work/examples"  # outside the source tree: only the installed package is there
for example in map_ray_cloud heightmap_from_scans map_recording map_outputs depth_camera \
  ros_messages; do
  echo "== example $example against the installed package"
  cmake -S "$work/examples/$example" -B "$work/build-$example" -G Ninja \
    -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$prefix" >"$work/$example-configure.log" ||
    { cat "$work/$example-configure.log" >&2; exit 1; }
  cmake --build "$work/build-$example" >"$work/$example-build.log" ||
    { tail -40 "$work/$example-build.log" >&2; exit 1; }
  if grep -q -- "-I$source_dir" "$work/build-$example/build.ninja"; then
    echo "check-install: $example was compiled against the source tree" >&2
    exit 1
  fi
done

echo "== map_ray_cloud agrees with raymap populate"
"$build/tools/raymap" simulate "$source_dir/config/scenes/room.yaml" --rays "$work/room.ply" >/dev/null
count() {  # count <key> <file of "key value" lines or JSON>
  grep -oE "(^|[^a-z_])$1\"?[: ]+[0-9]+" "$2" | head -1 | grep -oE '[0-9]+$'
}
for semantics in ray scan; do
  "$work/build-map_ray_cloud/map_ray_cloud" "$work/room.ply" --semantics "$semantics" \
    | tee "$work/example-$semantics.txt"
  "$build/tools/raymap" populate "$work/room.ply" -o "$work/room-$semantics.rmap" \
    --semantics "$semantics" --stats-json "$work/populate-$semantics.json" --quiet >/dev/null
  for key in voxels_occupied voxels_free; do
    ours=$(count "$key" "$work/example-$semantics.txt")
    theirs=$(count "$key" "$work/populate-$semantics.json")
    if [ "$ours" != "$theirs" ] || [ "$ours" -eq 0 ]; then
      echo "check-install: per-$semantics $key: example $ours, raymap populate $theirs" >&2
      exit 1
    fi
  done
  echo "per-$semantics: the example and raymap populate agree"
done

# Bad arguments are refused, not taken as defaults (issue 52, L14).
for bad in "--semantics bogus" "--save" "--resolution ten"; do
  # shellcheck disable=SC2086
  if "$work/build-map_ray_cloud/map_ray_cloud" "$work/room.ply" $bad >/dev/null 2>&1; then
    echo "check-install: map_ray_cloud accepted '$bad'" >&2
    exit 1
  fi
done

echo "== map_recording: NDT-OM and TSDF maps with the tiers on agree with raymap populate"
for mode in ndt-om tsdf; do
  "$work/build-map_recording/map_recording" "$work/room.ply" "$work/example-$mode.rmap" \
    --mode "$mode" --max-memory-mib 64 | tee "$work/example-$mode.txt"
  "$build/tools/raymap" populate "$work/room.ply" -o "$work/populate-$mode.rmap" --mode "$mode" \
    --max-memory 64MiB --stats-json "$work/populate-$mode.json" --quiet >/dev/null
  for key in regions rays_integrated; do
    ours=$(count "$key" "$work/example-$mode.txt")
    theirs=$(count "$key" "$work/populate-$mode.json")
    if [ "$ours" != "$theirs" ] || [ "$ours" -eq 0 ]; then
      echo "check-install: --mode $mode $key: example $ours, raymap populate $theirs" >&2
      exit 1
    fi
  done
  # The same layers: `raymap info` of both files says the same except the provenance.
  diff <("$build/tools/raymap" info "$work/example-$mode.rmap" | grep -vE '^(map|source|created_by|rays_in|rays_integrated|min_range_m|max_range_m|segment_length_m|walk) ') \
    <("$build/tools/raymap" info "$work/populate-$mode.rmap" | grep -vE '^(map|source|created_by|rays_in|rays_integrated|min_range_m|max_range_m|segment_length_m|walk) ') ||
    { echo "check-install: --mode $mode: the example's map differs from raymap populate's" >&2; exit 1; }
  echo "--mode $mode: the example and raymap populate agree"
done

echo "== map_outputs: a Nav2 costmap of the room and its export, as raymap export writes it"
mkdir -p "$work/outputs"
"$work/build-map_outputs/map_outputs" "$work/populate-ndt-om.rmap" "$work/outputs" --size 9 \
  --export ndt | tee "$work/outputs.txt"
"$build/tools/raymap" export "$work/populate-ndt-om.rmap" --mode ndt \
  --ply "$work/raymap-export.ply" --quiet
cmp "$work/outputs/voxels.ply" "$work/raymap-export.ply" ||
  { echo "check-install: map_outputs' export differs from raymap export's" >&2; exit 1; }
[ "$(head -c 13 "$work/outputs/costmap.pgm")" = "$(printf 'P5\n90 90\n255')" ] ||
  { echo "check-install: the costmap image is not 90 x 90 cells" >&2; exit 1; }
grep -qE '^image: costmap.pgm$' "$work/outputs/costmap.yaml" &&
  grep -qE '^origin: \[-4.5, -4.5, 0.0\]$' "$work/outputs/costmap.yaml" ||
  { echo "check-install: the costmap's map_server YAML is not as expected" >&2; exit 1; }
lethal=$(grep -oE '[0-9]+ lethal' "$work/outputs.txt" | grep -oE '^[0-9]+')
[ "${lethal:-0}" -gt 0 ] || { echo "check-install: the room's costmap has no lethal cell" >&2; exit 1; }

echo "== depth_camera: 16UC1 images with their intrinsics see the box, not what it hides"
"$work/build-depth_camera/depth_camera" | tee "$work/depth.txt"
for expected in "(1.05, 0.05, 0.45): free" "(2.05, 0.05, 0.45): occupied" \
  "(2.75, 0.05, 0.45): unobserved" "(3.05, 1.05, 0.45): occupied"; do
  grep -qF "voxel at $expected" "$work/depth.txt" ||
    { echo "check-install: depth_camera: not '$expected'" >&2; exit 1; }
done

for rolling in "" --rolling; do
  echo "== heightmap_from_scans $rolling"
  # shellcheck disable=SC2086
  "$work/build-heightmap_from_scans/heightmap_from_scans" "$work/heightmap.csv" $rolling | tee "$work/hm.txt"
  step=$(grep -oE 'elevation at \(3.55, 0.05\): [-0-9.]+' "$work/hm.txt" | grep -oE '[-0-9.]+$')
  floor=$(grep -oE 'elevation at \(1.05, 2.55\): [-0-9.]+' "$work/hm.txt" | grep -oE '[-0-9.]+$')
  awk -v s="$step" -v f="$floor" 'BEGIN { exit !(s > 0.2 && s < 0.35 && f > -0.1 && f < 0.05) }' ||
    { echo "check-install: $rolling step at $step m, floor at $floor m (want about 0.3 and 0)" >&2; exit 1; }
  [ "$(wc -l <"$work/heightmap.csv")" -eq 10001 ] ||
    { echo "check-install: the height-map CSV does not have 100 x 100 cells" >&2; exit 1; }
done
echo "== ros_messages: serialized Odometry and PointCloud2 decoded, the sweeps deskewed"
"$work/build-ros_messages/ros_messages" | tee "$work/ros.txt" ||
  { echo "check-install: ros_messages failed" >&2; exit 1; }
for expected in "clouds 10" "points 14400" "points_no_pose 0" \
  "voxel at (7.75, -0.05, 1.05): free" "damaged cloud: sensor_msgs/PointCloud2: truncated"; do
  grep -qF "$expected" "$work/ros.txt" ||
    { echo "check-install: ros_messages: not '$expected'" >&2; exit 1; }
done
if [ -d "$prefix/lib/python3/dist-packages/raymap" ]; then
  echo "== the installed Python module maps the room as raymap populate does"
  PYTHONPATH="$prefix/lib/python3/dist-packages" /usr/bin/python3 -B - "$work/room.ply" <<'PY' |
import sys, raymap
mapper = raymap.Mapper(semantics="ray")
for scan in raymap.read_recording(sys.argv[1]):
    mapper.integrate_rays(scan.origins, scan.ends, intensities=scan.intensities,
                          no_return=scan.no_return)
mapper.flush()
print(f"voxels_occupied {mapper.counts()['voxels_occupied']}")
print(f"voxels_free {mapper.counts()['voxels_free']}")
PY
    tee "$work/python.txt"
  for key in voxels_occupied voxels_free; do
    [ "$(count "$key" "$work/python.txt")" = "$(count "$key" "$work/populate-ray.json")" ] ||
      { echo "check-install: the installed Python module's $key differs from populate's" >&2; exit 1; }
  done
fi
echo "check-install: the installed package builds and runs the six examples"
