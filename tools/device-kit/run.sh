#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# The device kit's entry point (the kit is built by tools/device-kit.sh; docs/device-kit.md).
# Runs every GPU check of raymap on this machine with nothing but the kit: no compiler, no
# packages, no network. Sections, in this order:
#   devices    raymap devices (CUDA, and OpenCL where NVIDIA's OpenCL driver is present)
#   tests      the CUDA unit, device and data-agreement tests and the height-map tests
#   sanitizer  compute-sanitizer memcheck and racecheck over a short integration of each map mode
#              and of a map larger than its memory pool
#   pipeline   batches planned on the device against the host planner: rays/s and host CPU per
#              ray in every map mode, on all host cores and on 2 (taskset), a depth camera, and
#              raymapd at 10x an OS-1-128 planned on the device (issue 51)
#   bench      raymap bench on the Ouster data and a synthetic scene, every map mode, CUDA
#              against the CPU backend on all cores
#   scaling    the CPU backend's rays/s at 1, 2, 4, 8 and 16 threads, both semantics (issue 29)
#   heightmap  the CUDA height-map generator against the CPU one: the same cells, and timings
#   raymapd    raymapd on CUDA for 30 s at an Ouster OS-1-128's rate, then at rising rates to the
#              highest it keeps up with (loopback DDS only)
#   profile    Nsight Compute's view of the integration kernels, when time is left
# Without a CUDA device the first line says so, the CPU parts run (on a small synthetic scene),
# and the exit status is 77.
#   run.sh [--only SECTION[,SECTION...]] [--budget SECONDS]
# --budget (default 360): the run plans its benchmarks and rate steps to end within it.
# Results go to $OUT when set, else ./gpu-results: results.md (tables), results.json (every
# number), run.log and logs.tar.gz (every log and JSON the tools wrote); rewritten after every
# section. Exit status: 0 all passed on a CUDA device, 1 a check failed, 77 no CUDA device (the
# CPU parts passed), 2 bad arguments.
set -uo pipefail
kit=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
all_sections=(devices tests sanitizer pipeline bench scaling heightmap raymapd profile)
json_lists=(devices tests agreement sanitizer pipeline bench scaling heightmap raymapd profile)  # results.json's lists
only=""
budget=360
while [ $# -gt 0 ]; do
  case $1 in
    --only) only=${2:-}; shift 2 || shift ;;
    --budget) budget=${2:-}; shift 2 || shift ;;
    -h | --help) awk 'NR > 2 && /^#/ { sub(/^# ?/, ""); print; next } NR > 2 { exit }' "$0"; exit 0 ;;
    *) echo "run.sh: unknown argument '$1' (run.sh --help)" >&2; exit 2 ;;
  esac
done
if ! [[ $budget =~ ^[0-9]+$ ]] || [ "$budget" -lt 30 ]; then
  echo "run.sh: --budget must be a whole number of seconds, at least 30 (got '$budget')" >&2
  exit 2
fi
for s in ${only//,/ }; do
  if [[ " ${all_sections[*]} " != *" $s "* ]]; then
    echo "run.sh: --only: unknown section '$s' (sections: ${all_sections[*]})" >&2
    exit 2
  fi
done
wanted() { [ -z "$only" ] || [[ ",$only," == *",$1,"* ]]; }

started=$SECONDS
bin=$kit/bin
out=${OUT:-$PWD/gpu-results}
mkdir -p "$out" || { echo "run.sh: cannot create the results folder $out" >&2; exit 2; }
work=$(mktemp -d "${TMPDIR:-/tmp}/raymap-kit.XXXXXX") || exit 2
mkdir -p "$work/json" "$work/md" "$work/logs" "$work/tmp"
: >"$out/run.log"
source "$kit/bench-lib.sh"  # value, text: numbers and strings out of the tools' JSON
source "$kit/results.sh"
for f in "$kit"/checks/*.sh; do
  source "$f"
done

background_pids=()
cleanup() {
  local pid
  for pid in "${background_pids[@]}"; do
    kill "$pid" 2>/dev/null
  done
  wait 2>/dev/null
  rm -rf "$work"
}
trap cleanup EXIT
trap 'log "stopped by a signal"; publish_results; exit 1' TERM INT

# Everything the executables read comes from the kit; DDS stays on loopback.
export CYCLONEDDS_URI="file://$kit/config/cyclonedds-loopback.xml"
export RAYMAP_SHARED_DATA=$kit/data
export RAYMAP_SCENE_DIR=$kit/config/scenes
export RAYMAP_GOLDEN_DIR=$kit/tests/golden
export TMPDIR=$work/tmp
cpu_model=$(grep -m1 'model name' /proc/cpuinfo 2>/dev/null | cut -d: -f2 | sed 's/^ *//')
cpu_model=${cpu_model:-unknown CPU}

# NVIDIA's OpenCL driver, when the machine has it but no ICD file names it: a private vendors
# folder lets the kit's ICD loader find it, so OpenCL runs on the same GPU too.
for lib in /usr/lib/x86_64-linux-gnu/libnvidia-opencl.so.1 /usr/local/nvidia/lib64/libnvidia-opencl.so.1 \
  /usr/lib64/libnvidia-opencl.so.1; do
  if [ -e "$lib" ] && [ -z "${OCL_ICD_VENDORS:-}" ] && ! ls /etc/OpenCL/vendors/*.icd >/dev/null 2>&1; then
    mkdir -p "$work/icd"
    echo "$lib" >"$work/icd/nvidia.icd"
    export OCL_ICD_VENDORS=$work/icd
  fi
done

# The first line says whether there is a CUDA device.
have_cuda=0
have_opencl=0
gpu_name=""
gpu_driver=""
# (raymap devices exits 1 when no API has a device: that is an answer here, not a failure.)
"$bin/raymap" devices >"$work/logs/devices.txt" 2>&1
if grep -q "default for --backend cuda" "$work/logs/devices.txt"; then
  have_cuda=1
  gpu_name=$(sed -n 's/^default for --backend cuda: device 0 (\(.*\))$/\1/p' "$work/logs/devices.txt")
  if command -v nvidia-smi >/dev/null; then
    gpu_driver=$(nvidia-smi --query-gpu=driver_version --format=csv,noheader 2>/dev/null | head -1)
  fi
  log "raymap device kit: CUDA device 0: ${gpu_name:-unnamed}${gpu_driver:+, driver $gpu_driver}"
else
  why=$(sed -n '/^CUDA/,$p' "$work/logs/devices.txt" | grep -m1 'none:' | sed 's/^ *none: //')
  log "raymap device kit: no CUDA device (${why:-see devices.txt}): the CUDA parts are skipped, the CPU parts run"
fi
grep -q "default for --backend opencl" "$work/logs/devices.txt" && have_opencl=1
log "kit $(kit_field commit), $cpu_model, $(nproc) cores, budget $budget s, results in $out"

# The synthetic scene (the yard, driven through by a 32 x 1024 lidar) is simulated in the
# background while the tests run: 500 scans = 16.4 M rays on a GPU machine, 20 without.
scans=${RAYMAP_KIT_SCANS:-$([ "$have_cuda" = 1 ] && echo 500 || echo 20)}
synthetic=$work/synthetic.ply
if wanted bench || wanted heightmap; then
  ("$bin/raymap" simulate "$kit/config/scenes/yard.yaml" --rays "$synthetic.part" --scans "$scans" \
    -q >"$work/logs/simulate.log" 2>&1 && mv "$synthetic.part" "$synthetic") &
  synthetic_pid=$!
  background_pids+=("$synthetic_pid")
fi
# wait_synthetic: the scene file, once simulated; false (with a failure) if that failed.
wait_synthetic() {
  # (Sections run in subshells, which cannot wait for the main shell's jobs: poll.)
  while [ ! -f "$synthetic" ] && kill -0 "$synthetic_pid" 2>/dev/null; do
    sleep 0.5
  done
  if [ ! -f "$synthetic" ]; then
    fail "raymap simulate (synthetic scene) failed: $(tail -3 "$work/logs/simulate.log" | tr '\n' ' ')"
    return 1
  fi
}

# Each section runs in a subshell (what it records goes to files), so that a fault in the
# runner itself stops that section with a failure instead of ending the run quietly.
for section in "${all_sections[@]}"; do
  wanted "$section" || continue
  log "== $section"
  section_start=$SECONDS
  (set -u; "section_$section")
  section_rc=$?
  [ "$section_rc" = 0 ] || fail "section $section stopped with exit $section_rc (a fault of run.sh; see run.log)"
  log "   $section: $((SECONDS - section_start)) s"
  publish_results
done

publish_results
log "results: $(run_status) ($out/results.md)"
cat "$out/results.md"
if [ -s "$work/failures" ]; then
  exit 1
fi
[ "$have_cuda" = 1 ] && exit 0
exit 77
