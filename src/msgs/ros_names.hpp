// SPDX-License-Identifier: BSD-3-Clause
// ROS 2's names of topics and types as DDS spells them (the rmw convention: "rt/" topics,
// "pkg::msg::dds_::Name_" types), used by the bag reader, the DDS layer and the tools alike.
#pragma once

#include <string>
#include <string_view>

namespace raymap::msgs {

/// @brief The DDS topic of a ROS topic name, as rmw_cyclonedds names it: "/height_map" ->
/// "rt/height_map". A name that already starts with "rt/" and any other name (taken to be a DDS
/// topic name already, e.g. from `raymap topics`) are returned unchanged.
std::string ddsTopicName(std::string_view name);

/// @brief The ROS topic of a DDS topic: "rt/height_map" -> "/height_map"; "" for a topic
/// outside the ROS "rt/" convention (services' rq/ and rr/ topics included).
std::string rosTopicName(std::string_view dds_name);

/// @brief The ROS form of a DDS type name that follows the rmw convention
/// ("pkg::msg::dds_::Name_" -> "pkg/msg/Name"); any other name is returned unchanged.
std::string rosTypeName(std::string_view dds_type_name);

}  // namespace raymap::msgs
