# SPDX-License-Identifier: BSD-3-Clause
# Section "tests" of the device kit (sourced by run.sh): the CUDA unit tests, the device-backend
# tests (tests/device, the suite that runs on PoCL in CI), the agreement with the CPU reference
# on the kit's real data, and the height-map tests (every generator against a reference written
# from the specification). Executables run in GoogleTest shards side by side; the compute
# sanitizer's runs (section "sanitizer") overlap them when both sections run.

# The runs: a label, the executable, its shards, and an environment for it ("-": none). The device
# suite runs three times: as it is, with every batch planned on the device (issue 51), and the
# suites with a shared-memory variant with the host map mapped into the discrete GPU (the code
# path of a Jetson, whose GPU shares the host's memory).
kit_shared_memory_tests="*SharedMemory*:*DeviceMemoryMode*:DeviceBackend.Agrees*:*DeviceNdt.*:*DeviceDecay*:DeviceTsdf.*:*DeviceHeightmap*:DevicePlanning.RegionsOutside*"
kit_tests=("test_unit_cuda test_unit_cuda 1 -" "test_cuda_device test_cuda_device 2 -"
  "test_cuda_device+device_planning test_cuda_device 2 RAYMAP_TEST_DEVICE_PLANNING=device"
  "test_cuda_device+mapped_host_memory test_cuda_device 1 RAYMAP_TEST_CUDA_MAPPED=1"
  "test_cuda_data test_cuda_data 4 -" "test_heightmap test_heightmap 4 -" "test_unit_mapper test_unit_mapper 1 -")

section_tests() {
  local sanitizing=0
  if wanted sanitizer; then
    sanitizer_start && sanitizing=1
  fi
  md tests "## Tests" "" "| executable | result | tests | failed | skipped | seconds |" \
    "| --- | --- | ---: | ---: | ---: | ---: |"
  local entry label exe shards env i pids=()
  for entry in "${kit_tests[@]}"; do
    read -r label exe shards env <<<"$entry"
    local filter=()
    [ "$label" = test_cuda_device+mapped_host_memory ] && filter=(--gtest_filter="$kit_shared_memory_tests")
    [ "$env" = - ] && env=RAYMAP_KIT_TESTS=1
    for ((i = 0; i < shards; i++)); do
      (
        t0=$SECONDS
        env "$env" GTEST_TOTAL_SHARDS=$shards GTEST_SHARD_INDEX=$i timeout 180 "$bin/$exe" \
          "${filter[@]}" --gtest_output="json:$work/logs/$label.$i.json" \
          >"$work/logs/$label.$i.log" 2>&1
        echo "$? $((SECONDS - t0))" >"$work/$label.$i.rc"
      ) &
      pids+=($!)
    done
  done
  wait "${pids[@]}"
  for entry in "${kit_tests[@]}"; do
    read -r label exe shards env <<<"$entry"
    tests_record "$label" "$shards"
  done
  local line
  if grep -qh '^\[device-agreement\]' "$work"/logs/test_cuda_data.*.log 2>/dev/null; then
    md tests "" "Agreement with the CPU reference on the kit's data (0.1 m, 20 m, OctoMap's probabilities):" ""
    grep -h '^\[device-agreement\]' "$work"/logs/test_cuda_data.*.log | sort | while IFS= read -r line; do
      md tests "- ${line#\[device-agreement\] }"
      record agreement "{\"line\": $(json_string "${line#\[device-agreement\] }")}"
    done
  fi
  if [ "$sanitizing" = 1 ]; then
    sanitizer_finish
  fi
}

# tests_record EXE SHARDS: one row for an executable's shards together.
tests_record() {
  local exe=$1 shards=$2 i rc secs tests=0 failed=0 skipped=0 seconds=0 result=passed
  local rcs=""
  for ((i = 0; i < shards; i++)); do
    read -r rc secs <"$work/$exe.$i.rc" 2>/dev/null || { rc=127; secs=0; }
    rcs+="$rc "
    [ "$secs" -gt "$seconds" ] && seconds=$secs
    local json=$work/logs/$exe.$i.json
    tests=$((tests + $(number tests "$json")))
    failed=$((failed + $(number failures "$json")))
    if [ -f "$json" ]; then
      skipped=$((skipped + $(grep -c '"result": "SKIPPED"' "$json")))
    fi
    case $rc in
      0) ;;
      77)
        [ "$result" = passed ] && result="skipped"
        if [ "$have_cuda" = 1 ]; then
          result=failed
          fail "$exe shard $i skipped itself on a machine with a CUDA device: $(head -1 "$work/logs/$exe.$i.log")"
        fi
        ;;
      124)
        result=failed
        fail "$exe shard $i ran out of time (180 s)"
        ;;
      *)
        result=failed
        fail "$exe shard $i failed (exit $rc): $(grep -h '^\[  FAILED  \]' "$work/logs/$exe.$i.log" | sed 's/^\[  FAILED  \] //' | sort -u | head -8 | tr '\n' ';')"
        ;;
    esac
  done
  if [ "$result" = skipped ]; then
    result="skipped: $(sed -n 's/^skipped: //p' "$work/logs/$exe.0.log" | head -1)"
  fi
  md tests "| $exe | $result | $tests | $failed | $skipped | $seconds |"
  record tests "{\"executable\": \"$exe\", \"result\": $(json_string "$result"), \"exit_codes\": $(json_string "${rcs% }"), \"tests\": $tests, \"failed\": $failed, \"skipped\": $skipped, \"seconds\": $seconds}"
}
