// SPDX-License-Identifier: BSD-3-Clause
// `raymap replay BAG` into raymapd, as `ros2 bag play` would feed a robot's bag to it: the
// /tf_static latched before the first cloud, the pose from a TF chain, the cloud's frame learned
// from the data. And `raymap record --format mcap` read back by Foxglove's MCAP reader, every
// message of every type raymapd and raymap replay send decoded and re-serialized to the same
// bytes by Foxglove's ROS 2 serializer.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <optional>
#include <string>

#include <gtest/gtest.h>
#include <signal.h>

#include "tests/replay/replay_harness.hpp"
#include "tests/rosbag/bag_fixture.hpp"
#include "tests/service/service_fixture.hpp"
#include "tests/support/json_doc.hpp"

namespace raymap::test {
namespace {

/// The member `key`, or a null value when there is none (the expectation then fails).
const Json& member(const Json& v, const std::string& key) {
  static const Json kNull;
  const Json* found = findPath(v, {key});
  return found != nullptr ? *found : kNull;
}

/// A string's text ("" for any other value) and a number's value (NaN for any other value).
std::string textOf(const Json& v) { return v.is_string() ? v.get<std::string>() : std::string(); }
double numberOf(const Json& v) { return v.is_number() ? v.get<double>() : std::nan(""); }

double diagnostic(const Watcher& w, const std::string& key) {
  return w.diagnostics->number(key).value_or(-1.0);
}

/// raymapd for the bag drive: clouds on /ouster/points in a frame it learns (os_sensor), the
/// base's pose from TF map -> odom -> base_link, the extrinsic from /tf_static; every point
/// taken (no latency bound), a Nav2 costmap beside the GridMap. The scan queue holds a whole
/// drive: nothing may be dropped, and a machine too slow for 10 scans/s (a sanitizer build on a
/// busy runner) falls behind rather than dropping the oldest.
std::string bagDriveConfig(std::uint32_t domain) {
  std::string text = serviceConfig(domain, "", 32);
  const auto replace = [&](const std::string& from, const std::string& to) {
    const std::size_t at = text.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    text.replace(at, from.size(), to);
  };
  replace("pose: {source: odometry, topic: rt/odom, world_frame: odom, base_frame: base_link}",
          "pose: {source: tf, world_frame: map, base_frame: base_link}");
  replace("topic: rt/points, frame: lidar,", "topic: /ouster/points,");
  replace("queues: {", "queues: {max_latency_s: 0, ");
  replace("dds: {", "dds: {costmap_topic: /costmap, ");
  return text;
}

TEST(BagReplay, ABagPlayedIntoRaymapdGivesTrueHeightsFromItsTfChainAndStaticExtrinsic) {
  REQUIRE_NODE_HARNESS();
  TempDir dir;
  const int scans = 25;
  const Drive drive = makeDrive(dir, DrivePoses::kTfChain, scans);
  const std::string bag = dir.file("drive_bag");
  writeBag(drive.spec, bag, {"--compression", "lz4"});
  const std::uint32_t domain = uniqueDomain();
  Daemon daemon(dir, bagDriveConfig(domain));
  Watcher watcher(domain);
  watcher.collect(kStartWaitS, [&] { return watcher.grid_maps->matchedWriters() > 0; });
  ASSERT_GT(watcher.grid_maps->matchedWriters(), 0u) << daemon.log();
  auto replay = startRaymap({"replay", bag, "--domain", std::to_string(domain), "--stats-json",
                             dir.file("replay.json"), "-q"},
                            dir.file("replay.log"));
  watcher.collect(60.0, [&] { return !replay->running(); });
  const auto status = replay->stop(SIGTERM, std::chrono::milliseconds(100));
  ASSERT_TRUE(status.has_value());
  EXPECT_EQ(status->first, 0) << readFile(dir.file("replay.log"));
  // A report with every scan in (a slow machine may still be integrating), then the GridMaps
  // with the last of them, until the map goes stale and they stop.
  watcher.collect(kStartWaitS, [&] {
    return diagnostic(watcher, "raymapd: pipeline/scans_integrated") >= scans;
  });
  watcher.collectUntilQuiet(2.0, kStartWaitS);

  EXPECT_EQ(diagnostic(watcher, "raymapd: pipeline/clouds_received"), scans) << daemon.log();
  EXPECT_EQ(diagnostic(watcher, "raymapd: pipeline/scans_integrated"), scans);
  EXPECT_EQ(diagnostic(watcher, "raymapd: pipeline/scans_dropped_no_pose"), 0);
  EXPECT_GE(diagnostic(watcher, "raymapd: pipeline/extrinsics_from_tf"), 1)
      << "the extrinsic comes from the bag's /tf_static";
  ASSERT_FALSE(watcher.maps.empty());
  const HeightCheck heights = checkHeights(watcher.maps.back(), drive.scene);
  ASSERT_GT(heights.surfaces, 300);
  EXPECT_GT(static_cast<double>(heights.within) / heights.surfaces, 0.9)
      << heights.within << " of " << heights.surfaces
      << " surface cells within a voxel of the truth";
}

// Found by the soak (tools/soak.sh SOAK_BAG=1): replay also made its simulated driver's idle
// writers for a bag, and on the bag's own /odom they were a second pose source to raymapd (ERROR:
// "two pose sources for one robot") for the whole replay.
TEST(BagReplay, ABagWithOdometryIsTheOnlyPublisherOfItsTopics) {
  REQUIRE_NODE_HARNESS();
  TempDir dir;
  const int scans = 10;
  const Drive drive = makeDrive(dir, DrivePoses::kOdometry, scans);
  const std::string bag = dir.file("drive_bag");
  writeBag(drive.spec, bag, {});
  const std::uint32_t domain = uniqueDomain();
  std::string config = serviceConfig(domain, "", 32);
  const std::size_t at = config.find("topic: rt/points, frame: lidar,");
  ASSERT_NE(at, std::string::npos);
  config.replace(at, 31, "topic: /ouster/points,");
  Daemon daemon(dir, config);
  Watcher watcher(domain);
  watcher.collect(kStartWaitS, [&] { return watcher.grid_maps->matchedWriters() > 0; });
  ASSERT_GT(watcher.grid_maps->matchedWriters(), 0u) << daemon.log();
  auto replay = startRaymap({"replay", bag, "--domain", std::to_string(domain), "--loop", "-q"},
                            dir.file("replay.log"));
  // Reports while the bag plays (in a loop, so that several come): one writer of each input.
  double most_pose_publishers = 0.0;
  double most_cloud_publishers = 0.0;
  int reports = 0;
  double last_stamp = -1.0;
  watcher.collect(60.0, [&] {
    const double integrated = diagnostic(watcher, "raymapd: pipeline/scans_integrated");
    if (integrated > 0 && integrated != last_stamp) {
      last_stamp = integrated;
      ++reports;
      most_pose_publishers =
          std::max(most_pose_publishers, diagnostic(watcher, "raymapd: pipeline/pose_publishers"));
      most_cloud_publishers =
          std::max(most_cloud_publishers, diagnostic(watcher, "raymapd: sensor lidar/publishers"));
    }
    return reports >= 4;
  });
  ASSERT_TRUE(replay->stop(SIGINT, std::chrono::milliseconds(5000)).has_value());
  ASSERT_GE(reports, 4) << daemon.log();
  EXPECT_EQ(most_pose_publishers, 1.0) << daemon.log();
  EXPECT_EQ(most_cloud_publishers, 1.0) << daemon.log();
}

TEST(BagRecord, ALiveRunRecordedAsMcapIsReadAndReserializedByFoxglovesLibraries) {
  REQUIRE_NODE_HARNESS();
  TempDir dir;
  const int scans = 20;
  const Drive drive = makeDrive(dir, DrivePoses::kTfChain, scans);
  const std::string bag = dir.file("drive_bag");
  writeBag(drive.spec, bag, {});
  const std::uint32_t domain = uniqueDomain();
  Daemon daemon(dir, bagDriveConfig(domain));
  Watcher watcher(domain);
  watcher.collect(kStartWaitS, [&] { return watcher.grid_maps->matchedWriters() > 0; });
  ASSERT_GT(watcher.grid_maps->matchedWriters(), 0u) << daemon.log();
  const std::string recorded = dir.file("recorded");
  auto recorder = startRaymap({"record",
                               "--format",
                               "mcap",
                               "--compression",
                               "zstd",
                               "-o",
                               recorded,
                               "--domain",
                               std::to_string(domain),
                               "-t",
                               "/ouster/points",
                               "-t",
                               "/tf",
                               "-t",
                               "/tf_static",
                               "-t",
                               "/height_map",
                               "-t",
                               "/diagnostics",
                               "-t",
                               "/costmap"},
                              dir.file("record.log"));
  // The recorder has found raymapd's topics (the replay's come with the replay, which waits for
  // its subscribers and gives their side a second more to match).
  const auto recording = [&](const char* topic) {
    return readFile(dir.file("record.log")).find(std::string("recording ") + topic) !=
           std::string::npos;
  };
  watcher.collect(kStartWaitS, [&] {
    return recording("rt/height_map") && recording("rt/diagnostics") && recording("rt/costmap");
  });
  ASSERT_TRUE(recording("rt/height_map")) << readFile(dir.file("record.log"));
  auto replay = startRaymap({"replay", bag, "--domain", std::to_string(domain), "-q"},
                            dir.file("replay.log"));
  watcher.collect(60.0, [&] { return !replay->running(); });
  watcher.collect(1.5);  // the last maps and a diagnostics report
  const auto stopped = recorder->stop(SIGINT, kStopWait);
  ASSERT_TRUE(stopped.has_value());
  ASSERT_EQ(stopped->first, 0) << readFile(dir.file("record.log"));
  ASSERT_TRUE(std::filesystem::exists(recorded + "/metadata.yaml"))
      << readFile(dir.file("record.log"));
  EXPECT_FALSE(std::filesystem::exists(recorded + ".partial"));

  const RunResult read = runHarness("read_mcap.mjs", {recorded + "/recorded_0.mcap"});
  ASSERT_EQ(read.exit_code, 0) << describe(read);
  const auto json = parseJson(read.out);
  ASSERT_TRUE(json.has_value()) << read.out;
  EXPECT_EQ(textOf(member(*json, "profile")), "ros2");
  EXPECT_TRUE(member(*json, "errors").empty()) << read.out;
  std::map<std::string, const Json*> topics;
  for (const Json& t : member(*json, "topics")) {
    const std::string name = textOf(member(t, "topic"));
    topics[name] = &t;
    const double count = numberOf(member(t, "count"));
    EXPECT_GT(count, 0.0) << name;
    // read_mcap.mjs leaves out reencoded_identical_but_end_padding when there is none.
    EXPECT_EQ(numberOf(member(t, "reencoded_identical")) +
                  t.value("reencoded_identical_but_end_padding", 0.0),
              count)
        << name << ": Foxglove's serializer gives other bytes";
  }
  for (const char* topic :
       {"/ouster/points", "/tf", "/tf_static", "/height_map", "/diagnostics", "/costmap"}) {
    EXPECT_EQ(topics.count(topic), 1u) << topic << " missing from " << read.out;
  }
  if (topics.count("/ouster/points") == 1) {
    EXPECT_EQ(numberOf(member(*topics["/ouster/points"], "count")), scans);
    EXPECT_EQ(textOf(member(*topics["/ouster/points"], "type")), "sensor_msgs/msg/PointCloud2");
  }
  if (topics.count("/costmap") == 1) {
    const Json& info = member(member(*topics["/costmap"], "last"), "info");
    EXPECT_NEAR(numberOf(member(info, "resolution")), 0.1, 1e-6);
    EXPECT_EQ(textOf(member(*topics["/costmap"], "type")), "nav_msgs/msg/OccupancyGrid");
  }
  if (topics.count("/height_map") == 1) {
    EXPECT_EQ(textOf(member(*topics["/height_map"], "type")), "grid_map_msgs/msg/GridMap");
  }
  // raymap's own reader agrees.
  const RunResult info = runRaymap({"info", recorded, "--json"});
  EXPECT_EQ(info.exit_code, 0) << describe(info);
  const std::optional<Json> listed = parseJson(info.out);
  ASSERT_TRUE(listed.has_value());
  bool height_map_listed = false;
  for (const Json& t : member(*listed, "topics")) {
    height_map_listed = height_map_listed || textOf(member(t, "name")) == "/height_map";
  }
  EXPECT_TRUE(height_map_listed) << info.out;
}

}  // namespace
}  // namespace raymap::test
