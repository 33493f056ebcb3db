#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Builds raymap and runs its tests: tools/test.sh [--preset release|ci|asan|debug] [--no-install]
#   [extra ctest arguments, e.g. -L unit]
set -euo pipefail
cd "$(dirname "$0")/.."
preset=release
install=1
ctest_args=()
while [ $# -gt 0 ]; do
  case "$1" in
    --preset) preset=$2; shift 2 ;;
    --no-install) install=0; shift ;;
    *) ctest_args+=("$1"); shift ;;
  esac
done
if [ "$install" -eq 1 ]; then
  tools/setup-debian.sh
  tools/setup-node.sh  # the rosbag tests' independent MCAP/ROS 2 implementation (npm)
fi
cmake --preset "$preset" >/dev/null
cmake --build --preset "$preset"
ctest --preset "$preset" "${ctest_args[@]}"
