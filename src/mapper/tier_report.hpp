// SPDX-License-Identifier: BSD-3-Clause
// Where a map larger than memory keeps its regions at the end of a job (docs/large-maps.md).
#pragma once

#include <cstdint>
#include <optional>

#include "raymap/error.hpp"

#include "src/map/voxel_map.hpp"

namespace raymap::mapper {

/// @brief Where a tiered map's regions are. Value type.
struct TierReport {
  std::uint32_t pool_regions = 0;  ///< the pool's capacity
  std::uint32_t hot_regions = 0;   ///< regions in the pool
  RegionTierStats stats;
  /// Batches the backend cut in two because their regions did not fit the pool at once
  /// (BackendStats::batches_split; integrateRays fills it in).
  std::uint64_t batches_split = 0;
};

/// @brief The report of a tiered map; nullopt without tiers. Not thread-safe against a job
/// writing the map.
std::optional<TierReport> tierReport(const VoxelMap& map);

/// @brief Fails with the tiers' error when a tiered map lost a region on the way (a query or a
/// summary that met a damaged spill file): a job must not report success then.
Expected<void, Error> checkTiers(const VoxelMap& map);

}  // namespace raymap::mapper
