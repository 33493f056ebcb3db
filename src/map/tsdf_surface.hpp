// SPDX-License-Identifier: BSD-3-Clause
// The surface of a TSDF map: its zero crossings between neighbouring voxels, as points.
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include "src/core/vec3.hpp"
#include "src/map/voxel_map.hpp"

namespace raymap {

/// @brief One zero crossing of the signed distance, world frame.
struct TsdfSurfacePoint {
  Vec3d p_world;        ///< metres, on the segment between the two voxel centres
  float weight = 0.0f;  ///< the smaller weight of the two voxels
  /// Unit vector along the distance gradient between the two voxels (the axis they share,
  /// pointing from the negative to the positive side: out of the surface, towards the sensor).
  Vec3d normal;
};

/// @brief True when a voxel takes part in the surface: updated (weight > 0) and at least
/// min_weight heavy.
inline bool tsdfVoxelUsable(const rm_tsdf_voxel& v, float min_weight) noexcept {
  return v.weight > 0.0f && v.weight >= min_weight;
}

/// @brief True when two neighbouring voxels' distances (metres) have a zero crossing between them
/// that is a measured surface: opposite signs (d >= 0 on one side, d < 0 on the other), both
/// inside the truncation band (|d| < tau; a jump from +tau to -tau is no measured surface).
inline bool tsdfMeasuredCrossing(float a, float b, float tau) noexcept {
  return (a >= 0.0f) != (b >= 0.0f) && std::fabs(a) < tau && std::fabs(b) < tau;
}

/// @brief Zero crossings of a TSDF map: for every pair of face-adjacent voxels both with weight
/// >= min_weight, both distances inside the truncation band (|d| < tau: a jump from +tau to -tau
/// is no measured surface), and of opposite signs (d >= 0 on one, d < 0 on the other), the point
/// where the linear interpolation of the distance between their centres is zero. Each pair is
/// reported once, in region order (z, y, x), so the output is deterministic.
/// @pre map has a TSDF layer (VoxelMap::tsdfLayer() >= 0). Thread-safety: const; may run
/// alongside other const queries. @rt allocates: yes (offline tool).
std::vector<TsdfSurfacePoint> tsdfZeroCrossings(const VoxelMap& map, float min_weight);

/// @brief Counts of a TSDF map's voxels.
struct TsdfSummary {
  std::uint64_t updated = 0;    ///< weight > 0
  std::uint64_t behind = 0;     ///< of those: distance < 0 (behind / inside the surface)
  std::uint64_t saturated = 0;  ///< of those: weight at the maximum
};
/// @brief Counts over all stored regions (all zero without a TSDF layer). Const; @rt no.
TsdfSummary summariseTsdf(const VoxelMap& map);

}  // namespace raymap
