# SPDX-License-Identifier: BSD-3-Clause
# Section "profile" of the device kit (sourced by run.sh): what limits the CUDA integration, from
# Nsight Compute's hardware counters (ncu, where the machine has it and lets it read them): the
# speed-of-light, launch and occupancy sections of the first launches of each integration kernel
# during an occupancy and an NDT-OM integration of the synthetic scene's first 20 scans. Clocks
# are left as the card runs them (--clock-control none). Runs last and only with time to spare.

# find_ncu: ncu's path, from PATH or the usual places.
find_ncu() {
  local c
  for c in "$(command -v ncu 2>/dev/null)" /usr/local/cuda/bin/ncu /opt/nvidia/nsight-compute/*/ncu; do
    [ -n "$c" ] && [ -x "$c" ] && { echo "$c"; return 0; }
  done
  return 1
}

section_profile() {
  md profile "## Nsight Compute (what limits the kernels)" ""
  if [ "$have_cuda" != 1 ]; then
    md profile "Skipped: no CUDA device."
    return 0
  fi
  local ncu
  if ! ncu=$(find_ncu); then
    md profile "Skipped: ncu is not installed here."
    note "profile: ncu not installed; skipped"
    return 0
  fi
  if [ "$(remaining)" -lt 40 ]; then
    md profile "Skipped: out of time."
    note "profile: skipped, out of time"
    return 0
  fi
  "$bin/raymap" simulate "$kit/config/scenes/yard.yaml" --rays "$work/profile.ply" --scans 20 -q \
    >"$work/logs/profile-simulate.log" 2>&1 || { fail "profile: raymap simulate failed"; return 0; }
  local mode
  for mode in occupancy ndt-om; do
    [ "$(remaining)" -ge 20 ] || { note "profile: $mode skipped, out of time"; continue; }
    # The integration kernels only (not the cache fills), past the first batches' warm-up.
    timeout "$(($(remaining) - 5))" "$ncu" --clock-control none \
      --kernel-name "regex:^rm_(ndt_)?(tag|integrate|apply)" --launch-skip 3 --launch-count 6 \
      --section SpeedOfLight --section LaunchStats --section Occupancy \
      --section MemoryWorkloadAnalysis "$bin/raymap" bench "$work/profile.ply" --backend cuda \
      --mode "$mode" --semantics-list ray --repeat 1 --resolution 0.1 --max-range 20 \
      --json "$work/logs/profile-$mode-bench.json" >"$work/logs/profile-$mode.txt" 2>&1
    local rc=$?
    if [ "$rc" != 0 ]; then
      md profile "ncu on $mode: exit $rc ($(grep -m2 -i 'error\|==ERROR==\|==WARNING==' "$work/logs/profile-$mode.txt" | tr '\n' ' '))"
      note "profile: ncu on $mode exited $rc"
      continue
    fi
    md profile "### $mode" "" '```'
    # Per kernel: its name line, then the rows that say where the time goes.
    grep -E '^  rm_|^    (Duration|Compute \(SM\) Throughput|Memory Throughput|DRAM Throughput|L1/TEX Hit Rate|L2 Hit Rate|Registers Per Thread|Achieved Occupancy|Theoretical Occupancy|Block Limit Registers|Grid Size|Block Size|Elapsed Cycles)' \
      "$work/logs/profile-$mode.txt" | head -90 >>"$work/md/profile.md"
    md profile '```'
  done
}
