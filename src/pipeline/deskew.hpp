// SPDX-License-Identifier: BSD-3-Clause
// Deskewing: each point of a scan becomes a world-frame ray from the sensor's pose at the
// point's own time (the base's pose interpolated, composed with the sensor's extrinsic). One
// definition for raymapd's integrator and the offline readers of bags, so both build one map.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>

#include "src/io/sensor_ray.hpp"
#include "src/io/trajectory.hpp"
#include "src/map/ray.hpp"
#include "src/msgs/point_cloud.hpp"
#include "src/pipeline/pose_history.hpp"

namespace raymap::pipeline {

/// @brief A point's time: the header stamp plus its offset (seconds), in nanoseconds.
inline std::int64_t pointTimeNs(std::int64_t stamp_ns, float time_s) noexcept {
  return stamp_ns + static_cast<std::int64_t>(std::llround(static_cast<double>(time_s) * 1e9));
}

/// @brief A per-point time the scan can use: finite and within `max_offset_s` of the stamp.
inline bool usableTime(float time_s, float max_offset_s) noexcept {
  return std::fabs(time_s) <= max_offset_s;  // false for NaN
}

/// @brief The times a scan's poses must cover, and its points with a corrupt time.
struct ScanTimes {
  std::int64_t start_ns = 0;   ///< earliest usable point time (the stamp when none is earlier)
  std::int64_t end_ns = 0;     ///< latest usable point time (the stamp when none is later)
  std::uint64_t bad_time = 0;  ///< returns whose time is not usable (left out)
};

/// @brief A point with a corrupt time is left out, not allowed to stretch the scan.
inline ScanTimes scanTimes(std::span<const msgs::ScanPoint> points, std::int64_t stamp_ns,
                           float max_offset_s) noexcept {
  float t_min = 0.0f;
  float t_max = 0.0f;
  ScanTimes times;
  for (const msgs::ScanPoint& p : points) {
    if (!usableTime(p.time_s, max_offset_s)) {
      times.bad_time += (p.flags & msgs::kPointNoReturn) == 0u ? 1u : 0u;
      continue;
    }
    t_min = std::min(t_min, p.time_s);
    t_max = std::max(t_max, p.time_s);
  }
  times.start_ns = pointTimeNs(stamp_ns, t_min);
  times.end_ns = pointTimeNs(stamp_ns, t_max);
  return times;
}

/// @brief Turns points into rays, looking the sensor's pose up once per distinct point time.
/// Thread-safety: one thread. @rt allocates: no.
class PointDeskewer {
 public:
  /// @brief Forgets the cached pose (a new scan, or a new extrinsic).
  void reset() noexcept { last_time_ns_ = std::numeric_limits<std::int64_t>::min(); }

  /// @brief The ray of return `p` (not a no-return, with a usable time; a kPointFreeOnly point
  /// gives a kRayNoReturn ray) of a scan stamped
  /// `stamp_ns`, from sensor `extrinsic` on the base whose poses `history` holds.
  /// @return false when `history` has no pose for the point's time (nothing written).
  bool toRay(const msgs::ScanPoint& p, std::int64_t stamp_ns, const PoseHistory& history,
             std::int64_t hold_ns, const io::Pose& extrinsic, std::uint64_t scan,
             Ray& ray) noexcept {
    const std::int64_t t = pointTimeNs(stamp_ns, p.time_s);
    if (t != last_time_ns_) {
      io::Pose base;
      if (history.lookup(t, hold_ns, &base) != PoseLookup::kOk) {
        return false;
      }
      sensor_pose_ = io::compose(base, extrinsic);
      last_time_ns_ = t;
    }
    // The sensor's pose in the world frame maps the point (sensor frame, metres) into the world.
    io::aimRay(sensor_pose_,
               {static_cast<double>(p.x), static_cast<double>(p.y), static_cast<double>(p.z)}, ray);
    ray.time_s = static_cast<double>(t) * 1e-9;
    ray.intensity = p.intensity;
    ray.flags = (p.flags & msgs::kPointFreeOnly) != 0u ? kRayNoReturn : 0u;
    ray.scan = scan;
    return true;
  }

 private:
  std::int64_t last_time_ns_ = std::numeric_limits<std::int64_t>::min();
  io::Pose sensor_pose_;
};

}  // namespace raymap::pipeline
