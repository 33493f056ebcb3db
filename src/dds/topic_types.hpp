// SPDX-License-Identifier: BSD-3-Clause
// The idlc type descriptors of the ROS 2 messages raymapd reads and writes, without exposing the
// generated C headers, and the registry of these types by DDS and ROS name.
#pragma once

#include <span>
#include <string>
#include <string_view>

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
/// nav_msgs::msg::dds_::OccupancyGrid_ (the Nav2 costmap)
const dds_topic_descriptor_t* occupancyGridType() noexcept;
/// sensor_msgs::msg::dds_::Image_ (a depth camera's 16UC1 / 32FC1 images)
const dds_topic_descriptor_t* imageType() noexcept;
/// sensor_msgs::msg::dds_::CameraInfo_ (the intrinsics of a camera's images)
const dds_topic_descriptor_t* cameraInfoType() noexcept;

/// @brief A message type raymap can read: its name on the wire, its ROS 2 name and the idlc
/// descriptor a reader of it needs. Static data; the pointers live as long as the program.
struct KnownTopicType {
  const char* dds_name;  ///< e.g. "sensor_msgs::msg::dds_::PointCloud2_" (what DDS discovery shows)
  const char* ros_name;  ///< e.g. "sensor_msgs/msg/PointCloud2" (what `ros2 topic list -t` shows)
  const dds_topic_descriptor_t* descriptor;  ///< idlc's descriptor; its m_typename == dds_name
};

/// @brief The types raymap knows: PointCloud2, Odometry, TFMessage, GridMap, DiagnosticArray,
/// OccupancyGrid, Image, CameraInfo (in that order). @rt allocates: no; thread: any.
std::span<const KnownTopicType> knownTopicTypes() noexcept;

/// @brief Looks a type up by its DDS name ("grid_map_msgs::msg::dds_::GridMap_") or its ROS name
/// ("grid_map_msgs/msg/GridMap"); exact, case-sensitive match.
/// @return the entry, or nullptr when raymap does not know the type
/// @rt allocates: no; thread: any.
const KnownTopicType* findTopicType(std::string_view dds_or_ros_name) noexcept;

}  // namespace raymap::dds
