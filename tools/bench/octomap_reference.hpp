// SPDX-License-Identifier: BSD-3-Clause
// OctoMap as a reference mapper: the same rays integrated with OctoMap's own insertRay (per-ray)
// or insertPointCloud (per-scan), for benchmarks and agreement tests. Not part of raymap itself.
#pragma once

#include <cstdint>
#include <memory>
#include <span>

#include "src/core/vec3.hpp"
#include "src/map/map_params.hpp"
#include "src/map/ray.hpp"
#include "src/map/voxel_map.hpp"

namespace raymap::bench {

/// @brief Parameters, as raymap names them; probabilities in log-odds.
struct OctomapOptions {
  double resolution = 0.1;
  double min_range_m = 0.0;
  double max_range_m = 0.0;  ///< 0 = none (OctoMap's -1)
  OccupancyParams occupancy = OccupancyParams::octomap();
  Semantics semantics = Semantics::kPerRay;
};

/// @brief Counters and timing with the meaning of raymap's stats JSON.
struct OctomapCounts {
  std::uint64_t rays_in = 0;
  std::uint64_t rays_integrated = 0;
  std::uint64_t rays_rejected = 0;           ///< NaN/Inf or shorter than min range
  std::uint64_t rays_skipped_no_return = 0;  ///< per-scan: insertPointCloud has no free-only rays
  double integrate_seconds = 0.0;            ///< time inside OctoMap's insert calls
  std::uint64_t voxels_free = 0;
  std::uint64_t voxels_occupied = 0;
};

/// @brief Agreement of two maps, voxel by voxel, over voxels observed in either.
struct Agreement {
  std::uint64_t compared = 0;
  std::uint64_t same = 0;
  std::uint64_t only_raymap = 0;   ///< observed by raymap only
  std::uint64_t only_octomap = 0;  ///< observed by OctoMap only
  double fraction() const {
    return compared ? static_cast<double>(same) / static_cast<double>(compared) : 1.0;
  }
};

/// @brief An OctoMap OcTree fed ray by ray (per-ray) or scan by scan (per-scan).
/// Per-scan input must arrive as whole scans, in order (runs of equal Ray::scan); rays of a scan
/// are grouped by origin, since insertPointCloud takes one sensor origin per cloud.
class OctomapReference {
 public:
  explicit OctomapReference(const OctomapOptions& options);
  ~OctomapReference();
  OctomapReference(const OctomapReference&) = delete;
  OctomapReference& operator=(const OctomapReference&) = delete;

  /// @brief Integrates rays (per-scan: exactly one scan).
  void integrate(std::span<const Ray> rays);
  /// @brief Counts leaves (pruned leaves count as the voxels they cover).
  OctomapCounts counts() const;
  /// @brief Compares with a raymap map of the same resolution (voxel faces coincide).
  Agreement compare(const VoxelMap& map) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace raymap::bench
