// SPDX-License-Identifier: BSD-3-Clause
// The idlc type descriptors of the ROS 2 messages raymapd reads and writes, without exposing the
// generated C headers.
#pragma once

#include <dds/dds.h>

namespace raymap::dds {

/// sensor_msgs::msg::dds_::PointCloud2_
const dds_topic_descriptor_t* pointCloud2Type() noexcept;
/// nav_msgs::msg::dds_::Odometry_
const dds_topic_descriptor_t* odometryType() noexcept;
/// tf2_msgs::msg::dds_::TFMessage_ (/tf and /tf_static)
const dds_topic_descriptor_t* tfMessageType() noexcept;
/// grid_map_msgs::msg::dds_::GridMap_
const dds_topic_descriptor_t* gridMapType() noexcept;
/// diagnostic_msgs::msg::dds_::DiagnosticArray_
const dds_topic_descriptor_t* diagnosticArrayType() noexcept;

}  // namespace raymap::dds
