// SPDX-License-Identifier: BSD-3-Clause
// Serializing a lidar scan as a sensor_msgs/PointCloud2 in the Ouster ROS driver's point layout:
// bytes as a driver publishes them, for the decoder's benchmark and for tools that write clouds.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "src/msgs/point_cloud.hpp"

namespace raymap::msgs {

/// Bytes per point of serializeOusterCloud's layout.
inline constexpr std::uint32_t kOusterPointStep = 48;

/// @brief Serializes `points` as sensor_msgs/PointCloud2 (CDR_LE, encapsulation header included)
/// into `out`, replacing its contents, in the layout of the Ouster ROS driver:
/// x, y, z float32 at 0, 4, 8; intensity float32 at 16; t uint32 at 20 (nanoseconds after the
/// stamp); reflectivity uint16 at 24; ring uint16 at 26; ambient uint16 at 28; range uint32 at 32
/// (millimetres); 48 bytes a point. Organised as the driver publishes: `rows` rows (the beams) of
/// points.size() / rows points, is_dense true.
///
/// A point flagged kPointNoReturn is written as (0, 0, 0) with range 0, as the driver writes a
/// missing return; time_s is rounded to nanoseconds (negative and NaN times: 0);
/// reflectivity and ambient are 0; ring is rings[i], or the row when `rings` is empty.
/// @pre rows > 0, points.size() % rows == 0, rings empty or as long as points
/// @rt allocates: only when `out`'s capacity is too small; thread: any.
void serializeOusterCloud(std::int64_t stamp_ns, std::string_view frame_id, std::uint32_t rows,
                          std::span<const ScanPoint> points, std::span<const std::uint16_t> rings,
                          std::vector<std::byte>& out);

}  // namespace raymap::msgs
