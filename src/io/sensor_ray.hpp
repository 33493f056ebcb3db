// SPDX-License-Identifier: BSD-3-Clause
// The one conversion of a sensor-frame point into a world-frame ray.
#pragma once

#include <Eigen/Core>

#include "src/core/eigen_conversions.hpp"
#include "src/io/trajectory.hpp"
#include "src/map/ray.hpp"

namespace raymap::io {

/// @brief Aims `ray` from the sensor at `sensor_to_world` to `point_in_sensor` (the sensor's
/// frame, metres): origin and sample in the world frame; the other fields are the caller's.
///
/// The one point-to-ray conversion on the host, used by raymapd's pipeline and the bag reader
/// (pipeline::PointDeskewer) and by raymap::Mapper, for lidar points and depth pixels alike. It
/// applies the pose as rm_pose_apply (kernels/common/pose.h) does, which is also what the
/// devices' rm_deskew_point does, so a scan gives the same rays, and the same map, whichever of
/// them converts it. Real-time safe: no allocation, no exception.
inline void aimRay(const Pose& sensor_to_world, const Eigen::Vector3d& point_in_sensor,
                   Ray& ray) noexcept {
  ray.origin = toVec3(sensor_to_world.position);
  ray.sample = toVec3(sensor_to_world.transform(point_in_sensor));
}

}  // namespace raymap::io
