// SPDX-License-Identifier: BSD-3-Clause
// Ray preparation.
#include "src/map/ray_preparer.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "kernels/common/tsdf.h"

namespace raymap {
Expected<void, Error> RayFilter::validate() const {
  if (!std::isfinite(min_range_m) || min_range_m < 0.0) {
    return fail(ErrorCode::kInvalidArgument, "rays.min_range must be a distance >= 0 metres");
  }
  if (!std::isfinite(max_range_m) || max_range_m < 0.0) {
    return fail(ErrorCode::kInvalidArgument,
                "rays.max_range must be a distance >= 0 metres (0 = none)");
  }
  if (!std::isfinite(max_length_m) || max_length_m < 0.0) {
    return fail(ErrorCode::kInvalidArgument,
                "rays.max_ray_length must be a distance >= 0 metres (0 = none)");
  }
  if (max_length_m > 0.0 && max_length_m <= min_range_m) {
    return fail(ErrorCode::kInvalidArgument,
                "rays.max_ray_length must be larger than rays.min_range");
  }
  if (max_range_m > 0.0 && max_range_m <= min_range_m) {
    return fail(ErrorCode::kInvalidArgument, "rays.max_range must be larger than rays.min_range");
  }
  if (!std::isfinite(segment_length_m) || segment_length_m < 0.0) {
    return fail(ErrorCode::kInvalidArgument,
                "rays.segment_length must be a distance >= 0 metres (0 = off)");
  }
  return {};
}

RayPreparer::RayPreparer(const VoxelMap& map, const RayFilter& filter) noexcept
    : map_(&map),
      filter_(filter),
      inv_resolution_(1.0 / map.geometry().resolution),
      tsdf_(map.mode() == MapMode::kTsdf),
      truncation_m_(map.config().tsdf.truncationMetres(map.geometry().resolution)) {}

rm_prepare_params RayPreparer::params() const noexcept {
  rm_prepare_params p{};
  p.inv_resolution = inv_resolution_;
  p.min_range_m = filter_.min_range_m;
  p.max_range_m = filter_.max_range_m;
  p.max_length_m = filter_.max_length_m;
  p.truncation_m = truncation_m_;
  p.max_voxel = static_cast<double>(map_->maxVoxelCoord());
  p.tsdf = tsdf_ ? 1u : 0u;
  p.walk_flag = filter_.reverse ? RM_RAY_REVERSE : 0u;
  if (map_->config().policy == StorePolicy::kRolling) {
    // Clip half a voxel outside the window: a ray that leaves the window crosses its boundary
    // voxels completely, so they must be cleared; the end voxel, which is left out, and any
    // other voxel outside the window are skipped by the backend.
    const auto [lo, hi] = map_->windowBounds();
    const double margin = 0.5 * map_->geometry().resolution;
    p.rolling = 1u;
    p.window_lo = rm_vec3d{lo.x - margin, lo.y - margin, lo.z - margin};
    p.window_hi = rm_vec3d{hi.x + margin, hi.y + margin, hi.z + margin};
  }
  return p;
}

RayPreparer::Progress RayPreparer::prepareWith(const rm_prepare_params& params,
                                               std::span<const Ray> in, std::span<PreparedRay> out,
                                               RayCounters& counters) const noexcept {
  Progress progress;
  for (const Ray& ray : in) {
    // Zeroed: rm_prepare_ray fills it on every path that is read, which GCC at -O1 cannot see.
    rm_prepared_ends ends{};
    const rm_u32 outcome =
        rm_prepare_ray(&params, rm_vec3d{ray.origin.x, ray.origin.y, ray.origin.z},
                       rm_vec3d{ray.sample.x, ray.sample.y, ray.sample.z},
                       (ray.flags & kRayNoReturn) != 0u ? 1 : 0, &ends);
    if ((outcome & RM_PREPARE_REJECTED_MASK) != RM_PREPARE_ACCEPTED) {
      ++counters.rays_in;
      ++progress.consumed;
      countRejection(outcome, counters);
      continue;
    }
    const double kept = ends.kept_m;
    std::uint32_t pieces = 1;
    if (filter_.segment_length_m > 0.0 && kept > filter_.segment_length_m) {
      pieces = static_cast<std::uint32_t>(std::min<double>(
          std::ceil(kept / filter_.segment_length_m), RayFilter::kMaxPiecesPerRay));
    }
    if (progress.written + pieces > out.size()) {
      break;  // no room for this ray's pieces: the caller integrates and calls again
    }
    ++counters.rays_in;
    ++counters.rays_accepted;
    counters.rays_clipped += (outcome & RM_PREPARE_CLIPPED) != 0u ? 1u : 0u;
    counters.rays_no_return += (outcome & RM_PREPARE_NO_RETURN) != 0u ? 1u : 0u;
    counters.pieces_out += pieces;
    ++progress.consumed;
    if (pieces == 1) {
      out[progress.written++] = PreparedRay{ends.origin_voxel,
                                            ends.origin_local,
                                            ends.sample_voxel,
                                            ends.sample_local,
                                            ends.end_flag | params.walk_flag,
                                            ray.intensity,
                                            static_cast<float>(ends.end_sdf_m)};
      continue;
    }
    const rm_vec3d d = rm_vec3d_sub(ends.sample, ends.origin);
    rm_vec3i a_voxel = ends.origin_voxel;
    rm_vec3f a_local = ends.origin_local;
    for (std::uint32_t i = 1; i <= pieces; ++i) {
      rm_vec3i b_voxel = ends.sample_voxel;
      rm_vec3f b_local = ends.sample_local;
      if (i < pieces) {
        // In range: a point between two in-range points.
        (void)rm_prepare_key(
            &params, rm_vec3d_add(ends.origin, rm_vec3d_scale(d, static_cast<double>(i) / pieces)),
            &b_voxel, &b_local);
      }
      // Inner pieces leave their end voxel to the next piece, which starts there.
      const std::uint32_t flags = (i == pieces ? ends.end_flag : 0u) | params.walk_flag;
      // A piece ends (1 - i / pieces) * kept before the whole ray's end.
      const double piece_end_sdf = ends.end_sdf_m + (1.0 - static_cast<double>(i) / pieces) * kept;
      out[progress.written++] = PreparedRay{a_voxel,
                                            a_local,
                                            b_voxel,
                                            b_local,
                                            flags,
                                            ray.intensity,
                                            static_cast<float>(piece_end_sdf)};
      a_voxel = b_voxel;
      a_local = b_local;
    }
  }
  return progress;
}

void countRejection(std::uint32_t outcome, RayCounters& counters) noexcept {
  switch (outcome & RM_PREPARE_REJECTED_MASK) {
    case RM_PREPARE_INVALID:
      ++counters.rays_invalid;
      break;
    case RM_PREPARE_TOO_SHORT:
      ++counters.rays_too_short;
      break;
    case RM_PREPARE_OUT_OF_BOUNDS:
      ++counters.rays_out_of_bounds;
      break;
    case RM_PREPARE_OUTSIDE_WINDOW:
      ++counters.rays_outside_window;
      break;
    default:
      break;
  }
}

}  // namespace raymap
