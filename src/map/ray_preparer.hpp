// SPDX-License-Identifier: BSD-3-Clause
// Ray preparation: validation, range limits, clipping to a rolling window, segmentation and the
// conversion to exact voxel keys, with a counter for every ray that is dropped or changed.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "raymap/error.hpp"

#include "kernels/common/ray_prepare.h"
#include "src/map/ray.hpp"
#include "src/map/voxel_map.hpp"

namespace raymap {

// A batch of Rays goes to the device as rm_raw_ray (Backend::integrateRays) without conversion.
static_assert(sizeof(Ray) == sizeof(rm_raw_ray) &&
              offsetof(Ray, origin) == offsetof(rm_raw_ray, origin) &&
              offsetof(Ray, sample) == offsetof(rm_raw_ray, sample) &&
              offsetof(Ray, intensity) == offsetof(rm_raw_ray, intensity) &&
              offsetof(Ray, flags) == offsetof(rm_raw_ray, flags));
static_assert(kRayNoReturn == RM_RAW_RAY_NO_RETURN);

/// @brief Per-source ray limits. Aggregate with defaults; check with validate().
struct RayFilter {
  static constexpr std::uint32_t kMaxPiecesPerRay = 1024;

  double min_range_m = 0.0;  ///< rays shorter than this are dropped (returns from the robot)
  /// The longest ray a sensor can measure, metres: raymap's default for max_length_m.
  static constexpr double kDefaultMaxLength = 1000.0;

  double max_range_m = 0.0;  ///< 0 = none; longer rays are clipped: free up to here, no hit
  /// 0 = none; longer rays are outlier returns (a lidar's 35 km ghost), rejected as out of
  /// bounds and counted, before max_range_m would clip them into a long free-space ray.
  double max_length_m = kDefaultMaxLength;
  double segment_length_m = 0.0;  ///< 0 = off; longer rays are cut into equal pieces
  bool reverse = false;           ///< walk each ray from the sample back to the origin

  Expected<void, Error> validate() const;
};

/// @brief What happened to the rays offered so far. Plain counters (not synchronised).
struct RayCounters {
  std::uint64_t rays_in = 0;              ///< offered to prepare()
  std::uint64_t rays_invalid = 0;         ///< NaN or infinite coordinates (rejected)
  std::uint64_t rays_too_short = 0;       ///< shorter than min range (rejected)
  std::uint64_t rays_out_of_bounds = 0;   ///< beyond the map's key range or max length (rejected)
  std::uint64_t rays_outside_window = 0;  ///< entirely outside a rolling window (rejected)
  std::uint64_t rays_clipped = 0;         ///< shortened to max range or the window (integrated)
  std::uint64_t rays_no_return = 0;       ///< flagged no-return (integrated, free only)
  std::uint64_t rays_accepted = 0;        ///< integrated (possibly clipped)
  std::uint64_t pieces_out = 0;           ///< prepared rays written (> accepted with segmentation)

  std::uint64_t rejected() const noexcept {
    return rays_invalid + rays_too_short + rays_out_of_bounds + rays_outside_window;
  }
  RayCounters& operator+=(const RayCounters& o) noexcept {
    rays_in += o.rays_in;
    rays_invalid += o.rays_invalid;
    rays_too_short += o.rays_too_short;
    rays_out_of_bounds += o.rays_out_of_bounds;
    rays_outside_window += o.rays_outside_window;
    rays_clipped += o.rays_clipped;
    rays_no_return += o.rays_no_return;
    rays_accepted += o.rays_accepted;
    pieces_out += o.pieces_out;
    return *this;
  }
};

/// @brief Adds the rejection an rm_prepare_ray outcome names (if any) to `counters`; rays_in and
/// the accepted counts are the caller's.
void countRejection(std::uint32_t outcome, RayCounters& counters) noexcept;

/// @brief Turns Rays into PreparedRays for one map.
/// A ray with a real return gets RM_RAY_END_HIT. A clipped or no-return ray does not: it clears the
/// voxels before its end voxel, which it only partly crosses (OctoMap's insertRay does the same);
/// the inner pieces of a segmented ray leave their end voxel to the next piece, which starts there.
/// TSDF maps: a ray with a return is walked on by the truncation distance behind its sample and
/// gets no hit; every prepared ray carries its signed distance at its end (tsdf_end_m).
/// Thread-safety: one preparer per thread, except that the const prepare() (own counters) may run
/// on several threads at once while nothing else uses the preparer or changes the map (RayBatcher
/// prepares a batch's ranges on the backend's workers so). @rt prepare() allocates: no; throws: no.
class RayPreparer {
 public:
  /// @pre filter.validate() succeeded; `map` outlives the preparer.
  RayPreparer(const VoxelMap& map, const RayFilter& filter) noexcept;

  struct Progress {
    std::size_t consumed = 0;  ///< input rays handled (accepted or rejected)
    std::size_t written = 0;   ///< prepared rays appended to `out`
  };

  /// @brief Prepares input rays in order until all are consumed or `out` has no room for the
  /// pieces of the next ray.
  Progress prepare(std::span<const Ray> in, std::span<PreparedRay> out) noexcept {
    return prepare(in, out, counters_);
  }
  /// @brief The same, counting into `counters` instead of the preparer's own.
  Progress prepare(std::span<const Ray> in, std::span<PreparedRay> out,
                   RayCounters& counters) const noexcept {
    return prepareWith(params(), in, out, counters);
  }
  /// @brief The same with parameters taken from params() earlier (a rolling window as it was
  /// when the rays came: RayBatcher's batches for the device).
  Progress prepareWith(const rm_prepare_params& params, std::span<const Ray> in,
                       std::span<PreparedRay> out, RayCounters& counters) const noexcept;
  /// @brief Adds counters of the const prepare() to the preparer's own.
  void addCounters(const RayCounters& counters) noexcept { counters_ += counters; }

  const RayCounters& counters() const noexcept { return counters_; }
  void resetCounters() noexcept { counters_ = RayCounters{}; }
  const RayFilter& filter() const noexcept { return filter_; }

  /// @brief What rm_prepare_ray (kernels/common/ray_prepare.h) needs for this map and filter now
  /// (a rolling map's window as it is at the call): the host's preparation and the device's
  /// (Backend::integrateRays) use the same.
  rm_prepare_params params() const noexcept;

 private:
  const VoxelMap* map_;
  RayFilter filter_;
  double inv_resolution_;
  bool tsdf_;            ///< TSDF map: rays with a return are extended by the truncation distance
  double truncation_m_;  ///< TSDF truncation distance, metres
  RayCounters counters_;
};

}  // namespace raymap
