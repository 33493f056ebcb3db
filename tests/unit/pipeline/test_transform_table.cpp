// SPDX-License-Identifier: BSD-3-Clause
// TransformTable: /tf_static edges kept in any order and composed along chains.
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>

#include <gtest/gtest.h>

#include "src/pipeline/transform_table.hpp"

namespace raymap::pipeline {
namespace {

io::Pose at(double x, double y, double z, double yaw = 0.0) {
  io::Pose p;
  p.position = {x, y, z};
  p.orientation = {std::cos(0.5 * yaw), 0.0, 0.0, std::sin(0.5 * yaw)};
  return p;
}

TEST(TransformTable, ComposesAChainWhateverOrderItsEdgesCameIn) {
  // base_link -> mount (0.3 m forward, turned 90 degrees) -> os_sensor (1.2 m up), the child
  // edge first. A point 1 m ahead of the sensor lies 1 m to the left of the mount.
  TransformTable tf;
  ASSERT_TRUE(tf.set("mount", "os_sensor", at(0.0, 0.0, 1.2)));
  io::Pose pose;
  EXPECT_FALSE(tf.resolve("base_link", "os_sensor", &pose));  // not yet connected
  ASSERT_TRUE(tf.set("base_link", "mount", at(0.3, 0.0, 0.0, std::numbers::pi / 2)));
  ASSERT_TRUE(tf.resolve("base_link", "os_sensor", &pose));
  const Eigen::Vector3d p = pose.transform({1.0, 0.0, 0.0});
  EXPECT_NEAR(p.x(), 0.3, 1e-12);
  EXPECT_NEAR(p.y(), 1.0, 1e-12);
  EXPECT_NEAR(p.z(), 1.2, 1e-12);
  EXPECT_EQ(tf.size(), 2u);
}

TEST(TransformTable, ALaterEdgeForTheSameChildReplacesTheEarlier) {
  TransformTable tf;
  ASSERT_TRUE(tf.set("base_link", "lidar", at(0.0, 0.0, 0.5)));
  ASSERT_TRUE(tf.set("base_link", "lidar", at(0.0, 0.0, 0.7)));
  io::Pose pose;
  ASSERT_TRUE(tf.resolve("base_link", "lidar", &pose));
  EXPECT_DOUBLE_EQ(pose.position.z(), 0.7);
  EXPECT_EQ(tf.size(), 1u);
}

TEST(TransformTable, TheFrameItselfIsTheIdentityAndLoopsOrStrangersDoNotResolve) {
  TransformTable tf;
  io::Pose pose = at(1.0, 2.0, 3.0);
  ASSERT_TRUE(tf.resolve("base_link", "base_link", &pose));
  EXPECT_DOUBLE_EQ(pose.position.x(), 0.0);
  ASSERT_TRUE(tf.set("a", "b", at(1.0, 0.0, 0.0)));
  ASSERT_TRUE(tf.set("b", "a", at(1.0, 0.0, 0.0)));  // a loop (a broken tree)
  EXPECT_FALSE(tf.resolve("base_link", "a", &pose));
  EXPECT_FALSE(tf.resolve("base_link", "unknown", &pose));
}

TEST(TransformTable, AFullTableOrANameTooLongIsRefused) {
  TransformTable tf;
  const std::string long_name(TransformTable::kFrameChars, 'x');
  EXPECT_FALSE(tf.set("base_link", long_name.c_str(), at(0.0, 0.0, 0.0)));
  for (std::uint32_t i = 0; i < TransformTable::kMaxEdges; ++i) {
    char name[16];
    std::snprintf(name, sizeof(name), "f%u", i);
    ASSERT_TRUE(tf.set("base_link", name, at(0.0, 0.0, 0.0)));
  }
  EXPECT_FALSE(tf.set("base_link", "one_more", at(0.0, 0.0, 0.0)));
  EXPECT_TRUE(tf.set("base_link", "f7", at(0.0, 0.0, 1.0)));  // replacing still works
  EXPECT_EQ(tf.size(), TransformTable::kMaxEdges);
}

}  // namespace
}  // namespace raymap::pipeline
