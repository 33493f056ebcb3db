// SPDX-License-Identifier: BSD-3-Clause
// sensor_msgs/PointCloud2 as a lidar driver fills it: x, y, z (FLOAT32) and t (UINT32, ns).
#pragma once

#include <cstdint>
#include <span>
#include <string>

#include "sensor_msgsPubSubTypes.h"

#include "tests/fastdds/peer/room_lidar.hpp"

namespace raymap::fastdds_peer {

/// @brief Bytes of one point: x, y, z, t.
inline constexpr std::uint32_t kPointStep = 16;

/// @brief Sets `cloud` to `points` (an unorganised cloud, height 1, dense), stamped `stamp_ns`
/// (Unix time) in `frame`; the data in the host's byte order, is_bigendian saying which.
void fillCloud(std::span<const LidarPoint> points, std::int64_t stamp_ns, const std::string& frame,
               sensor_msgs::msg::dds_::PointCloud2_& cloud);

/// @brief `stamp_ns` (Unix nanoseconds) as builtin_interfaces/Time.
builtin_interfaces::msg::dds_::Time_ rosTime(std::int64_t stamp_ns);

}  // namespace raymap::fastdds_peer
