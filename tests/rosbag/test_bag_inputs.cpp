// SPDX-License-Identifier: BSD-3-Clause
// What populate and replay take from a bag, and what they refuse (issue 52): a cloud frame with
// no way onto the base, a bag without clouds, DDS topic names, the pose source auto picks, a bag
// with nothing to publish.
#include <filesystem>

#include <gtest/gtest.h>

#include "tests/rosbag/bag_fixture.hpp"
#include "tests/service/service_fixture.hpp"
#include "tests/support/bag_spec.hpp"

namespace raymap::test {
namespace {

constexpr std::int64_t kInputsT0 = 1700000000000000000;

/// How a small bag is made: five 64-point clouds on `cloud_topic` in `cloud_frame`, poses at
/// 10 Hz from Odometry on /odom (`odometry_messages` of them) and/or TF odom -> base_link on /tf.
struct SmallBag {
  std::string cloud_topic = "/points";
  std::string cloud_frame = "lidar";
  bool tf_static = true;  ///< base_link -> lidar on /tf_static
  bool odometry_channel = true;
  bool odometry_messages = true;
  bool tf = false;
};

std::string writeSmallBag(const TempDir& dir, const std::string& name, const SmallBag& how) {
  const std::string spec = dir.file(name + ".jsonl");
  {
    BagSpecWriter w(spec);
    if (how.tf_static) {
      w.channel("/tf_static", "tf2_msgs/msg/TFMessage");
      w.tf("/tf_static", kInputsT0,
           {{kInputsT0, "base_link", how.cloud_frame, io::Pose{{0.1, 0.0, 0.5}}}});
    }
    if (how.odometry_channel) {
      w.channel("/odom", "nav_msgs/msg/Odometry");
    }
    if (how.tf) {
      w.channel("/tf", "tf2_msgs/msg/TFMessage");
    }
    if (!how.cloud_topic.empty()) {
      w.channel(how.cloud_topic, "sensor_msgs/msg/PointCloud2");
    }
    const std::vector<msgs::ScanPoint> points = ringCloud(64);
    const std::vector<std::uint16_t> rings(64, 0);
    for (int k = 0; k <= 5; ++k) {
      const std::int64_t t = kInputsT0 + k * 100000000LL;
      const io::Pose base{{0.1 * k, 0.0, 0.0}};
      if (how.odometry_messages) {
        w.odometry("/odom", t, t, "odom", "base_link", base);
      }
      if (how.tf) {
        w.tf("/tf", t, {{t, "odom", "base_link", base}});
      }
      if (k == 5 || how.cloud_topic.empty()) {
        continue;
      }
      w.ousterCloud(how.cloud_topic, t + 100000001, t, how.cloud_frame, points, rings);
    }
  }
  const std::string bag = dir.file(name + ".mcap");
  writeBag(spec, bag, {"--file-only"});
  return bag;
}

TEST(BagInputs, ACloudFrameWithNoChainToTheBaseIsAnErrorNamingTheFrames) {
  REQUIRE_NODE_HARNESS();
  TempDir dir;
  SmallBag how;
  how.tf_static = false;
  const std::string bag = writeSmallBag(dir, "no_static", how);
  const std::string map = dir.file("m.rmap");
  const RunResult r = runRaymap({"populate", bag, "-o", map, "-q"});
  EXPECT_EQ(r.exit_code, 1) << describe(r);
  EXPECT_TRUE(contains(r.err, bag));
  EXPECT_TRUE(contains(r.err, "frame 'lidar'"));
  EXPECT_TRUE(contains(r.err, "'base_link'"));
  EXPECT_TRUE(contains(r.err,
                       "the base with --sensor-offset (X,Y,Z metres; 0,0,0 if it is at "
                       "the base's origin), or --base-frame"))
      << r.err;
  EXPECT_FALSE(std::filesystem::exists(map));
  // Said explicitly, the sensor's place is taken as given.
  const RunResult given = runRaymap({"populate", bag, "--sensor-offset", "0,0,0", "-o", map, "-q"});
  EXPECT_EQ(given.exit_code, 0) << describe(given);
  // A cloud in the base frame itself needs no chain.
  how.cloud_frame = "base_link";
  const RunResult base =
      runRaymap({"populate", writeSmallBag(dir, "in_base", how), "-o", map, "-q"});
  EXPECT_EQ(base.exit_code, 0) << describe(base);
}

TEST(BagInputs, ABagWithoutCloudsOrImagesSaysSoAndListsItsTopicsWithTypes) {
  REQUIRE_NODE_HARNESS();
  TempDir dir;
  SmallBag how;
  how.cloud_topic = "";
  const std::string bag = writeSmallBag(dir, "no_clouds", how);
  const RunResult r = runRaymap({"populate", bag, "-o", dir.file("m.rmap"), "-q"});
  EXPECT_EQ(r.exit_code, 1) << describe(r);
  EXPECT_TRUE(contains(r.err, "no sensor_msgs/msg/PointCloud2 and no sensor_msgs/msg/Image topic"));
  EXPECT_TRUE(contains(r.err, "/odom (nav_msgs/msg/Odometry)"));
  EXPECT_TRUE(contains(r.err, "/tf_static (tf2_msgs/msg/TFMessage)"));
}

TEST(BagInputs, PopulateTakesDdsTopicNamesAsRaymapdAndReplayDo) {
  REQUIRE_NODE_HARNESS();
  TempDir dir;
  const std::string bag = writeSmallBag(dir, "names", SmallBag{});
  const std::string map = dir.file("m.rmap");
  const RunResult r = runRaymap({"populate", bag, "--topic", "rt/points", "--pose-topic", "rt/odom",
                                 "-o", map, "--stats-json", "-", "-q"});
  EXPECT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_EQ(jsonValue(r.out, "cloud_topics"), R"(["/points"])") << r.out;
  EXPECT_TRUE(std::filesystem::exists(map));
}

TEST(BagInputs, ReplayOfABagWithNothingToPublishFailsNamingItsTopics) {
  REQUIRE_NODE_HARNESS();
  TempDir dir;
  const std::string spec = dir.file("poses.jsonl");
  {
    BagSpecWriter w(spec);
    w.channel("/pose", "geometry_msgs/msg/PoseStamped");
    w.message("/pose", kInputsT0,
              "{\"header\":{\"stamp\":{\"sec\":1700000000,\"nanosec\":0},\"frame_id\":\"map\"},"
              "\"pose\":{\"position\":{\"x\":0,\"y\":0,\"z\":0},\"orientation\":{\"x\":0,"
              "\"y\":0,\"z\":0,\"w\":1}}}");
  }
  const std::string unknown = dir.file("poses.mcap");
  writeBag(spec, unknown, {"--file-only"});
  SmallBag how;
  how.cloud_topic = "";
  how.tf_static = false;
  how.odometry_messages = false;
  const std::string empty = writeSmallBag(dir, "silent", how);
  const std::string domain = std::to_string(uniqueDomain());
  for (const auto& [bag, why] : {std::pair{unknown, "/pose (geometry_msgs/msg/PoseStamped)"},
                                 std::pair{empty, "hold no message"}}) {
    const RunResult r = runRaymap({"replay", bag, "--domain", domain, "--wait", "0", "-q"});
    EXPECT_EQ(r.exit_code, 1) << describe(r);
    EXPECT_TRUE(contains(r.err, bag + ": nothing to play"));
    EXPECT_TRUE(contains(r.err, why));
  }
}

TEST(BagInputs, ReplayLeavesARecordedServicesDiagnosticsOutUnlessAsked) {
  // Issue 52, L12: a recording's /diagnostics, replayed beside the live raymapd, carried the
  // recorded service's statuses under the live one's hardware_id (OK and ERROR alternating).
  REQUIRE_NODE_HARNESS();
  TempDir dir;
  const std::string spec = dir.file("diag.jsonl");
  {
    BagSpecWriter w(spec);
    w.channel("/odom", "nav_msgs/msg/Odometry");
    w.channel("/diagnostics", "diagnostic_msgs/msg/DiagnosticArray");
    for (int k = 0; k < 3; ++k) {
      const std::int64_t t = kInputsT0 + k * 100000000LL;
      w.odometry("/odom", t, t, "odom", "base_link", io::Pose{});
      w.message("/diagnostics", t + 1,
                "{\"header\":{\"stamp\":{\"sec\":1700000000,\"nanosec\":0},\"frame_id\":\"\"},"
                "\"status\":[{\"level\":2,\"name\":\"raymapd: pipeline\",\"message\":\"stale\","
                "\"hardware_id\":\"robot/raymapd\",\"values\":[]}]}");
    }
  }
  const std::string bag = dir.file("diag.mcap");
  writeBag(spec, bag, {"--file-only"});
  const std::string domain = std::to_string(uniqueDomain());
  const RunResult left_out = runRaymap({"replay", bag, "--domain", domain, "--wait", "0", "--rate",
                                        "10", "-q", "--stats-json", "-"});
  EXPECT_EQ(left_out.exit_code, 0) << describe(left_out);
  EXPECT_TRUE(contains(left_out.err,
                       "topic /diagnostics (diagnostic_msgs/msg/DiagnosticArray) "
                       "is not replayed"));
  EXPECT_EQ(jsonValue(left_out.out, "log_messages"), "3") << left_out.out;
  const RunResult all = runRaymap({"replay", bag, "--domain", domain, "--wait", "0", "--rate", "10",
                                   "-q", "--include-outputs", "--stats-json", "-"});
  EXPECT_EQ(all.exit_code, 0) << describe(all);
  EXPECT_EQ(jsonValue(all.out, "log_messages"), "6") << all.out;
}

TEST(BagInputs, AutoPoseSourceTakesTfOverAnOdometryTopicWithoutMessagesAndSaysSo) {
  REQUIRE_NODE_HARNESS();
  TempDir dir;
  SmallBag how;
  how.odometry_messages = false;  // the topic was recorded, nothing was ever published on it
  how.tf = true;
  const std::string indexed = writeSmallBag(dir, "tf", how);
  const std::string sqlite = dir.file("tf_sqlite");  // no statistics: counted by reading
  writeBag(dir.file("tf.jsonl"), sqlite, {"--storage", "sqlite3"});
  for (const std::string& bag : {indexed, sqlite}) {
    // Into a file: on standard output the summary follows the JSON.
    const std::string stats = dir.file("stats.json");
    const RunResult r = runRaymap({"populate", bag, "--stats-json", stats});
    EXPECT_EQ(r.exit_code, 0) << describe(r);
    EXPECT_TRUE(contains(r.err,
                         "raymap populate: note: --pose-source auto: poses from /tf (6 "
                         "messages)"))
        << r.err;
    EXPECT_TRUE(contains(r.err, "/odom has no message"));
    EXPECT_EQ(jsonValue(readFile(stats), "pose_source"), "tf odom -> base_link") << r.out;
  }
}

}  // namespace
}  // namespace raymap::test
