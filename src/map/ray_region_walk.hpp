// SPDX-License-Identifier: BSD-3-Clause
// Splits a prepared ray into the pieces that lie in each region it crosses, in walk order.
#pragma once

#include <cstdint>
#include <utility>

#include "kernels/common/key_math.h"
#include "kernels/common/line_walk.h"
#include "kernels/common/ray.h"
#include "src/core/vec3.hpp"

namespace raymap {

/// @brief The part of a ray inside one region.
struct RaySpan {
  Vec3i region;     ///< global region coordinate
  float t0 = 0.0f;  ///< ray parameter where the ray enters the region (0 at the walk start)
  float t1 = 1.0f;  ///< ray parameter where it leaves
  rm_vec3i box_lo;  ///< the region's voxels, relative to the walk's start voxel (inclusive)
  rm_vec3i box_hi;
  bool first = false;  ///< holds the walk's start voxel
  bool last = false;   ///< holds the walk's end voxel
};

/// @brief Coarse walk over the regions a ray crosses: the same line walk as for voxels, in region
/// units (a region is N voxels), so region faces are exactly voxel faces.
/// Value type; O(regions crossed); allocation-free and noexcept (real-time safe).
class RayRegionWalk {
 public:
  RayRegionWalk(const rm_prepared_ray& ray, std::int32_t region_voxels) noexcept
      : frame_(rm_ray_walk_frame_make(ray)),
        voxel_ray_(rm_line_walk_ray_make(frame_.start, frame_.end, frame_.end_voxel)),
        n_(region_voxels) {
    start_region_ = rm_region_of_voxel(frame_.start_voxel, n_);
    start_local_ = rm_local_in_region(frame_.start_voxel, start_region_, n_);
    const rm_vec3i end_global = rm_vec3i_make(frame_.start_voxel.x + frame_.end_voxel.x,
                                              frame_.start_voxel.y + frame_.end_voxel.y,
                                              frame_.start_voxel.z + frame_.end_voxel.z);
    end_region_ = rm_region_of_voxel(end_global, n_);
    const rm_vec3i end_region = end_region_;
    const float inv_n = 1.0f / static_cast<float>(n_);
    const rm_vec3f region_start =
        rm_vec3f_make((static_cast<float>(start_local_.x) + frame_.start.x) * inv_n,
                      (static_cast<float>(start_local_.y) + frame_.start.y) * inv_n,
                      (static_cast<float>(start_local_.z) + frame_.start.z) * inv_n);
    const rm_vec3f region_end =
        rm_vec3f_make((static_cast<float>(start_local_.x) + frame_.end.x) * inv_n,
                      (static_cast<float>(start_local_.y) + frame_.end.y) * inv_n,
                      (static_cast<float>(start_local_.z) + frame_.end.z) * inv_n);
    rm_line_walk_init(&walk_, region_start, region_end,
                      rm_vec3i_make(end_region.x - start_region_.x, end_region.y - start_region_.y,
                                    end_region.z - start_region_.z));
  }

  const rm_ray_walk_frame& frame() const noexcept { return frame_; }
  /// @brief The voxel-level constants of the ray, shared by all its spans.
  const rm_line_walk_ray& voxelRay() const noexcept { return voxel_ray_; }

  /// @brief Region and in-region index of the ray's sample voxel (the walk's end voxel, or its
  /// start voxel for a reverse walk), without a division.
  std::pair<Vec3i, std::uint32_t> sampleCell() const noexcept {
    if (frame_.sample_is_start != 0) {
      return {Vec3i{start_region_.x, start_region_.y, start_region_.z},
              rm_local_index(start_local_, n_)};
    }
    const rm_vec3i local =
        rm_vec3i_make(start_local_.x + frame_.end_voxel.x - (end_region_.x - start_region_.x) * n_,
                      start_local_.y + frame_.end_voxel.y - (end_region_.y - start_region_.y) * n_,
                      start_local_.z + frame_.end_voxel.z - (end_region_.z - start_region_.z) * n_);
    return {Vec3i{end_region_.x, end_region_.y, end_region_.z}, rm_local_index(local, n_)};
  }

  /// @brief A region's first voxel relative to a walk's start voxel (global key): RaySpan's
  /// box_lo, for callers that keep the region and the ray but not the span's box.
  static rm_vec3i boxLo(Vec3i region, rm_vec3i walk_start_voxel, std::int32_t n) noexcept {
    return rm_vec3i_make(region.x * n - walk_start_voxel.x, region.y * n - walk_start_voxel.y,
                         region.z * n - walk_start_voxel.z);
  }

  /// @brief The next span; false when every region has been visited.
  bool next(RaySpan* span) noexcept {
    if (done_) {
      return false;
    }
    if (started_ && rm_line_walk_next(&walk_) < 0) {
      done_ = true;
      return false;
    }
    span->first = !started_;
    started_ = true;
    span->region =
        Vec3i{start_region_.x + walk_.x, start_region_.y + walk_.y, start_region_.z + walk_.z};
    span->t0 = rm_line_walk_t_enter(&walk_);
    span->t1 = rm_line_walk_t_exit(&walk_);
    span->last = walk_.steps_left == 0;
    span->box_lo = boxLo(span->region, frame_.start_voxel, n_);
    span->box_hi =
        rm_vec3i_make(span->box_lo.x + n_ - 1, span->box_lo.y + n_ - 1, span->box_lo.z + n_ - 1);
    return true;
  }

 private:
  rm_ray_walk_frame frame_;
  rm_line_walk_ray voxel_ray_;
  std::int32_t n_;
  rm_vec3i start_region_;
  rm_vec3i start_local_;
  rm_vec3i end_region_;
  rm_line_walk walk_;
  bool started_ = false;
  bool done_ = false;
};

}  // namespace raymap
