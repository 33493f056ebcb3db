// SPDX-License-Identifier: BSD-3-Clause
// A simulated lidar driver's output: scans of a scene in the sensor frame with per-point time
// and ring, as a ROS 2 lidar driver publishes them, and the robot's pose along its path.
#pragma once

#include <cstdint>
#include <vector>

#include "src/io/trajectory.hpp"
#include "src/msgs/point_cloud.hpp"
#include "src/sim/lidar.hpp"
#include "src/sim/scene.hpp"

namespace raymap::driver {

/// @brief Scans of a simulated recording, one at a time (sensor = base frame: identity
/// extrinsic). Thread-safety: none. Not real-time (it ray-casts the scene).
class SimulatedLidar {
 public:
  /// @param config the scene's simulation (lidar model, path, seed); `scans` is ignored.
  SimulatedLidar(sim::Scene scene, sim::SimulationConfig config);

  /// @brief Scan `k` (start time k * scan period after the path's start): points in the sensor
  /// frame (metres; NaN for no-return), time_s after the scan start, ring = beam index.
  void scan(std::uint64_t k, std::vector<msgs::ScanPoint>& points,
            std::vector<std::uint16_t>& rings) const;
  /// @brief The base (= sensor) pose in the world at `time_s` after the path's start.
  io::Pose poseAt(double time_s) const;
  double scanPeriod() const noexcept { return config_.lidar.scan_period_s; }
  /// @brief True when the path has more than one pose (every scan differs in where it looks).
  bool moving() const noexcept { return config_.path.knots().size() > 1; }
  std::uint32_t pointsPerScan() const noexcept;
  const sim::Scene& scene() const noexcept { return scene_; }

 private:
  sim::Scene scene_;
  sim::SimulationConfig config_;
};

}  // namespace raymap::driver
