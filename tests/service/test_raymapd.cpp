// SPDX-License-Identifier: BSD-3-Clause
// raymapd end to end, as separate processes on loopback DDS: a ROS-like lidar driver publishes,
// raymapd maps, an independent subscriber decodes the GridMaps; systemd's notify protocol is
// checked with a fake notify socket.
#include <algorithm>
#include <cmath>
#include <fstream>
#include <numeric>
#include <string>
#include <thread>

#include "sensor_msgs.h"
#include <gtest/gtest.h>
#include <signal.h>

#include "platform/clock.hpp"
#include "src/dds/topic_types.hpp"
#include "src/msgs/occupancy_grid_decode.hpp"
#include "src/sim/scene.hpp"
#include "tests/service/daemon_process.hpp"
#include "tests/service/service_fixture.hpp"
#include "tests/support/cli_runner.hpp"
#include "tests/support/fake_notify_socket.hpp"
#include "tests/support/scene_truth.hpp"

namespace raymap::test {
namespace {

TEST(Raymapd, PublishesDecodableGridMapsAtFiveHertzWithTrueHeightsUnderSystemd) {
  const std::uint32_t domain = uniqueDomain();
  RunningDaemon daemon(serviceConfig(domain), true);
  // READY=1 only once everything is created and the threads run.
  const auto ready = daemon.notify.waitFor("READY=1", kStartWait);
  ASSERT_TRUE(ready.has_value()) << daemon.log();
  EXPECT_TRUE(ready->value("STATUS").has_value());

  RosSide ros(domain, 70000);
  ASSERT_TRUE(ros.waitForService(kStartWaitS)) << daemon.log();
  const driver::SimulatedLidar lidar = yardLidar(32, 1024, /*moving=*/true);
  driver::PlaybackOptions options;
  std::vector<driver::ReceivedGridMap> maps;
  ros.play(lidar, options, 6.0, maps);

  // In order and at about 5 Hz, from the subscriber's arrival times. How close to 200 ms the
  // period is, is a figure of the machine: run-daemon-benchmarks.sh records it.
  ASSERT_GE(maps.size(), fewestMaps(6.0)) << daemon.log();
  expectInOrderAtAboutFiveHertz(maps);

  // The bytes decoded as grid_map_msgs/GridMap (Cyclone's own deserialiser): layout and layers.
  const driver::ReceivedGridMap& last = maps.back();
  EXPECT_EQ(last.frame_id, "odom");
  EXPECT_DOUBLE_EQ(last.resolution, 0.1);
  EXPECT_NEAR(last.length_x, 12.0, 1e-9);
  EXPECT_NEAR(last.length_y, 12.0, 1e-9);
  ASSERT_EQ(last.layers,
            (std::vector<std::string>{"elevation", "clearance", "kind", "observed_count"}));
  EXPECT_EQ(last.basic_layers, std::vector<std::string>{"elevation"});
  ASSERT_EQ(last.dim_labels, (std::vector<std::string>{"column_index", "row_index"}));
  EXPECT_EQ(last.dim_sizes, (std::vector<std::uint32_t>{120, 120}));
  EXPECT_EQ(last.dim_strides, (std::vector<std::uint32_t>{14400, 120}));
  ASSERT_EQ(last.data.size(), 4u);
  for (const auto& layer : last.data) {
    ASSERT_EQ(layer.size(), 14400u);
  }
  // The robot ended at the path's end, (4, 0): the map is centred there (to the cell).
  EXPECT_NEAR(last.centre_x, 4.0, 0.1);
  EXPECT_NEAR(last.centre_y, 0.0, 0.1);

  // Heights: every surface cell against the scene's exact surface.
  const HeightCheck heights = checkHeights(last, lidar.scene());
  EXPECT_GE(heights.surfaces, 14400 / 4) << "too little of the map observed";
  EXPECT_GE(heights.within, heights.surfaces * 95 / 100)
      << heights.within << " of " << heights.surfaces;

  // Watchdog: pinged after every cycle, while the last maps go out and after they stop (the
  // input ended: stale, withheld), never silent for WatchdogSec (1 s, WATCHDOG_USEC), or systemd
  // would restart the service. The pings come every cycle (200 ms); the widest gap is recorded
  // by run-daemon-benchmarks.sh (watchdog_gap_max_ms).
  const auto from = std::chrono::steady_clock::now();
  const auto pings = daemon.notify.collectFor(std::chrono::milliseconds(3000));
  const auto silence =
      FakeNotifySocket::longestSilence(pings, "WATCHDOG=1", from, std::chrono::steady_clock::now());
  EXPECT_LT(silence, std::chrono::seconds(1))
      << std::chrono::duration_cast<std::chrono::milliseconds>(silence).count() << " ms";

  // SIGTERM: STOPPING=1 and a clean exit (the stop time is recorded by the benchmark too).
  const auto stopped = daemon.process->stop(SIGTERM, kStopWait);
  ASSERT_TRUE(stopped.has_value()) << daemon.log();
  EXPECT_EQ(stopped->first, 0) << daemon.log();
  EXPECT_TRUE(daemon.notify.waitFor("STOPPING=1", kStopWait).has_value());
}

/// A PointCloud2 with one x/y/z field set: fields[i] = (name, offset, datatype), everything else
/// as given. `data` is what the message carries.
struct BadCloud {
  std::vector<std::string> names;
  std::vector<sensor_msgs_msg_dds__PointField_> fields;
  std::vector<std::uint8_t> data;
  sensor_msgs_msg_dds__PointCloud2_ msg{};

  BadCloud(std::vector<std::tuple<std::string, std::uint32_t, std::uint8_t>> layout,
           std::uint32_t width, std::uint32_t height, std::uint32_t point_step,
           std::size_t data_bytes) {
    for (const auto& [name, offset, type] : layout) {
      names.push_back(name);
      (void)offset;
      (void)type;
    }
    for (std::size_t i = 0; i < layout.size(); ++i) {
      sensor_msgs_msg_dds__PointField_ f{};
      f.name = names[i].data();
      f.offset = std::get<1>(layout[i]);
      f.datatype = std::get<2>(layout[i]);
      f.count = 1;
      fields.push_back(f);
    }
    data.assign(data_bytes, 0x3f);
    // NOLINTNEXTLINE(cppcoreguidelines-pro-type-const-cast): read-only for dds_write
    msg.header.frame_id = const_cast<char*>("lidar");
    msg.width = width;
    msg.height = height;
    msg.point_step = point_step;
    msg.row_step = width * point_step;
    msg.fields._buffer = fields.data();
    msg.fields._length = msg.fields._maximum = static_cast<std::uint32_t>(fields.size());
    msg.data._buffer = data.data();
    msg.data._length = msg.data._maximum = static_cast<std::uint32_t>(data.size());
  }
};

TEST(Raymapd, CountsAndDropsMalformedCloudsAndKeepsPublishing) {
  const std::uint32_t domain = uniqueDomain();
  RunningDaemon daemon(serviceConfig(domain), false);
  ASSERT_TRUE(daemon.notify.waitFor("READY=1", kStartWait).has_value()) << daemon.log();
  RosSide ros(domain, 70000);
  ASSERT_TRUE(ros.waitForService(kStartWaitS));
  constexpr std::uint8_t kInt8 = 1;
  constexpr std::uint8_t kFloat32 = 7;
  std::vector<BadCloud> bad;
  // x as INT8: a wrong field type.
  bad.emplace_back(
      std::vector<std::tuple<std::string, std::uint32_t, std::uint8_t>>{
          {"x", 0, kInt8}, {"y", 4, kFloat32}, {"z", 8, kFloat32}},
      10, 1, 16, 160);
  // Truncated: 10 points declared, 3 carried.
  bad.emplace_back(
      std::vector<std::tuple<std::string, std::uint32_t, std::uint8_t>>{
          {"x", 0, kFloat32}, {"y", 4, kFloat32}, {"z", 8, kFloat32}},
      10, 1, 16, 48);
  // point_step smaller than the fields.
  bad.emplace_back(
      std::vector<std::tuple<std::string, std::uint32_t, std::uint8_t>>{
          {"x", 0, kFloat32}, {"y", 4, kFloat32}, {"z", 8, kFloat32}},
      10, 1, 8, 80);
  // Absurd size: 2^31 x 2 points in 64 bytes.
  bad.emplace_back(
      std::vector<std::tuple<std::string, std::uint32_t, std::uint8_t>>{
          {"x", 0, kFloat32}, {"y", 4, kFloat32}, {"z", 8, kFloat32}},
      0x80000000u, 2, 16, 64);
  // No z field.
  bad.emplace_back(
      std::vector<std::tuple<std::string, std::uint32_t, std::uint8_t>>{{"x", 0, kFloat32},
                                                                        {"y", 4, kFloat32}},
      10, 1, 16, 160);
  constexpr int kRepeats = 4;
  for (int r = 0; r < kRepeats; ++r) {
    for (BadCloud& b : bad) {
      ASSERT_TRUE(ros.publisher->cloudWriter().write(&b.msg).has_value());
      platform::sleepUntilMonotonicNs(platform::monotonicNowNs() + 5000000);
    }
  }
  // Then good data: the service still maps and publishes.
  const driver::SimulatedLidar lidar = yardLidar(16, 512, false);
  std::vector<driver::ReceivedGridMap> maps;
  ros.play(lidar, driver::PlaybackOptions{}, 3.0, maps);
  ros.settle(1.5, &maps);
  EXPECT_TRUE(daemon.process->running()) << daemon.log();
  const auto malformed = ros.diagnostics->number("raymapd: pipeline/clouds_malformed");
  const auto too_large = ros.diagnostics->number("raymapd: pipeline/clouds_too_large");
  ASSERT_TRUE(malformed.has_value()) << "no diagnostics received";
  // Loopback best effort delivers these small messages; allow a loss or two all the same.
  EXPECT_GE(*malformed + too_large.value_or(0.0), 0.8 * static_cast<double>(bad.size() * kRepeats));
  EXPECT_GT(ros.diagnostics->number("raymapd: pipeline/scans_integrated").value_or(0.0), 10.0);
  // Maps from 3 s of input and the second after it (then the map is stale and withheld).
  EXPECT_GE(maps.size(), fewestMaps(4.0));
  const auto stopped = daemon.process->stop(SIGTERM, kStopWait);
  ASSERT_TRUE(stopped.has_value());
  EXPECT_EQ(stopped->first, 0) << daemon.log();
}

TEST(Raymapd, OverflowAtTenTimesTheInputRateDropsOldestScansAndKeepsPublishing) {
  const std::uint32_t domain = uniqueDomain();
  RunningDaemon daemon(serviceConfig(domain, "", /*scan_slots=*/2), false);
  ASSERT_TRUE(daemon.notify.waitFor("READY=1", kStartWait).has_value()) << daemon.log();
  RosSide ros(domain, 70000);
  ASSERT_TRUE(ros.waitForService(kStartWaitS));
  // A 10 Hz lidar played at 100 Hz: 32 x 1024 points per scan, 3.3 M points/s.
  const driver::SimulatedLidar lidar = yardLidar(32, 1024, false);
  driver::PlaybackOptions options;
  options.scan_rate_hz = 100.0;
  std::vector<driver::ReceivedGridMap> maps;
  ros.play(lidar, options, 5.0, maps);
  // The overload is reported while it lasts, with its cause.
  const std::string level = ros.diagnostics->values().at("raymapd: pipeline/level");
  const std::string message = ros.diagnostics->values().at("raymapd: pipeline/message");
  EXPECT_EQ(level, "1") << message;
  EXPECT_TRUE(message.find("oldest first") != std::string::npos ||
              message.find("shed") != std::string::npos ||
              message.find("cut short") != std::string::npos)
      << message;
  ros.settle(1.2, &maps);
  EXPECT_TRUE(daemon.process->running()) << daemon.log();
  const double dropped =
      ros.diagnostics->number("raymapd: pipeline/clouds_dropped_overflow").value_or(0.0);
  const double received = ros.diagnostics->number("raymapd: pipeline/clouds_received").value_or(0);
  const double integrated =
      ros.diagnostics->number("raymapd: pipeline/scans_integrated").value_or(0.0);
  EXPECT_GT(dropped, 0.0) << "100 Hz of 32k-point scans should overflow 2 slots";
  // Dropped before they were decoded: one scan waits decoded, the other as received, and only
  // undecoded ones are dropped (docs/raymapd.md, Overflow).
  EXPECT_EQ(ros.diagnostics->number("raymapd: pipeline/clouds_dropped_before_decode").value_or(-1),
            dropped);
  EXPECT_GT(integrated, 0.0);
  EXPECT_LE(integrated + dropped, received);  // every received cloud is counted once
  EXPECT_LE(ros.diagnostics->number("raymapd: pipeline/scan_queue_depth").value_or(99.0), 2.0);
  // Still publishing, in order, at about 5 Hz. How well the publish instants hold under
  // overload is what run-overload-benchmarks.sh measures (map_period_error_ms, cycles_late).
  ASSERT_GE(maps.size(), fewestMaps(5.0));
  expectInOrderAtAboutFiveHertz(maps);
  const auto stopped = daemon.process->stop(SIGTERM, kStopWait);
  ASSERT_TRUE(stopped.has_value());
  EXPECT_EQ(stopped->first, 0) << daemon.log();
}

TEST(Raymapd, TakesThePoseFromTfAndPublishesOccupiedVoxelsWhileSubscribed) {
  const std::uint32_t domain = uniqueDomain();
  std::string config = serviceConfig(domain);
  config.replace(config.find("source: odometry"), 16, "source: tf");
  RunningDaemon daemon(config, false);
  ASSERT_TRUE(daemon.notify.waitFor("READY=1", kStartWait).has_value()) << daemon.log();
  RosSide ros(domain, 70000);
  auto voxels = dds::RawReader::create(*ros.subscriber_participant, "rt/raymap/occupied_voxels",
                                       dds::pointCloud2Type(), dds::Reliability::kReliable, 4);
  ASSERT_TRUE(voxels.has_value());
  ASSERT_TRUE(ros.waitForService(kStartWaitS));
  const driver::SimulatedLidar lidar = yardLidar(32, 1024, /*moving=*/false);
  driver::PlaybackOptions options;
  options.pose_as_tf = true;
  std::vector<driver::ReceivedGridMap> maps;
  ros.play(lidar, options, 3.0, maps);
  ros.settle(1.2, &maps);

  // The map follows the TF pose: centred on the path's start (-6, -1), to the cell.
  ASSERT_GE(maps.size(), fewestMaps(3.0)) << daemon.log();
  EXPECT_NEAR(maps.back().centre_x, -6.0, 0.1);
  EXPECT_NEAR(maps.back().centre_y, -1.0, 0.1);
  const HeightCheck heights = checkHeights(maps.back(), lidar.scene());
  EXPECT_GE(heights.surfaces, 1000);
  EXPECT_GE(heights.within, heights.surfaces * 95 / 100);
  EXPECT_GT(ros.diagnostics->number("raymapd: pipeline/poses_received").value_or(0.0), 100.0);

  // Occupied voxels at 1 Hz while this reader is matched: voxel centres on the scene's surfaces.
  std::vector<msgs::ScanPoint> points(200000);
  int clouds = 0;
  std::uint32_t occupied = 0;
  std::uint32_t on_grid = 0;
  voxels->takeEach(
      [&](std::span<const std::byte> cdr, std::int64_t) {
        auto header = msgs::decodePointCloud2(cdr, points, msgs::CloudDecodeOptions{});
        if (!header) {
          return;
        }
        ++clouds;
        occupied = header.value().points;
        on_grid = 0;
        for (std::uint32_t k = 0; k < occupied; ++k) {
          const double fx = static_cast<double>(points[k].x) / 0.1;
          const double fy = static_cast<double>(points[k].y) / 0.1;
          on_grid += std::fabs(fx - std::floor(fx) - 0.5) < 1e-3 &&
                             std::fabs(fy - std::floor(fy) - 0.5) < 1e-3
                         ? 1u
                         : 0u;
        }
      },
      16);
  EXPECT_GE(clouds, 1);
  EXPECT_GT(occupied, 1000u);
  EXPECT_EQ(on_grid, occupied);
  const auto stopped = daemon.process->stop(SIGTERM, kStopWait);
  ASSERT_TRUE(stopped.has_value());
  EXPECT_EQ(stopped->first, 0) << daemon.log();
}

/// Plays a still 32 x 1024 lidar in the yard for 3 s (then 0.5 s to settle) and checks that the
/// last GridMap, one of at least fewestMaps(3.0), has the scene's heights on 95 % of at least
/// 1,000 surface cells. @return that GridMap's frame.
std::string expectSceneHeightsAfterPlaying(RosSide& ros, RunningDaemon& daemon,
                                           const driver::PlaybackOptions& options) {
  const driver::SimulatedLidar lidar = yardLidar(32, 1024, /*moving=*/false);
  std::vector<driver::ReceivedGridMap> maps;
  ros.play(lidar, options, 3.0, maps);
  ros.settle(0.5, &maps);
  if (maps.size() < fewestMaps(3.0)) {
    ADD_FAILURE() << maps.size() << " GridMaps\n" << daemon.log();
    return {};
  }
  const HeightCheck heights = checkHeights(maps.back(), lidar.scene());
  EXPECT_GE(heights.surfaces, 1000);
  EXPECT_GE(heights.within, heights.surfaces * 95 / 100)
      << heights.within << " of " << heights.surfaces;
  return maps.back().frame_id;
}

TEST(Raymapd, UsesTheLatchedTfStaticExtrinsicPublishedBeforeItStarted) {
  const std::uint32_t domain = uniqueDomain();
  // The lidar sits 0.5 m above base_link; only /tf_static says so (the YAML's extrinsic is the
  // identity), and it is published before raymapd exists, as a robot's static_transform_publisher
  // runs before a restarted service.
  RosSide ros(domain, 70000);
  ros.publisher->publishTfStatic(io::Pose{{0.0, 0.0, 0.5}}, "base_link", "lidar");
  std::string config = serviceConfig(domain);
  config.replace(config.find("base_height: 1.2"), 16, "base_height: 0.7");
  RunningDaemon daemon(config, false);
  ASSERT_TRUE(daemon.notify.waitFor("READY=1", kStartWait).has_value()) << daemon.log();
  ASSERT_TRUE(ros.waitForService(kStartWaitS));
  driver::PlaybackOptions options;
  options.sensor_in_base = {0.0, 0.0, 0.5};  // the published base pose is 0.5 m below the lidar
  // With the extrinsic ignored every surface would come out 0.5 m low.
  expectSceneHeightsAfterPlaying(ros, daemon, options);
  expectCleanStop(daemon);
}

TEST(Raymapd, ResolvesATfStaticChainThatArrivedBeforeTheFirstCloudWithTheFrameLearned) {
  const std::uint32_t domain = uniqueDomain();
  // As robots publish it: sensors[].frame left to the first cloud (""), and the lidar 0.5 m
  // above base_link through a mount (base_link -> mount 0.3 m, mount -> lidar 0.2 m), both
  // edges on /tf_static before any cloud, the child edge first. The YAML's extrinsic is the
  // identity. Before, a transform that came before the sensor's frame was known was dropped.
  std::string config = serviceConfig(domain);
  config.replace(config.find("frame: lidar,"), 13, "frame: \"\",");
  config.replace(config.find("base_height: 1.2"), 16, "base_height: 0.7");
  RunningDaemon daemon(config, false);
  ASSERT_TRUE(daemon.notify.waitFor("READY=1", kStartWait).has_value()) << daemon.log();
  RosSide ros(domain, 70000);
  ASSERT_TRUE(ros.waitForService(kStartWaitS));
  // In one latched TFMessage, as robot_state_publisher sends them (two messages on a keep-last-1
  // writer could lose the first before it is delivered).
  const driver::DriverPublisher::StaticEdge chain[] = {
      {io::Pose{{0.0, 0.0, 0.2}}, "mount", "lidar"},
      {io::Pose{{0.0, 0.0, 0.3}}, "base_link", "mount"}};
  ros.publisher->publishTfStatic(chain);
  driver::PlaybackOptions options;
  options.sensor_in_base = {0.0, 0.0, 0.5};  // the published base pose is 0.5 m below the lidar
  expectSceneHeightsAfterPlaying(ros, daemon, options);
  EXPECT_EQ(ros.diagnostics->number("raymapd: pipeline/tf_static_edges").value_or(0.0), 2.0);
  EXPECT_GE(ros.diagnostics->number("raymapd: pipeline/extrinsics_from_tf").value_or(0.0), 1.0);
  expectCleanStop(daemon);
}

TEST(Raymapd, ComposesATfChainFromTheWorldFrameToTheBase) {
  const std::uint32_t domain = uniqueDomain();
  // As robots publish it: map -> odom (localisation, rarely) and odom -> base_link (odometry, at
  // 100 Hz) on /tf; raymapd maps in `map`. There is no direct map -> base_link transform, so
  // without composing the chain no scan would ever get a pose.
  std::string config = serviceConfig(domain);
  config.replace(config.find("source: odometry"), 16, "source: tf");
  config.replace(config.find("world_frame: odom"), 17, "world_frame: map");
  RunningDaemon daemon(config, false);
  ASSERT_TRUE(daemon.notify.waitFor("READY=1", kStartWait).has_value()) << daemon.log();
  RosSide ros(domain, 70000);
  ASSERT_TRUE(ros.waitForService(kStartWaitS));
  for (int i = 0; i < 5; ++i) {  // /tf is volatile: a few times, once matched is enough
    ros.publisher->publishTf(0, io::Pose{}, "map", "odom");
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  driver::PlaybackOptions options;
  options.pose_as_tf = true;  // odom -> base_link
  EXPECT_EQ(expectSceneHeightsAfterPlaying(ros, daemon, options), "map");
  expectCleanStop(daemon);
}

TEST(Raymapd, TakesTheExtrinsicOfASensorOnAMovingMountThroughItsChain) {
  const std::uint32_t domain = uniqueDomain();
  // A lidar on a pan unit: base_link -> pan on /tf (0.3 m up; it would turn), pan -> lidar on
  // /tf_static (0.2 m up). The sensor's extrinsic is the chain composed: 0.5 m.
  std::string config = serviceConfig(domain);
  config.replace(config.find("source: odometry"), 16, "source: tf");
  config.replace(config.find("base_height: 1.2"), 16, "base_height: 0.7");
  RunningDaemon daemon(config, false);
  ASSERT_TRUE(daemon.notify.waitFor("READY=1", kStartWait).has_value()) << daemon.log();
  RosSide ros(domain, 70000);
  ASSERT_TRUE(ros.waitForService(kStartWaitS));
  ros.publisher->publishTfStatic(io::Pose{{0.0, 0.0, 0.2}}, "pan", "lidar");
  for (int i = 0; i < 5; ++i) {  // /tf is volatile: a few times, once matched is enough
    ros.publisher->publishTf(0, io::Pose{{0.0, 0.0, 0.3}}, "base_link", "pan");
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  driver::PlaybackOptions options;
  options.pose_as_tf = true;                 // odom -> base_link
  options.sensor_in_base = {0.0, 0.0, 0.5};  // the published base pose is 0.5 m below the lidar
  expectSceneHeightsAfterPlaying(ros, daemon, options);
  EXPECT_GE(ros.diagnostics->number("raymapd: pipeline/extrinsics_from_tf").value_or(0.0), 1.0);
  expectCleanStop(daemon);
}

TEST(Raymapd, PublishesANav2CostmapWithEachHeightMapOnTheSameGrid) {
  const std::uint32_t domain = uniqueDomain();
  std::string config = serviceConfig(domain);
  config.replace(config.find("dds: {"), 6, "dds: {costmap_topic: rt/costmap, ");
  RunningDaemon daemon(config, false);
  ASSERT_TRUE(daemon.notify.waitFor("READY=1", kStartWait).has_value()) << daemon.log();
  RosSide ros(domain, 70000);
  // As Nav2's StaticLayer subscribes: reliable, transient-local.
  auto costmaps =
      dds::RawReader::create(*ros.subscriber_participant, "rt/costmap", dds::occupancyGridType(),
                             dds::Reliability::kReliable, 64, dds::Durability::kTransientLocal);
  ASSERT_TRUE(costmaps.has_value());
  ASSERT_TRUE(ros.waitForService(kStartWaitS));
  const driver::SimulatedLidar lidar = yardLidar(32, 1024, /*moving=*/false);
  std::vector<driver::ReceivedGridMap> maps;
  ros.play(lidar, driver::PlaybackOptions{}, 3.0, maps);
  ros.settle(0.5, &maps);
  ASSERT_GE(maps.size(), fewestMaps(3.0)) << daemon.log();
  std::vector<msgs::DecodedOccupancyGrid> grids;
  costmaps->takeEach(
      [&](std::span<const std::byte> cdr, std::int64_t) {
        auto grid = msgs::decodeOccupancyGrid(cdr);
        ASSERT_TRUE(grid.has_value()) << msgs::toString(grid.error());
        grids.push_back(std::move(grid).value());
      },
      64);
  // The costmap of the last height map: same stamp, frame and grid, its origin the grid's
  // (-x, -y) corner; unknown exactly where the height map knows nothing.
  const driver::ReceivedGridMap& hm = maps.back();
  const auto same = std::find_if(grids.begin(), grids.end(),
                                 [&](const auto& g) { return g.stamp_ns == hm.stamp_ns; });
  ASSERT_NE(same, grids.end()) << grids.size() << " costmaps";
  const auto cells_x = static_cast<std::uint32_t>(std::lround(hm.length_x / hm.resolution));
  const auto cells_y = static_cast<std::uint32_t>(std::lround(hm.length_y / hm.resolution));
  ASSERT_EQ(same->width, cells_x);
  ASSERT_EQ(same->height, cells_y);
  EXPECT_EQ(same->frame_id, hm.frame_id);
  EXPECT_NEAR(same->resolution, hm.resolution, 1e-6);
  EXPECT_NEAR(same->origin_x, hm.centre_x - 0.5 * hm.length_x, 1e-6);
  EXPECT_NEAR(same->origin_y, hm.centre_y - 0.5 * hm.length_y, 1e-6);
  const std::vector<float>* kind = hm.layer("kind");
  ASSERT_NE(kind, nullptr);
  std::uint32_t free = 0;
  std::uint32_t lethal = 0;
  std::uint32_t mismatched = 0;
  for (std::uint32_t j = 0; j < cells_y; ++j) {
    for (std::uint32_t i = 0; i < cells_x; ++i) {
      const float k = (*kind)[i + j * cells_x];  // column-major, (0, 0) at +x/+y
      const std::int8_t cost = same->data[(cells_y - 1 - j) * cells_x + (cells_x - 1 - i)];
      mismatched += (k == 0.0F) != (cost == -1) ? 1u : 0u;  // kind 0: unknown
      free += cost >= 0 && cost < 100 ? 1u : 0u;            // traversable, at some cost for slope
      lethal += cost == 100 ? 1u : 0u;
    }
  }
  EXPECT_EQ(mismatched, 0u);
  EXPECT_GT(free, 1000u) << lethal << " lethal";  // the yard's ground
  EXPECT_GT(lethal, 10u);                         // its walls and boxes
  // One costmap with each GridMap, by raymapd's own counts, in a report that covers the maps
  // received here (reports come once a second, and later on a slow machine). Mid-cycle a report
  // can count a costmap whose GridMap is being written; once the map is stale they stay equal.
  const auto count = [&](const char* key) {
    return ros.diagnostics->number(std::string("raymapd: height map/") + key).value_or(-1.0);
  };
  const auto received = static_cast<double>(maps.size());
  EXPECT_TRUE(ros.settleUntil(kStartWaitS,
                              [&] {
                                return count("maps_published") >= received &&
                                       count("costmaps_published") == count("maps_published");
                              }))
      << count("costmaps_published") << " costmaps, " << count("maps_published") << " maps, "
      << received << " received";
  expectCleanStop(daemon);
}

TEST(Raymapd, CheckConfigAcceptsTheProfilesAndNamesTheKeyOfAnError) {
  const auto [ok, ok_text] = runToCompletion(
      RAYMAPD_PATH, {"--check-config", std::string(RAYMAP_CONFIG_DIR) + "/cpu.yaml"});
  EXPECT_EQ(ok, 0) << ok_text;
  EXPECT_NE(ok_text.find("ok"), std::string::npos);
  TempDir dir;
  const std::string bad = dir.file("bad.yaml");
  std::ofstream(bad) << "heightmap:\n  rate_hz: 5\n  sise: 20\n";
  const auto [status, text] = runToCompletion(RAYMAPD_PATH, {"--check-config", bad});
  EXPECT_EQ(status, 2);
  EXPECT_NE(text.find("bad.yaml"), std::string::npos) << text;
  EXPECT_NE(text.find("heightmap.sise"), std::string::npos) << text;
  EXPECT_NE(text.find("unknown key"), std::string::npos) << text;
  const auto [missing, missing_text] =
      runToCompletion(RAYMAPD_PATH, {"--config", dir.file("absent.yaml")});
  EXPECT_EQ(missing, 2);
  EXPECT_NE(missing_text.find("absent.yaml"), std::string::npos) << missing_text;
}

}  // namespace
}  // namespace raymap::test
