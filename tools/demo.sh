#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Installs, builds and runs the main job on built-in data: a simulated lidar drive through a yard
# is recorded as a ray cloud, mapped on the CPU, saved, exported and checked against the scene.
# Then the service: raymapd on loopback DDS, driven by a simulated lidar (tools/service-demo.sh).
# Output goes to ./raymap-demo (or the directory given as the first argument).
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-raymap-demo}
tools/setup-debian.sh
cmake --preset release >/dev/null
cmake --build --preset release --target raymap raymapd raymap-load
build/release/tools/raymap demo --output-dir "$out"
build/release/tools/raymap info "$out/yard.rmap"
tools/service-demo.sh build/release
