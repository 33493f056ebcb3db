// SPDX-License-Identifier: BSD-3-Clause
// The CUDA devices of this machine, through the CUDA runtime API only (linked statically; the
// NVIDIA driver is opened at run time), so a binary built with CUDA starts on machines without
// the driver and says so. No CUDA type appears in this header.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "raymap/error.hpp"

namespace raymap::cuda {

/// @brief What raymap needs to know about one CUDA device (value type).
struct DeviceInfo {
  int index = 0;  ///< CUDA device ordinal (after CUDA_VISIBLE_DEVICES)
  std::string name;
  int compute_major = 0;  ///< compute capability, e.g. 8.7 for Orin, 9.0 for Hopper
  int compute_minor = 0;
  std::uint32_t multiprocessors = 0;
  std::uint64_t global_mem_bytes = 0;
  bool integrated = false;           ///< shares memory with the host (Jetson)
  bool can_map_host_memory = false;  ///< can address mapped page-locked host memory
  std::string pci_bus_id;            ///< "0000:01:00.0"; empty on Jetson
  int runtime_version = 0;           ///< CUDA runtime linked into raymap, e.g. 13000
  int driver_version = 0;            ///< highest CUDA version the driver supports
};

/// @brief Every CUDA device. Fails with a clear message when the NVIDIA driver is missing or too
/// old for the runtime raymap was built with, or when the driver finds no device.
/// Thread-safety: safe to call from any thread.
Result<std::vector<DeviceInfo>> listDevices();

/// @brief The device with ordinal `index` (-1: device 0), or an error listing what exists.
Result<DeviceInfo> selectDevice(const std::vector<DeviceInfo>& devices, int index);

/// @brief listDevices() then selectDevice(): the device a `--cuda-device` option names.
Result<DeviceInfo> findDevice(int index);

/// @brief Checks a launch's threads per block: a multiple of 32 from 32 to 1024.
Expected<void, Error> checkBlockThreads(unsigned block_threads);

/// @brief "13.0" for 13000 (CUDA's version encoding).
std::string versionText(int version);

}  // namespace raymap::cuda
