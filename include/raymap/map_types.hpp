// SPDX-License-Identifier: BSD-3-Clause
// The kinds of map raymap builds and what a voxel can be: shared by the public API and the
// library's internals (one definition).
#pragma once

#include <cstdint>

namespace raymap {

/// @brief What a map models in each voxel.
enum class MapMode : std::uint8_t {
  kOccupancy = 0,  ///< log-odds occupancy (and the voxel mean)
  kNdtOm = 1,      ///< NDT-OM: occupancy whose misses are shaped by a Gaussian of the samples
  kNdtTm = 2,      ///< NDT-TM: NDT-OM plus hit/miss counts (permeability) and intensity statistics
  kTsdf = 3,       ///< truncated signed distance field only (no occupancy layer)
};

/// @brief How rays of one scan combine.
enum class Semantics : std::uint8_t {
  kPerRay = 0,   ///< every ray updates every voxel it crosses (OHM, OctoMap insertRay)
  kPerScan = 1,  ///< each voxel at most once per scan, occupied wins (OctoMap insertPointCloud)
};

/// @brief Occupancy state of a voxel: unobserved (no ray reached it, or outside the stored
/// map), free (log-odds below the threshold) or occupied (at or above it).
enum class VoxelState : std::uint8_t { kUnobserved, kFree, kOccupied };

}  // namespace raymap
