#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# The CUDA check on a machine with an NVIDIA GPU: builds raymap with CUDA, runs the CUDA tests
# (agreement with the CPU reference on generated rays and, when present, on the shared data),
# then benchmarks the CPU, OpenCL (when a platform exists) and CUDA backends on the shared data
# and on a large synthetic scene, and prints one table; then the height-map tests and timings.
#   tools/gpu-check.sh [DATA_DIR] [OUT_DIR]
# Environment: RAYMAP_CUDA_ARCHITECTURES (default: the build's 87;89;90),
# RAYMAP_GPU_CHECK_SCANS (synthetic scans of 32 x 512 rays, default 1000 = 16.4 M rays),
# RAYMAP_BENCH_REPEAT (default 3). Needs what tools/setup-debian.sh installs, plus the CUDA
# toolkit (nvcc) and the NVIDIA driver. Exits 1 when there is no CUDA device or a test fails.
set -euo pipefail
cd "$(dirname "$0")/.."
data=${1:-../shared/data}
out=${2:-build/gpu-check}
build=build/gpu-check-build
repeat=${RAYMAP_BENCH_REPEAT:-3}
scans=${RAYMAP_GPU_CHECK_SCANS:-1000}
mkdir -p "$out"

echo "== build (Release, CUDA on, warnings as errors)"
arch=()
if [ -n "${RAYMAP_CUDA_ARCHITECTURES:-}" ]; then
  arch=(-DCMAKE_CUDA_ARCHITECTURES="$RAYMAP_CUDA_ARCHITECTURES")
fi
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DRAYMAP_CUDA=ON -DRAYMAP_WERROR=ON \
  "${arch[@]}" >"$out/configure.log"
cmake --build "$build" >"$out/build.log" 2>&1 || { tail -40 "$out/build.log"; exit 1; }
raymap="$build/tools/raymap"

echo "== devices"
"$raymap" devices | tee "$out/devices.txt"
if ! grep -q "default for --backend cuda" "$out/devices.txt"; then
  echo "gpu-check: no CUDA device here (see above); nothing to check" >&2
  exit 1
fi
have_opencl=0
grep -q "default for --backend opencl" "$out/devices.txt" && have_opencl=1

echo "== CUDA tests"
tests_status=0
RAYMAP_SHARED_DATA="$data" ctest --test-dir "$build" -L cuda --output-on-failure \
  -j "$(nproc)" >"$out/ctest-cuda.log" 2>&1 || tests_status=$?
grep -E "tests passed|tests failed|Skipped|Failed" "$out/ctest-cuda.log" || true
# Agreement figures the data tests print, for docs/benchmarks.md.
grep -h "\[device-agreement\]" "$build"/Testing/Temporary/LastTest.log >"$out/agreement.txt" || true
cat "$out/agreement.txt"

source tools/bench/bench-lib.sh

echo "== synthetic scene: the built-in yard, $scans scans"
scene="$out/scene/yard_raycloud.ply"
if [ ! -f "$scene" ]; then
  "$raymap" demo --scans "$scans" --output-dir "$out/scene" --quiet
fi

common=(--resolution 0.1 --max-range 20 --hit 0.7 --miss 0.4 --repeat "$repeat" --steady-state)
table="$out/gpu-check.md"
{
  machine_line "repeat $repeat, steady state, 0.1 m, 20 m"
  echo "device: $(grep -m1 -A0 'device 0:' "$out/devices.txt" | tail -1 | sed 's/^ *//')"
  echo
  echo "| data | semantics | backend | rays/s | × CPU | updates dropped | rays skipped | cache hits / misses / evictions | host planning (rays/s) | wait (s) |"
  echo "| --- | --- | --- | ---: | ---: | ---: | ---: | --- | ---: | ---: |"
} >"$table"

bench() {  # bench NAME INPUT [options]: every backend, both semantics, one row each
  local name=$1 input=$2
  shift 2
  [ -f "$input" ] || { echo "gpu-check: $input absent, $name skipped" >&2; return 0; }
  local backends=(cpu cuda)
  [ "$have_opencl" = 1 ] && backends=(cpu opencl cuda)
  for semantics in ray scan; do
    local cpu_rate=""
    for backend in "${backends[@]}"; do
      local f="$out/$name-$semantics-$backend.json"
      local threads=()
      [ "$backend" = cpu ] && threads=(--threads-list 0)
      "$raymap" bench "$input" "${common[@]}" "$@" --semantics-list "$semantics" \
        --backend "$backend" "${threads[@]}" --json "$f" 2>>"$out/bench.log"
      local rate
      rate=$(value rays_per_second "$f")
      [ "$backend" = cpu ] && cpu_rate=$rate
      if [ "$backend" = cpu ]; then
        printf '| %s | %s | cpu (%s threads) | %.0f | 1.00 | %s | | | | |\n' "$name" "$semantics" \
          "$(nproc)" "$rate" "$(value updates_dropped "$f")" >>"$table"
        continue
      fi
      local plan rays
      plan=$(value plan_seconds "$f")
      rays=$(value rays_integrated "$f")
      printf '| %s | %s | %s | %.0f | %.2f | %s | %s | %s / %s / %s | %.0f | %.3f |\n' \
        "$name" "$semantics" "$backend" "$rate" \
        "$(awk -v a="$rate" -v b="$cpu_rate" 'BEGIN { print a / b }')" \
        "$(value updates_dropped "$f")" "$(value rays_skipped "$f")" \
        "$(value cache_hits "$f")" "$(value cache_misses "$f")" "$(value cache_evictions "$f")" \
        "$(awk -v r="$rays" -v s="$plan" 'BEGIN { print s > 0 ? r / s : 0 }')" \
        "$(value wait_seconds "$f")" >>"$table"
    done
  done
}

echo "== benchmarks"
if [ -d "$data" ]; then
  run_data_sets bench "$data"
else
  echo "gpu-check: no shared data at $data; synthetic scene only" >&2
fi
bench "synthetic-yard-$scans" "$scene"
echo "cuda device: $(text device "$out/synthetic-yard-$scans-ray-cuda.json")" >>"$table"
echo
cat "$table"
echo "== height maps (CUDA, OpenCL and CPU generators)"
ctest --test-dir "$build" -L heightmap --output-on-failure >"$out/ctest-heightmap.log" 2>&1 ||
  tests_status=$?
grep -E "tests passed|tests failed" "$out/ctest-heightmap.log" || true
tools/bench/run-heightmap-benchmarks.sh "$data" "$out" "$build"
echo "== raymapd on CUDA (Ouster-like input over loopback DDS, see docs/benchmarks.md)"
DURATION=15 tools/bench/run-daemon-benchmarks.sh "$build" "cuda cpu" "10 20 30" \
  >"$out/raymapd.jsonl" 2>"$out/raymapd.log" || tests_status=$?
cat "$out/raymapd.jsonl"
if [ "$tests_status" != 0 ]; then
  echo "gpu-check: CUDA tests failed (see $out/ctest-cuda.log)" >&2
  exit 1
fi
