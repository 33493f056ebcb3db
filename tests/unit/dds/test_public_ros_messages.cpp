// SPDX-License-Identifier: BSD-3-Clause
// raymap/ros_messages.hpp, the public decoders: messages serialized by the tests' own encoder
// (cdr_test_writer) and by raymap's serializers decode into the library's types, with times in the
// pose stamps' time base; damaged messages are errors naming the type and the reason.
#include <cmath>
#include <string>
#include <vector>

#include "raymap/ros_messages.hpp"
#include <gtest/gtest.h>

#include "src/msgs/depth_image_writer.hpp"
#include "src/msgs/point_cloud_writer.hpp"
#include "tests/unit/dds/cdr_test_writer.hpp"

namespace raymap {
namespace {

constexpr std::int64_t kStampNs = 1'700'000'000'250'000'000;

std::vector<msgs::ScanPoint> twoRowsOfPoints() {
  std::vector<msgs::ScanPoint> points;
  for (int i = 0; i < 20; ++i) {
    msgs::ScanPoint p{2.0f + 0.5f * static_cast<float>(i),
                      -1.0f,
                      0.25f,
                      0.005f * static_cast<float>(i),
                      static_cast<float>(i),
                      0u};
    if (i == 7) {
      p.flags = msgs::kPointNoReturn;
    }
    points.push_back(p);
  }
  return points;
}

TEST(PublicRosMessages, APointCloudDecodesToSensorPointsWithAbsoluteTimes) {
  const std::vector<msgs::ScanPoint> points = twoRowsOfPoints();
  std::vector<std::byte> bytes;
  msgs::serializeOusterCloud(kStampNs, "os_lidar", 2, points, {}, bytes);
  auto cloud = ros::decodePointCloud2(bytes);
  ASSERT_TRUE(cloud) << cloud.error().message;
  EXPECT_EQ(cloud->stamp_ns, kStampNs);
  EXPECT_EQ(cloud->frame_id, "os_lidar");
  EXPECT_EQ(cloud->height, 2u);
  EXPECT_EQ(cloud->width, 10u);
  EXPECT_TRUE(cloud->has_time);
  EXPECT_TRUE(cloud->has_intensity);
  EXPECT_EQ(cloud->no_return, 1u);
  ASSERT_EQ(cloud->points.size(), points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    const SensorPoint& p = cloud->points[i];
    EXPECT_EQ(p.no_return, i == 7) << i;
    if (i != 7) {
      EXPECT_EQ(p.position.x(), static_cast<double>(points[i].x)) << i;
      EXPECT_EQ(p.position.y(), -1.0) << i;
      EXPECT_EQ(p.position.z(), 0.25) << i;
    }
    EXPECT_EQ(p.intensity, points[i].intensity) << i;
    // The stamp plus the point's offset (whole nanoseconds on the wire): the odometry's time base.
    EXPECT_NEAR(p.time_s, 1'700'000'000.25 + 0.005 * static_cast<double>(i), 1e-6) << i;
  }
  // Without per-point times every point is at the stamp, and intensity can be left out.
  ros::PointCloudOptions options;
  options.time_field = "none";
  options.intensity_field.clear();
  auto plain = ros::decodePointCloud2(bytes, options);
  ASSERT_TRUE(plain) << plain.error().message;
  EXPECT_FALSE(plain->has_time || plain->has_intensity);
  EXPECT_EQ(plain->points[19].time_s, 1'700'000'000.25);
  EXPECT_EQ(plain->points[19].intensity, 0.0f);
}

TEST(PublicRosMessages, ANamedTimeFieldTheCloudLacksIsAnError) {
  std::vector<std::byte> bytes;
  msgs::serializeOusterCloud(kStampNs, "os_lidar", 2, twoRowsOfPoints(), {}, bytes);
  ros::PointCloudOptions options;
  options.time_field = "timestamp";
  auto cloud = ros::decodePointCloud2(bytes, options);
  ASSERT_FALSE(cloud);
  EXPECT_EQ(cloud.error().code, ErrorCode::kInvalidArgument);
  EXPECT_EQ(cloud.error().message.rfind("sensor_msgs/PointCloud2: ", 0), 0u)
      << cloud.error().message;
}

TEST(PublicRosMessages, OdometryAndTfDecodeToIsometries) {
  dds::test::TestPose pose;
  pose.t[0] = 1.5;
  pose.q[2] = std::sin(0.35);  // 0.7 rad about z (x, y, z, w)
  pose.q[3] = std::cos(0.35);
  for (const bool little : {true, false}) {
    auto odometry = ros::decodeOdometry(dds::test::encodeOdometry(pose, little));
    ASSERT_TRUE(odometry) << odometry.error().message;
    EXPECT_EQ(odometry->stamp_ns, 100'000'000'005);
    EXPECT_EQ(odometry->parent_frame, "odom");
    EXPECT_EQ(odometry->child_frame, "base_link");
    const Eigen::Vector3d moved = odometry->transform * Eigen::Vector3d(1.0, 0.0, 0.0);
    EXPECT_NEAR(moved.x(), 1.5 + std::cos(0.7), 1e-12);
    EXPECT_NEAR(moved.y(), 2.0 + std::sin(0.7), 1e-12);
    EXPECT_NEAR(moved.z(), 3.0, 1e-12);
  }
  std::vector<dds::test::TestPose> poses;
  for (const char* child : {"base_link", "os_lidar", "camera"}) {
    dds::test::TestPose p;
    p.child = std::string(child);
    poses.push_back(p);
  }
  auto tf = ros::decodeTfMessage(dds::test::encodeTfMessage(poses));
  ASSERT_TRUE(tf) << tf.error().message;
  ASSERT_EQ(tf->size(), 3u);
  EXPECT_EQ((*tf)[2].child_frame, "camera");
  EXPECT_EQ((*tf)[2].transform.translation(), Eigen::Vector3d(1.0, 2.0, 3.0));
  poses[1].q[3] = 0.0;  // one bad quaternion refuses the message
  auto bad = ros::decodeTfMessage(dds::test::encodeTfMessage(poses));
  ASSERT_FALSE(bad);
  EXPECT_EQ(bad.error().message, "tf2_msgs/TFMessage: bad_quaternion");
}

TEST(PublicRosMessages, CameraInfoGivesTheIntrinsics) {
  CameraIntrinsics camera;
  camera.width = 640;
  camera.height = 480;
  camera.fx = 385.0;
  camera.fy = 386.0;
  camera.cx = 320.5;
  camera.cy = 240.5;
  std::vector<std::byte> bytes;
  msgs::serializeCameraInfo(kStampNs, "camera_depth_optical_frame", camera, bytes);
  auto info = ros::decodeCameraInfo(bytes);
  ASSERT_TRUE(info) << info.error().message;
  EXPECT_EQ(info->stamp_ns, kStampNs);
  EXPECT_EQ(info->frame_id, "camera_depth_optical_frame");
  EXPECT_EQ(info->camera.width, 640u);
  EXPECT_EQ(info->camera.fy, 386.0);
  EXPECT_EQ(info->camera.cx, 320.5);
  EXPECT_EQ(info->camera.distortion, DistortionModel::kNone);
}

TEST(PublicRosMessages, DamagedMessagesAreErrorsNamingTheTypeAndReason) {
  std::vector<std::byte> cloud;
  msgs::serializeOusterCloud(kStampNs, "os_lidar", 2, twoRowsOfPoints(), {}, cloud);
  cloud.resize(cloud.size() / 2);
  auto c = ros::decodePointCloud2(cloud);
  ASSERT_FALSE(c);
  EXPECT_EQ(c.error().message, "sensor_msgs/PointCloud2: truncated");
  const std::vector<std::byte> two_bytes(2);
  auto o = ros::decodeOdometry(two_bytes);
  ASSERT_FALSE(o);
  EXPECT_EQ(o.error().message.rfind("nav_msgs/Odometry: ", 0), 0u) << o.error().message;
  auto i = ros::decodeCameraInfo(two_bytes);
  ASSERT_FALSE(i);
  EXPECT_EQ(i.error().message.rfind("sensor_msgs/CameraInfo: ", 0), 0u) << i.error().message;
}

}  // namespace
}  // namespace raymap
