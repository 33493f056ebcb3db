// SPDX-License-Identifier: BSD-3-Clause
// What raymap::Mapper integrates: scans of world-frame rays, or of sensor-frame points with the
// sensor's pose (one for the scan, or one per point time).
#pragma once

#include <functional>
#include <optional>

#include <Eigen/Geometry>

namespace raymap {

/// @brief One measurement in the world (map) frame, metres: the sensor's position when it was
/// taken and the return. Plain value type.
struct WorldRay {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  ///< sensor position, world frame, metres
  /// The return (or, with no_return, the point the free space reaches), world frame, metres.
  Eigen::Vector3d end = Eigen::Vector3d::Zero();
  float intensity = 0.0f;  ///< NDT-TM's intensity layer; otherwise unused
  bool no_return = false;  ///< nothing came back: clears free space to `end`, marks no hit
};

/// @brief One point as a sensor reports it: in the sensor frame (metres) at a time (seconds, in
/// the time base of the pose function; unused with one pose per scan). Plain value type.
struct SensorPoint {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  ///< sensor frame, metres
  double time_s = 0.0;
  float intensity = 0.0f;
  bool no_return = false;  ///< nothing came back along this direction (see WorldRay)
};

/// @brief The sensor's pose in the world frame (p_world = pose * p_sensor) at a time (seconds),
/// or nullopt when it is not known then (those points are counted and left out). Called once
/// per distinct point time, in the order of the points, on the thread that calls integrate().
using SensorPoseFunction = std::function<std::optional<Eigen::Isometry3d>(double time_s)>;

/// @brief A sample of the sensor's pose in the world frame (p_world = sensor_to_world * p_sensor)
/// at a time (seconds, the time base of the points). Plain value type.
struct TimedPose {
  double time_s = 0.0;
  Eigen::Isometry3d sensor_to_world = Eigen::Isometry3d::Identity();
};

}  // namespace raymap
