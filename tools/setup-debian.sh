#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Installs what raymap needs to build and test on Debian 12, from Debian packages only.
set -euo pipefail
packages=(
  cmake ninja-build g++ pkg-config
  zlib1g-dev libzstd-dev libpng-dev libeigen3-dev  # the map library: gzip, map files, cold tiers, PNG height maps; host geometry and the public API
  libcli11-dev libyaml-cpp-dev
  nlohmann-json3-dev      # the JSON the command line and benchmarks print and the tests read (header-only)
  libgtest-dev libgmock-dev libbenchmark-dev
  liboctomap-dev          # OctoMap: the reference in benchmarks and agreement tests only
  ocl-icd-opencl-dev opencl-headers  # the OpenCL backend (ICD loader and headers)
  pocl-opencl-icd clinfo  # OpenCL on the CPU: the OpenCL tests run for real without a GPU
  cyclonedds-dev cyclonedds-tools  # raymapd's DDS I/O (C API; idlc is in -tools)
  libfastrtps-dev fastddsgen  # Fast DDS 2.9 and its type generator: the tests' independent peer
  iproute2                # ip netns: the multicast discovery test between two network namespaces
  libsystemd-dev systemd  # sd_notify for Type=notify; systemd-analyze lints the unit in the tests
  libboost-dev            # Boost.Lockfree SPSC queues (header-only)
  libssl-dev openssl      # DDS Security: keystores (raymap security), checks of enclave files
  tcpdump                 # the security tests capture loopback traffic to prove it is encrypted
  liblz4-dev libsqlite3-dev  # rosbag2: compressed MCAP chunks (zstd: above), SQLite (.db3) bags
  clang-format
  universal-ctags         # tests/lint/check_function_length.sh: where each function ends
  clang libclang-rt-14-dev clang-tidy  # the asan/tsan/fuzz presets (libFuzzer), clang-tidy
  patchelf                # tools/device-kit.sh: the kit's executables find its own libraries
  dpkg-dev file           # cpack -G DEB: dpkg-shlibdeps computes Depends: (tools/check-deb.sh)
  pybind11-dev python3-dev python3-numpy python3-pytest  # `import raymap` (python/) and its tests
)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi
sudo=""
if [ "$(id -u)" -ne 0 ]; then
  sudo="sudo"
fi
echo "setup: installing ${missing[*]}"
$sudo apt-get update -qq
DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq "${missing[@]}" >/dev/null
