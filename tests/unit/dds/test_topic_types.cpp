// SPDX-License-Identifier: BSD-3-Clause
// The registry of known message types and the rmw_cyclonedds name conversions.
#include <cstring>
#include <string>

#include <gtest/gtest.h>

#include "src/dds/topic_types.hpp"
#include "src/msgs/ros_names.hpp"

namespace raymap::dds {
namespace {

TEST(KnownTopicTypes, ListsTheEightTypesWithTheirDescriptorsNames) {
  const auto types = knownTopicTypes();
  ASSERT_EQ(types.size(), 8U);
  for (const KnownTopicType& type : types) {
    ASSERT_NE(type.descriptor, nullptr) << type.ros_name;
    // The spelled-out DDS name is what the descriptor registers, i.e. what discovery shows.
    EXPECT_STREQ(type.dds_name, type.descriptor->m_typename);
    EXPECT_EQ(msgs::rosTypeName(type.dds_name), type.ros_name);
  }
  EXPECT_EQ(types[0].descriptor, pointCloud2Type());
  EXPECT_EQ(types[1].descriptor, odometryType());
  EXPECT_EQ(types[2].descriptor, tfMessageType());
  EXPECT_EQ(types[3].descriptor, gridMapType());
  EXPECT_EQ(types[4].descriptor, diagnosticArrayType());
  EXPECT_EQ(types[5].descriptor, occupancyGridType());
  EXPECT_EQ(types[6].descriptor, imageType());
  EXPECT_EQ(types[7].descriptor, cameraInfoType());
}

TEST(FindTopicType, FindsByDdsAndByRosName) {
  const KnownTopicType* by_dds = findTopicType("grid_map_msgs::msg::dds_::GridMap_");
  ASSERT_NE(by_dds, nullptr);
  EXPECT_EQ(by_dds->descriptor, gridMapType());
  EXPECT_STREQ(by_dds->ros_name, "grid_map_msgs/msg/GridMap");
  EXPECT_EQ(findTopicType("grid_map_msgs/msg/GridMap"), by_dds);
  const KnownTopicType* diagnostics = findTopicType("diagnostic_msgs/msg/DiagnosticArray");
  ASSERT_NE(diagnostics, nullptr);
  EXPECT_EQ(diagnostics->descriptor, diagnosticArrayType());
  EXPECT_EQ(findTopicType("sensor_msgs::msg::dds_::PointCloud2_")->descriptor, pointCloud2Type());
  EXPECT_EQ(findTopicType("nav_msgs/msg/Odometry")->descriptor, odometryType());
  EXPECT_EQ(findTopicType("tf2_msgs/msg/TFMessage")->descriptor, tfMessageType());
  EXPECT_EQ(findTopicType("sensor_msgs/msg/Image")->descriptor, imageType());
  EXPECT_EQ(findTopicType("sensor_msgs::msg::dds_::Image_")->descriptor, imageType());
  EXPECT_EQ(findTopicType("sensor_msgs/msg/CameraInfo")->descriptor, cameraInfoType());
  EXPECT_EQ(findTopicType("sensor_msgs::msg::dds_::CameraInfo_")->descriptor, cameraInfoType());
}

TEST(FindTopicType, ReturnsNullForUnknownOrInexactNames) {
  EXPECT_EQ(findTopicType(""), nullptr);
  EXPECT_EQ(findTopicType("std_msgs/msg/String"), nullptr);
  EXPECT_EQ(findTopicType("std_msgs::msg::dds_::Header_"), nullptr);
  EXPECT_EQ(findTopicType("grid_map_msgs/msg/gridmap"), nullptr);  // case-sensitive
  EXPECT_EQ(findTopicType("grid_map_msgs::msg::GridMap"), nullptr);
  EXPECT_EQ(findTopicType("grid_map_msgs/msg/GridMap "), nullptr);
}

TEST(DdsTopicName, PrefixesRosNamesAndKeepsDdsNames) {
  EXPECT_EQ(msgs::ddsTopicName("/height_map"), "rt/height_map");
  EXPECT_EQ(msgs::ddsTopicName("/ouster/points"), "rt/ouster/points");
  EXPECT_EQ(msgs::ddsTopicName("rt/height_map"), "rt/height_map");
  EXPECT_EQ(msgs::ddsTopicName("rt/ouster/points"), "rt/ouster/points");
  EXPECT_EQ(msgs::ddsTopicName("ros_discovery_info"), "ros_discovery_info");
  EXPECT_EQ(msgs::ddsTopicName(""), "");
}

TEST(RosTopicName, StripsTheRtPrefixOnly) {
  EXPECT_EQ(msgs::rosTopicName("rt/height_map"), "/height_map");
  EXPECT_EQ(msgs::rosTopicName("rt/ouster/points"), "/ouster/points");
  EXPECT_EQ(msgs::rosTopicName("rq/add_two_intsRequest"), "");
  EXPECT_EQ(msgs::rosTopicName("ros_discovery_info"), "");
  EXPECT_EQ(msgs::rosTopicName("rt/"), "");
  EXPECT_EQ(msgs::rosTopicName("rtx/a"), "");
  EXPECT_EQ(msgs::rosTopicName(""), "");
}

TEST(RosTypeName, ConvertsTheRmwConventionAndKeepsOtherNames) {
  EXPECT_EQ(msgs::rosTypeName("grid_map_msgs::msg::dds_::GridMap_"), "grid_map_msgs/msg/GridMap");
  EXPECT_EQ(msgs::rosTypeName("rmw_dds_common::msg::dds_::ParticipantEntitiesInfo_"),
            "rmw_dds_common/msg/ParticipantEntitiesInfo");
  EXPECT_EQ(msgs::rosTypeName("example::srv::dds_::AddTwoInts_Request_"),
            "example/srv/AddTwoInts_Request");
  // Not the convention: unchanged.
  EXPECT_EQ(msgs::rosTypeName("KeyedSeq"), "KeyedSeq");
  EXPECT_EQ(msgs::rosTypeName("rtmap::msg::HeightMap"), "rtmap::msg::HeightMap");
  EXPECT_EQ(msgs::rosTypeName("a::dds_::X_"), "a::dds_::X_");
  EXPECT_EQ(msgs::rosTypeName("pkg::msg::dds_::Name"), "pkg::msg::dds_::Name");
  EXPECT_EQ(msgs::rosTypeName("pkg::msg::dds_::_"), "pkg::msg::dds_::_");
  EXPECT_EQ(msgs::rosTypeName("::msg::dds_::X_"), "::msg::dds_::X_");
  EXPECT_EQ(msgs::rosTypeName(""), "");
}

}  // namespace
}  // namespace raymap::dds
