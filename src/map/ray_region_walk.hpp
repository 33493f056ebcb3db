// SPDX-License-Identifier: BSD-3-Clause
// Splits a prepared ray into the pieces that lie in each region it crosses, in walk order.
#pragma once

#include <cstdint>
#include <utility>

#include "kernels/common/line_walk.h"
#include "kernels/common/ray.h"
#include "kernels/common/region_walk.h"
#include "src/core/vec3.hpp"

namespace raymap {

/// @brief The part of a ray inside one region.
struct RaySpan {
  Vec3i region;       ///< global region coordinate
  float t0 = 0.0f;    ///< ray parameter where the ray enters the region (0 at the walk start)
  float t1 = 1.0f;    ///< ray parameter where it leaves
  rm_vec3i box_lo{};  ///< the region's voxels, relative to the walk's start voxel (inclusive)
  rm_vec3i box_hi{};
  bool first = false;  ///< holds the walk's start voxel
  bool last = false;   ///< holds the walk's end voxel
};

/// @brief Coarse walk over the regions a ray crosses: the same line walk as for voxels, in region
/// units (a region is N voxels), so region faces are exactly voxel faces. The walk itself is
/// kernels/common/region_walk.h, which the device planner's kernels run too; this class adds the
/// voxel-level constants the CPU walks spans with.
/// Value type; O(regions crossed); allocation-free and noexcept (real-time safe).
class RayRegionWalk {
 public:
  RayRegionWalk(const rm_prepared_ray& ray, std::int32_t region_voxels) noexcept
      : walk_(rm_region_walk_make(ray, region_voxels)),
        voxel_ray_(
            rm_line_walk_ray_make(walk_.frame.start, walk_.frame.end, walk_.frame.end_voxel)) {}

  const rm_ray_walk_frame& frame() const noexcept { return walk_.frame; }
  /// @brief The voxel-level constants of the ray, shared by all its spans.
  const rm_line_walk_ray& voxelRay() const noexcept { return voxel_ray_; }

  /// @brief Region and in-region index of the ray's sample voxel (the walk's end voxel, or its
  /// start voxel for a reverse walk), without a division.
  std::pair<Vec3i, std::uint32_t> sampleCell() const noexcept {
    rm_vec3i region;
    const std::uint32_t index = rm_region_walk_sample_cell(&walk_, &region);
    return {Vec3i{region.x, region.y, region.z}, index};
  }

  /// @brief A region's first voxel relative to a walk's start voxel (global key): RaySpan's
  /// box_lo, for callers that keep the region and the ray but not the span's box.
  static rm_vec3i boxLo(Vec3i region, rm_vec3i walk_start_voxel, std::int32_t n) noexcept {
    return rm_region_box_lo(rm_vec3i_make(region.x, region.y, region.z), walk_start_voxel, n);
  }

  /// @brief Regions the ray crosses (spans next() gives), inside a rolling window or not.
  std::uint32_t regionCount() const noexcept { return rm_region_walk_regions(&walk_); }

  /// @brief The next span; false when every region has been visited.
  bool next(RaySpan* span) noexcept {
    rm_region_span s;
    if (rm_region_walk_next(&walk_, &s) == 0) {
      return false;
    }
    span->region = Vec3i{s.region.x, s.region.y, s.region.z};
    span->t0 = s.t0;
    span->t1 = s.t1;
    span->first = (s.flags & RM_SPAN_FIRST) != 0u;
    span->last = (s.flags & RM_SPAN_LAST) != 0u;
    span->box_lo = s.box_lo;
    const std::int32_t n = walk_.n;
    span->box_hi = rm_vec3i_make(s.box_lo.x + n - 1, s.box_lo.y + n - 1, s.box_lo.z + n - 1);
    return true;
  }

 private:
  rm_region_walk walk_;
  rm_line_walk_ray voxel_ray_;
};

}  // namespace raymap
