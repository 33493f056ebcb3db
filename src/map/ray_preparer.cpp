// SPDX-License-Identifier: BSD-3-Clause
// Ray preparation.
#include "src/map/ray_preparer.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "kernels/common/tsdf.h"

namespace raymap {
namespace {

// Rays longer than this many voxels are rejected: the walk runs in float relative to its start
// voxel, and 2^22 voxels (419 km at 0.1 m) keeps positions exact to better than 1e-3 voxel.
constexpr double kMaxRayVoxels = 4194304.0;

// Clips the segment a + t (b - a), t in [0, 1], to an axis-aligned box. Returns false when the
// segment misses the box; otherwise [*t0, *t1] is the part inside.
bool clipToBox(Vec3d a, Vec3d b, Vec3d lo, Vec3d hi, double* t0, double* t1) {
  double enter = 0.0;
  double exit = 1.0;
  for (int axis = 0; axis < 3; ++axis) {
    const double d = b[axis] - a[axis];
    if (d == 0.0) {
      if (a[axis] < lo[axis] || a[axis] > hi[axis]) {
        return false;
      }
      continue;
    }
    double ta = (lo[axis] - a[axis]) / d;
    double tb = (hi[axis] - a[axis]) / d;
    if (ta > tb) {
      std::swap(ta, tb);
    }
    enter = std::max(enter, ta);
    exit = std::min(exit, tb);
    if (enter > exit) {
      return false;
    }
  }
  *t0 = enter;
  *t1 = exit;
  return true;
}

}  // namespace

Expected<void, Error> RayFilter::validate() const {
  if (!std::isfinite(min_range_m) || min_range_m < 0.0) {
    return fail(ErrorCode::kInvalidArgument, "min-range must be a distance >= 0 metres");
  }
  if (!std::isfinite(max_range_m) || max_range_m < 0.0) {
    return fail(ErrorCode::kInvalidArgument, "max-range must be a distance >= 0 metres (0 = none)");
  }
  if (max_range_m > 0.0 && max_range_m <= min_range_m) {
    return fail(ErrorCode::kInvalidArgument, "max-range must be larger than min-range");
  }
  if (!std::isfinite(segment_length_m) || segment_length_m < 0.0) {
    return fail(ErrorCode::kInvalidArgument,
                "segment-length must be a distance >= 0 metres (0 = off)");
  }
  return {};
}

RayPreparer::RayPreparer(const VoxelMap& map, const RayFilter& filter) noexcept
    : map_(&map),
      filter_(filter),
      inv_resolution_(1.0 / map.geometry().resolution),
      tsdf_(map.mode() == MapMode::kTsdf),
      truncation_m_(map.config().tsdf.truncationMetres(map.geometry().resolution)) {}

bool RayPreparer::toKey(Vec3d p, rm_vec3i* voxel, rm_vec3f* local) const noexcept {
  const double sx = p.x * inv_resolution_;
  const double sy = p.y * inv_resolution_;
  const double sz = p.z * inv_resolution_;
  const double fx = std::floor(sx);
  const double fy = std::floor(sy);
  const double fz = std::floor(sz);
  // VoxelMap::voxelInRange's test (same resolution) on the floors taken here: calling it floored
  // every axis a second time (2.3 % of a 3DTK profile, beside 5.3 % for the rest of the
  // preparation).
  if (!map_->flooredVoxelInRange(fx) || !map_->flooredVoxelInRange(fy) ||
      !map_->flooredVoxelInRange(fz)) {
    return false;
  }
  *voxel = rm_vec3i{static_cast<std::int32_t>(fx), static_cast<std::int32_t>(fy),
                    static_cast<std::int32_t>(fz)};
  *local = rm_vec3f{static_cast<float>(sx - fx), static_cast<float>(sy - fy),
                    static_cast<float>(sz - fz)};
  return true;
}

RayPreparer::Progress RayPreparer::prepare(std::span<const Ray> in, std::span<PreparedRay> out,
                                           RayCounters& counters) const noexcept {
  Progress progress;
  const bool rolling = map_->config().policy == StorePolicy::kRolling;
  for (const Ray& ray : in) {
    Vec3d origin = ray.origin;
    Vec3d sample = ray.sample;
    if (!origin.isFinite() || !sample.isFinite()) {
      ++counters.rays_in;
      ++counters.rays_invalid;
      ++progress.consumed;
      continue;
    }
    const double length = (sample - origin).norm();
    if (length < filter_.min_range_m) {
      ++counters.rays_in;
      ++counters.rays_too_short;
      ++progress.consumed;
      continue;
    }
    const bool no_return = (ray.flags & kRayNoReturn) != 0u;
    std::uint32_t end_flag = no_return ? 0u : RM_RAY_END_HIT;
    bool clipped = false;
    // TSDF maps: signed distance at the ray's end, metres (kernels/common/tsdf.h). Rays that
    // update free space only keep RM_TSDF_FREE.
    double end_sdf = static_cast<double>(RM_TSDF_FREE);
    if (filter_.max_range_m > 0.0 && length > filter_.max_range_m) {
      sample = origin + (sample - origin) * (filter_.max_range_m / length);
      end_flag = 0u;
      clipped = true;
    }
    if (tsdf_ && end_flag != 0u) {
      // The walk goes on tau behind the sample, so the negative side of the surface is updated;
      // the sample voxel gets no hit (a TSDF map has no occupancy).
      if (length > 0.0) {
        sample = sample + (sample - origin) * (truncation_m_ / length);
        end_sdf = -truncation_m_;
      } else {
        end_sdf = 0.0;
      }
      end_flag = 0u;
    }
    if (rolling) {
      auto [lo, hi] = map_->windowBounds();
      // Clip half a voxel outside the window: a ray that leaves the window crosses its boundary
      // voxels completely, so they must be cleared; the end voxel, which is left out, and any
      // other voxel outside the window are skipped by the backend.
      const double margin = 0.5 * map_->geometry().resolution;
      lo = lo - Vec3d{margin, margin, margin};
      hi = hi + Vec3d{margin, margin, margin};
      double t0 = 0.0;
      double t1 = 1.0;
      if (!clipToBox(origin, sample, lo, hi, &t0, &t1)) {
        ++counters.rays_in;
        ++counters.rays_outside_window;
        ++progress.consumed;
        continue;
      }
      const Vec3d d = sample - origin;
      if (t1 < 1.0) {
        end_sdf += (1.0 - t1) * d.norm();
        sample = origin + d * t1;
        end_flag = 0u;
        clipped = true;
      }
      if (t0 > 0.0) {
        origin = origin + d * t0;
        clipped = true;
      }
    }
    const double kept = (sample - origin).norm();
    rm_vec3i origin_voxel;
    rm_vec3i sample_voxel;
    rm_vec3f origin_local;
    rm_vec3f sample_local;
    if (kept * inv_resolution_ > kMaxRayVoxels || !toKey(origin, &origin_voxel, &origin_local) ||
        !toKey(sample, &sample_voxel, &sample_local)) {
      ++counters.rays_in;
      ++counters.rays_out_of_bounds;
      ++progress.consumed;
      continue;
    }
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
    counters.rays_clipped += clipped ? 1u : 0u;
    counters.rays_no_return += no_return ? 1u : 0u;
    counters.pieces_out += pieces;
    ++progress.consumed;
    const std::uint32_t walk_flag = filter_.reverse ? RM_RAY_REVERSE : 0u;
    if (pieces == 1) {
      out[progress.written++] = PreparedRay{origin_voxel,
                                            origin_local,
                                            sample_voxel,
                                            sample_local,
                                            end_flag | walk_flag,
                                            ray.intensity,
                                            static_cast<float>(end_sdf)};
      continue;
    }
    const Vec3d d = sample - origin;
    rm_vec3i a_voxel = origin_voxel;
    rm_vec3f a_local = origin_local;
    for (std::uint32_t i = 1; i <= pieces; ++i) {
      rm_vec3i b_voxel = sample_voxel;
      rm_vec3f b_local = sample_local;
      if (i < pieces) {
        // In range: a point between two in-range points.
        (void)toKey(origin + d * (static_cast<double>(i) / pieces), &b_voxel, &b_local);
      }
      // Inner pieces leave their end voxel to the next piece, which starts there.
      const std::uint32_t flags = (i == pieces ? end_flag : 0u) | walk_flag;
      // A piece ends (1 - i / pieces) * kept before the whole ray's end.
      const double piece_end_sdf = end_sdf + (1.0 - static_cast<double>(i) / pieces) * kept;
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

}  // namespace raymap
