// SPDX-License-Identifier: BSD-3-Clause
// The idlc descriptors behind src/dds/topic_types.hpp and the name conversions of rmw_cyclonedds.
#include "src/dds/topic_types.hpp"

#include <array>
#include <vector>

#include "diagnostic_msgs.h"
#include "grid_map_msgs.h"
#include "nav_msgs.h"
#include "sensor_msgs.h"
#include "tf2_msgs.h"

namespace raymap::dds {

const dds_topic_descriptor_t* pointCloud2Type() noexcept {
  return &sensor_msgs_msg_dds__PointCloud2__desc;
}
const dds_topic_descriptor_t* odometryType() noexcept { return &nav_msgs_msg_dds__Odometry__desc; }
const dds_topic_descriptor_t* tfMessageType() noexcept {
  return &tf2_msgs_msg_dds__TFMessage__desc;
}
const dds_topic_descriptor_t* occupancyGridType() noexcept {
  return &nav_msgs_msg_dds__OccupancyGrid__desc;
}
const dds_topic_descriptor_t* imageType() noexcept { return &sensor_msgs_msg_dds__Image__desc; }
const dds_topic_descriptor_t* cameraInfoType() noexcept {
  return &sensor_msgs_msg_dds__CameraInfo__desc;
}

const dds_topic_descriptor_t* gridMapType() noexcept {
  return &grid_map_msgs_msg_dds__GridMap__desc;
}
const dds_topic_descriptor_t* diagnosticArrayType() noexcept {
  return &diagnostic_msgs_msg_dds__DiagnosticArray__desc;
}

namespace {

// The DDS names are spelled out (not read from m_typename) so that the table is a constant; a
// unit test checks each against its descriptor's m_typename.
constexpr std::array<KnownTopicType, 8> kKnownTypes = {{
    {"sensor_msgs::msg::dds_::PointCloud2_", "sensor_msgs/msg/PointCloud2",
     &sensor_msgs_msg_dds__PointCloud2__desc},
    {"nav_msgs::msg::dds_::Odometry_", "nav_msgs/msg/Odometry", &nav_msgs_msg_dds__Odometry__desc},
    {"tf2_msgs::msg::dds_::TFMessage_", "tf2_msgs/msg/TFMessage",
     &tf2_msgs_msg_dds__TFMessage__desc},
    {"grid_map_msgs::msg::dds_::GridMap_", "grid_map_msgs/msg/GridMap",
     &grid_map_msgs_msg_dds__GridMap__desc},
    {"diagnostic_msgs::msg::dds_::DiagnosticArray_", "diagnostic_msgs/msg/DiagnosticArray",
     &diagnostic_msgs_msg_dds__DiagnosticArray__desc},
    {"nav_msgs::msg::dds_::OccupancyGrid_", "nav_msgs/msg/OccupancyGrid",
     &nav_msgs_msg_dds__OccupancyGrid__desc},
    {"sensor_msgs::msg::dds_::Image_", "sensor_msgs/msg/Image", &sensor_msgs_msg_dds__Image__desc},
    {"sensor_msgs::msg::dds_::CameraInfo_", "sensor_msgs/msg/CameraInfo",
     &sensor_msgs_msg_dds__CameraInfo__desc},
}};

/// rmw_cyclonedds prefixes every ROS topic with this (ROS_TOPIC_PREFIX in namespace_prefix.hpp).

}  // namespace

std::span<const KnownTopicType> knownTopicTypes() noexcept { return kKnownTypes; }

const KnownTopicType* findTopicType(std::string_view dds_or_ros_name) noexcept {
  for (const KnownTopicType& type : kKnownTypes) {
    if (dds_or_ros_name == type.dds_name || dds_or_ros_name == type.ros_name) {
      return &type;
    }
  }
  return nullptr;
}

}  // namespace raymap::dds
