// SPDX-License-Identifier: BSD-3-Clause
// Counts over a decay-rate map's voxels, for the tools' reports.
#pragma once

#include <cstdint>

#include "src/map/voxel_map.hpp"

namespace raymap {

/// @brief Counts of the voxels of a map with the traversal layer (kernels/common/decay.h).
struct DecaySummary {
  std::uint64_t crossed = 0;       ///< voxels with ray path inside them (traversal > 0)
  std::uint64_t with_samples = 0;  ///< of those: with at least one sample (rate > 0)
  double metres = 0.0;             ///< total ray path over all voxels, metres
  std::uint64_t samples = 0;       ///< total samples in the crossed voxels
};

/// @brief Counts over all regions in every tier (all zero without the traversal or voxel-mean
/// layer; on a tiered map a region that cannot be read back is left out, see tierFailure()).
/// Thread-safety: as the map's queries. @rt allocates: on a tiered map.
DecaySummary summariseDecay(const VoxelMap& map);

}  // namespace raymap
