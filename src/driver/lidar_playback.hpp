// SPDX-License-Identifier: BSD-3-Clause
// Publishes a simulated lidar in real time: odometry at a steady rate and each scan when its
// sweep is complete, stamped with the wall clock like a live driver.
#pragma once

#include <cstdint>
#include <vector>

#include "src/driver/ros_endpoints.hpp"
#include "src/driver/simulated_lidar.hpp"

namespace raymap::driver {

struct PlaybackOptions {
  double scan_rate_hz = 10.0;  ///< scans published per second (may exceed the lidar's own)
  /// A lidar that does not move (one pose) has its scans precomputed and cycled (their noise
  /// differs); a moving one simulates each scan when it is due.
  int distinct_scans = 4;
  double odometry_rate_hz = 100.0;
  bool pose_as_tf = false;  ///< the pose on rt/tf instead of nav_msgs/Odometry on rt/odom
  /// Where the lidar sits on the base (metres, base frame; no rotation): the published pose is
  /// the base's, this far from the simulated sensor.
  Vec3d sensor_in_base{0.0, 0.0, 0.0};
  const char* frame = "lidar";  ///< frame_id of the clouds (= base: identity extrinsic)
  const char* world_frame = "odom";
  const char* base_frame = "base_link";
  /// Fault injection: this many points of every cloud carry a per-point time of 4.29 s
  /// (an Ouster driver's t of 0xFFFFFFFF ns: a corrupt time field).
  std::uint32_t bad_time_points = 0;
};

/// @brief Call publishDue() often (every few ms); it publishes what is due.
/// Thread-safety: one thread. Not real-time (a moving lidar ray-casts each scan).
class LidarPlayback {
 public:
  LidarPlayback(const SimulatedLidar& lidar, DriverPublisher& publisher, PlaybackOptions options);
  /// @brief Time zero of the recording: now (monotonic) and the wall clock now.
  void start(std::int64_t monotonic_ns, std::int64_t wall_ns);
  /// @brief Publishes the odometry and scans due at `monotonic_ns`; returns when the next is due.
  std::int64_t publishDue(std::int64_t monotonic_ns);
  std::uint64_t scansPublished() const noexcept { return scans_; }
  std::uint64_t pointsPublished() const noexcept { return points_; }

 private:
  void corruptTimes(std::vector<msgs::ScanPoint>& scan) const;  // bad_time_points

  const SimulatedLidar& lidar_;
  DriverPublisher& publisher_;
  PlaybackOptions options_;
  std::vector<std::vector<msgs::ScanPoint>> scans_cache_;
  std::vector<std::vector<std::uint16_t>> rings_cache_;
  std::int64_t t0_ = 0, stamp0_ = 0, scan_period_ = 0, odometry_period_ = 0;
  std::int64_t next_scan_ = 0, next_odometry_ = 0;
  std::uint64_t scans_ = 0, points_ = 0;
};

}  // namespace raymap::driver
