// SPDX-License-Identifier: BSD-3-Clause
// Recorded rays turned back into what a lidar driver and a localisation stack publish: one
// point cloud per scan in the sensor frame, with per-point time, and the sensor's pose over time.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "raymap/error.hpp"

#include "src/core/vec3.hpp"
#include "src/io/ray_source.hpp"
#include "src/map/ray.hpp"
#include "src/msgs/point_cloud.hpp"

namespace raymap::replay {

/// @brief The rays of one scan (a run of equal scan index in the file), in file order.
struct RecordedScan {
  std::uint64_t index = 0;
  double t_first_s = 0.0;  ///< earliest ray time (file time base, seconds)
  double t_last_s = 0.0;   ///< latest ray time
  std::vector<Ray> rays;
};

/// @brief Reads a ray source one scan at a time. Not thread-safe.
class ScanReader {
 public:
  explicit ScanReader(std::unique_ptr<io::RaySource> source);
  /// @brief The next scan into `scan`; false at the end of the file.
  Result<bool> next(RecordedScan& scan);
  double progress() const noexcept { return source_->progress(); }
  const io::RaySourceInfo& info() const noexcept { return source_->info(); }

 private:
  Result<bool> refill();
  std::unique_ptr<io::RaySource> source_;
  std::vector<Ray> buffer_;
  std::size_t position_ = 0, size_ = 0;
  bool end_ = false;
};

/// @brief A pose sample as odometry carries it: the sensor (= base) position in the world frame
/// at `stamp_ns`, orientation the identity (a ray file has positions only).
struct PoseKnot {
  std::int64_t stamp_ns = 0;
  Vec3d position;
};

/// @brief One scan as a driver publishes it.
struct DriverScan {
  std::int64_t stamp_ns = 0;            ///< header stamp: the scan's first ray
  std::vector<PoseKnot> knots;          ///< strictly increasing stamps over the whole scan
  std::vector<msgs::ScanPoint> points;  ///< sensor frame, time_s after stamp_ns
  std::uint64_t origin_conflicts = 0;   ///< rays sharing an instant but not an origin
};

/// @brief Converts a recorded scan. File time t maps to stamp `stamp_of_zero_ns + (t - t_zero_s)`.
/// Poses are sampled from the rays' origins about every `knot_period_s` (plus the first and
/// last ray), and every point is expressed relative to the pose *interpolated linearly between
/// those knots at its own time* — the same interpolation a subscriber that deskews with the
/// odometry does — so the subscriber recovers the recorded sample points exactly (to float
/// rounding) and the origins to the path's deviation from a straight line between knots.
/// The sensor frame's axes are the world's (identity orientation). No-return rays become
/// kPointNoReturn points (published as NaN, REP 117).
void toDriverScan(const RecordedScan& scan, std::int64_t stamp_of_zero_ns, double t_zero_s,
                  double knot_period_s, DriverScan& out);

}  // namespace raymap::replay
