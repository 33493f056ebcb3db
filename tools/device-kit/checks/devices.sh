# SPDX-License-Identifier: BSD-3-Clause
# Section "devices" of the device kit (sourced by run.sh): what raymap sees on this machine, and
# proof that every executable of the kit starts here with the kit's libraries alone.

section_devices() {
  md devices "## Devices" "" '```' "$(cat "$work/logs/devices.txt")" '```'
  record devices "{\"cuda\": $have_cuda, \"opencl\": $have_opencl, \"gpu\": $(json_string "$gpu_name"), \"listing\": $(json_string "$(cat "$work/logs/devices.txt")")}"
  "$bin/raymap" devices --json >"$work/logs/devices.json" 2>&1
  if command -v nvidia-smi >/dev/null; then
    # The card as found (clocks, power, other processes): leads for reading the timings.
    nvidia-smi >"$work/logs/nvidia-smi.txt" 2>&1
    local card
    card=$(nvidia-smi --query-gpu=name,driver_version,memory.total,clocks.sm,clocks.max.sm,power.limit,temperature.gpu \
      --format=csv 2>&1)
    md devices "" "nvidia-smi at the start:" "" '```' "$card" '```'
    record devices "{\"nvidia_smi\": $(json_string "$card")}"
  fi
  if grep -q "error while loading shared libraries" "$work/logs/devices.txt"; then
    fail "raymap does not start: $(head -1 "$work/logs/devices.txt")"
  fi
  local exe rc started_ok=0 total=0
  for exe in "$bin"/*; do
    total=$((total + 1))
    case $(basename "$exe") in
      test_*) "$exe" --gtest_list_tests >"$work/logs/start-$(basename "$exe").log" 2>&1 ;;
      *) "$exe" --help >"$work/logs/start-$(basename "$exe").log" 2>&1 ;;
    esac
    rc=$?
    if [ "$rc" = 0 ]; then
      started_ok=$((started_ok + 1))
    else
      fail "$(basename "$exe") does not start (exit $rc): $(head -2 "$work/logs/start-$(basename "$exe").log" | tr '\n' ' ')"
    fi
  done
  md devices "" "Executables that start with the kit's libraries alone: $started_ok of $total."
  record devices "{\"executables\": $total, \"started\": $started_ok}"
}
