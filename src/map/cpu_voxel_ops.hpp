// SPDX-License-Identifier: BSD-3-Clause
// The CPU integrator's inner loops: walking the voxels of one ray span inside one region and
// applying the shared update rules (kernels/common) to them.
#pragma once

#include <cstdint>

#include "kernels/common/key_math.h"
#include "kernels/common/line_walk.h"
#include "kernels/common/occupancy.h"
#include "kernels/common/ray.h"
#include "kernels/common/scan_mark.h"
#include "kernels/common/voxel_mean.h"
#include "src/core/assert.hpp"
#include "src/map/ray_region_walk.hpp"

namespace raymap::detail {

/// @brief Calls visit(index) for each voxel of `span` (index inside the span's region), leaving out
/// the ray's sample voxel, which the caller updates by its own rule. Returns the voxels visited.
/// @rt allocates: no.
template <class Visit>
inline std::uint32_t walkSpan(const RayRegionWalk& ray, const RaySpan& span,
                              std::int32_t region_voxels, Visit&& visit) noexcept {
  const rm_ray_walk_frame& frame = ray.frame();
  rm_line_walk w;
  rm_line_walk_init_span(&w, &ray.voxelRay(), span.t0, span.t1, span.box_lo, span.box_hi,
                         span.first ? 1 : 0, span.last ? 1 : 0);
  const std::int32_t n = region_voxels;
  RAYMAP_DEBUG_ASSERT(w.x >= span.box_lo.x && w.x <= span.box_hi.x && w.y >= span.box_lo.y &&
                      w.y <= span.box_hi.y && w.z >= span.box_lo.z && w.z <= span.box_hi.z);
  std::int32_t index =
      (w.x - span.box_lo.x) + n * ((w.y - span.box_lo.y) + n * (w.z - span.box_lo.z));
  const std::int32_t delta[3] = {w.step_x, w.step_y * n, w.step_z * n * n};
  const bool skip_first = span.first && frame.sample_is_start != 0;
  const bool skip_last = span.last && frame.sample_is_start == 0;
  // The span's voxels are its first voxel plus one per remaining step; the sample voxel is left
  // out at whichever end it is.
  std::int32_t steps = w.steps_left;
  if (skip_first) {
    if (steps == 0) {
      return 0;
    }
    index += delta[rm_line_walk_step(&w)];
    --steps;
  }
  if (skip_last) {
    if (steps == 0) {
      return 0;
    }
    --steps;
  }
  visit(static_cast<std::uint32_t>(index));
  for (std::int32_t k = 0; k < steps; ++k) {
    index += delta[rm_line_walk_step(&w)];
    visit(static_cast<std::uint32_t>(index));
  }
  return static_cast<std::uint32_t>(steps + 1);
}

/// Per-ray miss: every crossing lowers the occupancy.
struct PerRayMiss {
  float* occupancy;
  rm_occupancy_params params;
  void operator()(std::uint32_t i) const noexcept {
    occupancy[i] = rm_occupancy_miss(occupancy[i], params);
  }
};

/// Per-scan miss: the first crossing in this scan lowers the occupancy, unless the scan hit the
/// voxel (occupied wins).
struct PerScanMiss {
  float* occupancy;
  std::uint32_t* marks;
  std::uint32_t sequence;
  rm_occupancy_params params;
  void operator()(std::uint32_t i) const noexcept {
    if (rm_scan_needs_miss(marks[i], sequence)) {
      occupancy[i] = rm_occupancy_miss(occupancy[i], params);
      marks[i] = rm_scan_mark_miss(sequence);
    }
  }
};

/// @brief Pointers to one region's layers (null for absent layers).
struct RegionLayers {
  float* occupancy = nullptr;
  rm_voxel_mean* mean = nullptr;
  std::uint32_t* marks = nullptr;
};

/// @brief Applies a ray's hit to its sample voxel (index `i` of region `layers`). Per-scan hits
/// change the occupancy in a separate pass (applyScanHit); here they only feed the mean.
/// @pre ray.flags has RM_RAY_END_HIT.
inline void applySampleHit(const rm_prepared_ray& ray, const RegionLayers& layers, std::uint32_t i,
                           bool per_scan, const rm_occupancy_params& params) noexcept {
  if (!per_scan) {
    layers.occupancy[i] = rm_occupancy_hit(layers.occupancy[i], params);
  }
  if (layers.mean != nullptr) {
    rm_voxel_mean& m = layers.mean[i];
    m.packed = rm_mean_fold(m.packed, m.count, ray.sample_local);
    m.count = rm_mean_count_increment(m.count);
  }
}

/// @brief Per-scan hit pass: the first hit of a voxel in this scan raises its occupancy once.
inline void applyScanHit(const RegionLayers& layers, std::uint32_t i, std::uint32_t sequence,
                         const rm_occupancy_params& params) noexcept {
  if (rm_scan_needs_hit(layers.marks[i], sequence)) {
    layers.occupancy[i] = rm_occupancy_hit(layers.occupancy[i], params);
    layers.marks[i] = rm_scan_mark_hit(sequence);
  }
}

}  // namespace raymap::detail
