// SPDX-License-Identifier: BSD-3-Clause
// A global map's region pool sized to the machine (see pool_fit.hpp).
#include "src/mapper/pool_fit.hpp"

#include <algorithm>
#include <cstdint>

#include "platform/memory.hpp"

namespace raymap::mapper {

std::string fitPoolToMemory(MapConfig& map) {
  if (map.policy != StorePolicy::kGlobal) {
    return {};
  }
  const std::uint32_t voxels = map.geometry.voxelsPerRegion();
  const std::uint64_t per_region = map.schema().bytesPerRegion(voxels);
  const std::uint64_t at_creation =
      std::max<std::uint64_t>(map.schema().bytesWrittenAtCreation(voxels), 4096);
  const platform::MemoryLimit limit = platform::availableMemory();
  if (per_region == 0 || limit.bytes == UINT64_MAX) {
    return {};
  }
  // Address space limits (RLIMIT_AS) count the whole pool, written or not, and everything else
  // the process maps (a quarter is left for that).
  const bool address_space = limit.source.find("RLIMIT_AS") != std::string::npos;
  const std::uint64_t usable = std::max<std::uint64_t>(
      address_space ? limit.bytes / 4 * 3 / per_region : limit.bytes / at_creation, 1);
  if (map.capacityRegions() <= usable) {
    return {};
  }
  const std::uint64_t asked = map.capacityRegions();
  map.memory_budget_bytes = usable * per_region;
  const auto mib = [](std::uint64_t bytes) { return std::to_string(bytes >> 20) + " MiB"; };
  return "map.max_memory asks for " + std::to_string(asked) + " regions; this machine can hold " +
         std::to_string(usable) + " (" + mib(limit.bytes) + " available by " + limit.source +
         ", each region takes " + std::to_string((address_space ? per_region : at_creation) >> 10) +
         (address_space ? " KiB of address space" : " KiB when created") +
         "): the map is sized for those";
}

}  // namespace raymap::mapper
