// SPDX-License-Identifier: BSD-3-Clause
// The ROS 2 message definitions (.msg field lists) of every type raymap reads or writes, in the
// concatenated form rosbag2 stores as an MCAP schema (encoding "ros2msg"): the type's own
// fields, then for each type it uses a separator line of 80 '=', "MSG: pkg/Type" and its fields.
#pragma once

#include <string>
#include <string_view>

namespace raymap::bag {

/// @brief The ros2msg schema text of `type` ("sensor_msgs/msg/PointCloud2"), or "" when raymap
/// does not know the type.
std::string ros2MessageDefinition(std::string_view type);

}  // namespace raymap::bag
