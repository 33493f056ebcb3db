#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# raymap against its peers, side by side, in one interleaved run: OctoMap (Debian's
# liboctomap-dev: insertRay and insertPointCloud), OHM (ohmpopcpu, ohmpopocl on PoCL) and Bonxai
# (ProbabilisticMap::insertPointCloud), built from their public sources at pinned commits, on the
# shared data sets and a synthetic town. One command from a checkout:
#
#   tools/bench/run-peer-benchmarks.sh OHM_GIT BONXAI_GIT [OUT_DIR]
#
#   OHM_GIT     a git directory (bare or .git) holding csiro-robotics/ohm commit 4e2e769
#               (git clone --bare https://github.com/csiro-robotics/ohm)
#   BONXAI_GIT  a git directory holding facontidavide/Bonxai commit 3e8e63f
#               (git clone --bare https://github.com/facontidavide/Bonxai)
#   OUT_DIR     default build/peers/out-<commit>; its summary.md is the table for
#               docs/benchmarks.md
#
# Environment: PEERS_KIT (the team's peer kit: drivers, ray-file converter, runner and summary;
# default ../shared/bench), PEERS_DATA (default ../shared/data), PEERS_ROUNDS (default 5),
# PEERS_SYSTEMS (a subset of the runner's systems, e.g. "rm_cpu1_ray bonxai"), PEERS_DATASETS
# (default "ouster 3dtk octomap synth20"), QUIET_MAX (seconds to wait before each run for the
# machine to go quiet; default 60), RAYMAP (a raymap binary; default: the release build, built
# here).
#
# Where things go: build/peers/ (git-ignored) holds a copy of the kit, the peers' sources and
# builds (.anchors/src), the converted ray files (.anchors/rays) and the runs. A second run reuses
# the builds and ray files (delete build/peers to start over). Debian packages the peers need:
# tools/bench/run-peer-benchmarks.sh --packages prints the apt-get line.
set -euo pipefail
cd "$(dirname "$0")/../.."
packages="g++ cmake liboctomap-dev libglm-dev zlib1g-dev libtbb-dev libeigen3-dev \
pocl-opencl-icd ocl-icd-opencl-dev opencl-headers time python3"
if [ "${1:-}" = --packages ]; then
  echo "apt-get install -y $packages"
  exit 0
fi
if [ $# -lt 2 ]; then
  sed -n '3,27p' "$0" | sed 's/^# \{0,1\}//' >&2
  exit 2
fi
ohm_git=$(realpath "$1")
bonxai_git=$(realpath "$2")
kit=$(realpath "${PEERS_KIT:-../shared/bench}")
data=$(realpath "${PEERS_DATA:-../shared/data}")
work=build/peers
commit=$(git rev-parse --short HEAD)
out=$(realpath -m "${3:-$work/out-$commit}")
read -r -a datasets <<<"${PEERS_DATASETS:-ouster 3dtk octomap synth20}"
for f in peers.sh peers_run.sh peers_summary.py rays_convert.py synth_rays.cpp; do
  [ -e "$kit/$f" ] || { echo "error: $kit/$f: the peer kit is not there (PEERS_KIT)" >&2; exit 1; }
done
for f in ouster/raw 3dtk/raw octomap/raw; do
  [ -d "$data/$f" ] || { echo "error: $data/$f: no such folder (PEERS_DATA)" >&2; exit 1; }
done

if [ -z "${RAYMAP:-}" ]; then
  cmake --preset release >/dev/null
  cmake --build --preset release --target raymap >/dev/null
  RAYMAP=$(realpath build/release/tools/raymap)
fi
export RAYMAP

# The runner expects the kit in bench/, the data in shared/data and the peers in .anchors/ of one
# folder.
mkdir -p "$work/.anchors/rays" "$work/shared"
rm -rf "$work/bench"
cp -r "$kit" "$work/bench"
ln -sfn "$data" "$work/shared/data"
cd "$work"
if [ ! -x .anchors/src/ohm/build/bin/ohmpopcpu ] || [ ! -e .anchors/src/bonxai/build/libbonxai_map.a ]; then
  echo "== building OctoMap driver, OHM and Bonxai (about 8 minutes on 2 cores)"
  bench/peers.sh "$ohm_git" "$bonxai_git" >peers-build.log 2>&1 ||
    { echo "error: the peer build failed; see $work/peers-build.log" >&2; exit 1; }
else
  bench/build.sh >/dev/null  # the peers are built: only our drivers, into the fresh kit copy
  g++ -std=c++17 -O3 -DNDEBUG -I.anchors/src/bonxai/bonxai_core/include \
    -I.anchors/src/bonxai/bonxai_map/include -o bench/bin/bonxai_bench bench/bonxai_bench.cpp \
    .anchors/src/bonxai/build/libbonxai_map.a
fi

# Ray files: RAYBIN01 for the OctoMap and Bonxai drivers, ray-cloud PLY for OHM (and raymap on
# the synthetic town). Written under a temporary name and renamed, so an interrupted conversion
# is redone.
R=.anchors/rays
D=shared/data
convert() {  # convert NAME ARGS...: rays_convert.py ARGS -o $R/NAME.rays, then its PLY
  local name=$1
  shift
  if [ ! -e "$R/$name.rays" ]; then
    echo "== converting $name"
    python3 bench/rays_convert.py "$@" -o "$R/$name.rays.tmp" >"$R/$name.log" 2>&1
    mv "$R/$name.rays.tmp" "$R/$name.rays"
  fi
  if [ ! -e "$R/$name.ply" ]; then
    python3 bench/rays_convert.py to-ply "$R/$name.rays" "$R/$name.ply.tmp" >>"$R/$name.log" 2>&1
    mv "$R/$name.ply.tmp" "$R/$name.ply"
  fi
}
convert octomap_scan octomap-dat $D/octomap/raw/scan.dat.bz2
convert 3dtk_frames 3dtk $D/3dtk/raw --poses frames
convert ouster_os1_lb_n3 ouster $D/ouster/raw/OS-1-128_v2.3.0_1024x10_lb_n3.pcap \
  $D/ouster/raw/OS-1-128_v2.3.0_1024x10.json \
  $D/ouster/raw/OS-1-128_v2.3.0_1024x10_lb_n3_poses_kitti.txt
if [ ! -e "$R/synth_town_20.rays" ]; then
  bench/bin/synth_rays "$R/synth_town_20.rays.tmp" --scans 20 >/dev/null
  mv "$R/synth_town_20.rays.tmp" "$R/synth_town_20.rays"
fi
convert synth_town_20

echo "== $(date -u +%T) interleaved run: ${PEERS_ROUNDS:-5} rounds, ${datasets[*]} -> $out"
mkdir -p "$out"
{
  echo "# raymap $commit ($RAYMAP)"
  echo "# $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $(nproc) cores"
} >"$out/machine.txt"
QUIET_MAX=${QUIET_MAX:-60} bench/peers_run.sh "$out" "${PEERS_ROUNDS:-5}" "${datasets[@]}"
python3 bench/peers_summary.py "$out" --ohminfo .anchors/src/ohm/build/bin/ohminfo \
  >"$out/summary.md"
echo "== summary: $out/summary.md"
