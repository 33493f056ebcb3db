// SPDX-License-Identifier: BSD-3-Clause
// Comparing two maps a device integrated from the same rays (planning and preparation on the host
// against on the device): which regions differ, and when they must not.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <string>

#include "src/map/backend.hpp"
#include "src/map/voxel_map.hpp"

namespace raymap::test {

/// Regions whose layers differ in any byte between the maps, or that only one holds.
inline std::uint64_t differingRegions(const VoxelMap& a, const VoxelMap& b) {
  std::uint64_t differing = 0;
  std::uint64_t seen = 0;
  a.store().forEachRegion([&](std::uint32_t slot_a, Vec3i region) {
    ++seen;
    const std::uint32_t slot_b = b.store().find(region);
    if (slot_b == RegionStore::kNoSlot) {
      ++differing;
      return;
    }
    for (int l = 0; l < a.store().schema().size(); ++l) {
      const std::size_t bytes = a.store().layerRegionBytes(l);
      if (bytes != 0 && std::memcmp(a.store().layerBytes(slot_a, l),
                                    b.store().layerBytes(slot_b, l), bytes) != 0) {
        ++differing;
        return;
      }
    }
  });
  return differing + (b.store().size() - std::min<std::uint64_t>(seen, b.store().size()));
}

/// Whether maps `backend` integrated into `map` from the same rays and plans must agree bit for
/// bit: where each voxel has one writer (span work per region, as on PoCL) or its updates commute
/// (plain occupancy). Elsewhere float additions of several work-items (decay rates, TSDF, NDT
/// misses) land in the device's order, and so round its way.
inline bool mapsAgreeBitForBit(const VoxelMap& map, const Backend& backend) {
  const bool one_writer = backend.deviceName().find("span work per region") != std::string::npos;
  const bool commuting =
      map.mode() == MapMode::kOccupancy && map.occupancyLayer() >= 0 && map.traversalLayer() < 0;
  return one_writer || commuting;
}

}  // namespace raymap::test
