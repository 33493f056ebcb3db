// SPDX-License-Identifier: BSD-3-Clause
// raymapd against an independent Fast DDS 2.9 peer (raymap-fastdds-peer, configured as
// rmw_fastrtps configures Fast DDS), as separate processes on loopback: Fast DDS's lidar,
// odometry and /tf_static go into the map; Fast DDS's subscriber decodes the GridMaps, costmaps
// and diagnostics. Behaviour only: counts and decoded fields, never rates or periods.
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "platform/clock.hpp"
#include "src/dds/entities.hpp"
#include "src/driver/lidar_playback.hpp"
#include "src/driver/ros_endpoints.hpp"
#include "src/io/map_file.hpp"
#include "src/security/enclave_check.hpp"
#include "src/security/keystore/keystore_writer.hpp"
#include "tests/fastdds/peer_process.hpp"
#include "tests/fastdds/veth_hosts.hpp"
#include "tests/service/service_fixture.hpp"
#include "tests/support/cli_runner.hpp"
#include "tests/support/temp_dir.hpp"
#include "tests/support/test_rays.hpp"

namespace raymap::test {
namespace {

using std::chrono::seconds;

/// How long a peer may run: it ends as soon as what the test waits for has happened.
constexpr seconds kPeerRun{90};

#define RAYMAP_SKIP_WITHOUT_FASTDDS_PEER()                                            \
  if (!fastDdsPeerBuilt()) {                                                          \
    GTEST_SKIP() << "raymap-fastdds-peer is not built (libfastrtps-dev, fastddsgen)"; \
  }

/// Replaces the first `from` in `text` with `to`. @return false (and the text unchanged) when
/// `from` is not there: the tests' base configuration changed under a test.
bool replaceFirst(std::string& text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  if (at == std::string::npos) {
    ADD_FAILURE() << "'" << from << "' is not in:\n" << text;
    return false;
  }
  text.replace(at, from.size(), to);
  return true;
}

/// The tests' raymapd configuration (one lidar on rt/points in frame lidar, odometry on rt/odom,
/// a 12 m GridMap at 5 Hz) with the Nav2 costmap on rt/costmap.
std::string fastDdsConfig(std::uint32_t domain) {
  std::string config = serviceConfig(domain);
  replaceFirst(config, "voxels_topic: rt/raymap/occupied_voxels}",
               "voxels_topic: rt/raymap/occupied_voxels, costmap_topic: rt/costmap}");
  return config;
}

std::vector<std::string> subscribeArgs() {
  return {"--seconds", std::to_string(kPeerRun.count()), "--until", "3"};
}

/// The GridMap's layout as raymapd sends it (docs/raymapd.md, What it publishes), decoded by
/// Fast DDS's generated code.
void expectRaymapdsGridMap(const Json& result) {
  ASSERT_NE(findPath(result, {"last_map"}), nullptr);
  EXPECT_EQ(textAt(result, {"last_map", "frame_id"}), "odom");
  EXPECT_NEAR(numberAt(result, {"last_map", "resolution"}).value_or(0.0), 0.1, 1e-9);
  EXPECT_NEAR(numberAt(result, {"last_map", "length_x"}).value_or(0.0), 12.0, 1e-9);
  EXPECT_NEAR(numberAt(result, {"last_map", "length_y"}).value_or(0.0), 12.0, 1e-9);
  EXPECT_EQ(textsAt(result, {"last_map", "layers"}),
            (std::vector<std::string>{"elevation", "clearance", "kind", "observed_count"}));
  EXPECT_EQ(textsAt(result, {"last_map", "basic_layers"}), std::vector<std::string>{"elevation"});
  EXPECT_EQ(textsAt(result, {"last_map", "dim_labels"}),
            (std::vector<std::string>{"column_index", "row_index"}));
  EXPECT_EQ(textsAt(result, {"last_map", "dim_sizes"}), (std::vector<std::string>{"120", "120"}));
  EXPECT_EQ(textsAt(result, {"last_map", "dim_strides"}),
            (std::vector<std::string>{"14400", "120"}));
  EXPECT_EQ(textsAt(result, {"last_map", "layer_sizes"}),
            (std::vector<std::string>{"14400", "14400", "14400", "14400"}));
  EXPECT_GT(numberAt(result, {"last_map", "surface_cells"}).value_or(0.0), 0.0);
}

/// The costmap as raymapd sends it: the GridMap's window, every cell a valid cost.
void expectRaymapdsCostmap(const Json& result) {
  ASSERT_NE(findPath(result, {"last_costmap"}), nullptr);
  EXPECT_EQ(textAt(result, {"last_costmap", "frame_id"}), "odom");
  EXPECT_EQ(numberAt(result, {"last_costmap", "width"}), 120.0);
  EXPECT_EQ(numberAt(result, {"last_costmap", "height"}), 120.0);
  EXPECT_NEAR(numberAt(result, {"last_costmap", "resolution"}).value_or(0.0), 0.1, 1e-6);
  EXPECT_EQ(numberAt(result, {"last_costmap", "cells"}), 14400.0);
  EXPECT_EQ(numberAt(result, {"last_costmap", "invalid"}), 0.0);
  EXPECT_GT(numberAt(result, {"last_costmap", "free"}).value_or(0.0) +
                numberAt(result, {"last_costmap", "costed"}).value_or(0.0),
            0.0)
      << "no traversable cell";
}

/// A Fast DDS subscriber's report: maps, costmaps and diagnostics all arrived and decoded.
void expectMapsCostmapsAndDiagnostics(const Json& result, const std::string& logs) {
  EXPECT_GT(numberAt(result, {"maps"}).value_or(0.0), 0.0) << logs;
  EXPECT_GT(numberAt(result, {"costmaps"}).value_or(0.0), 0.0) << logs;
  EXPECT_GT(numberAt(result, {"diagnostics"}).value_or(0.0), 0.0) << logs;
  EXPECT_EQ(numberAt(result, {"writers", "grid_map"}), 1.0);
  const double level = numberAt(result, {"pipeline_level"}).value_or(-1.0);
  EXPECT_GE(level, 0.0);  // OK, WARN or ERROR: decoded, whichever raymapd reported
  EXPECT_LE(level, 2.0);
  EXPECT_GT(numberAt(result, {"last_diagnostics", "maps_published"}).value_or(0.0), 0.0);
  EXPECT_GT(numberAt(result, {"last_diagnostics", "costmaps_published"}).value_or(0.0), 0.0);
  expectRaymapdsGridMap(result);
  expectRaymapdsCostmap(result);
}

/// The input: the tests' Cyclone lidar driver in the yard, until `peer` has had enough.
void feedYardLidarWhileRunning(std::uint32_t domain, PeerProcess& peer, const RunningDaemon& daemon,
                               const dds::SecurityFiles& security = {}) {
  RosSide ros(domain, 70000, security, security);
  ASSERT_TRUE(ros.waitForService(kStartWaitS)) << daemon.log();
  const driver::SimulatedLidar lidar = yardLidar(16, 512, /*moving=*/false);
  driver::LidarPlayback playback(lidar, *ros.publisher, driver::PlaybackOptions{});
  const std::int64_t t0 = platform::monotonicNowNs();
  playback.start(t0, platform::realtimeNowNs());
  const std::int64_t end = t0 + std::chrono::nanoseconds(kPeerRun).count();
  for (std::int64_t now = t0; peer.running() && now < end; now = platform::monotonicNowNs()) {
    const std::int64_t due = playback.publishDue(now);
    platform::sleepUntilMonotonicNs(std::min(due, now + 20'000'000));
  }
}

/// Waits for `subscriber` (publisher's room lidar into raymapd, raymapd's maps out) and checks
/// that every output arrived and the map has the room's floor where it is; stops raymapd.
void expectTheRoomsFloorMapped(RunningDaemon& daemon, PeerProcess& publisher,
                               PeerProcess& subscriber) {
  const std::optional<int> status = subscriber.finish(kPeerRun + seconds(30));
  EXPECT_EQ(publisher.finish(seconds(0)), 0) << publisher.log();
  ASSERT_EQ(status, 0) << subscriber.log();
  const std::optional<Json> result = subscriber.result();
  ASSERT_TRUE(result.has_value()) << subscriber.log();
  const std::string logs = "raymapd:\n" + daemon.log() + "\nsubscriber:\n" + subscriber.log() +
                           "\npublisher:\n" + publisher.log();
  expectMapsCostmapsAndDiagnostics(*result, logs);
  EXPECT_EQ(numberAt(*result, {"last_diagnostics", "pose_publishers"}), 1.0);
  EXPECT_EQ(numberAt(*result, {"last_diagnostics", "clouds_malformed"}), 0.0);
  // The robot stands at the room's centre on a floor at z = 0 (the peer's simulated room).
  EXPECT_NEAR(numberAt(*result, {"last_map", "centre_x"}).value_or(99.0), 0.0, 0.1);
  EXPECT_NEAR(numberAt(*result, {"last_map", "centre_y"}).value_or(99.0), 0.0, 0.1);
  EXPECT_GT(numberAt(*result, {"last_map", "surface_cells"}).value_or(0.0), 100.0);
  EXPECT_NEAR(numberAt(*result, {"last_map", "surface_elevation_median"}).value_or(99.0), 0.0, 0.15)
      << logs;
  expectCleanStop(daemon);
}

TEST(FastDdsPeer, RaymapdIntegratesAFastDdsLidarWithItsOdometryAndTfStatic) {
  RAYMAP_SKIP_WITHOUT_FASTDDS_PEER();
  const std::uint32_t domain = uniqueDomain();
  RunningDaemon daemon(fastDdsConfig(domain), false);
  ASSERT_TRUE(daemon.notify.waitFor("READY=1", kStartWait).has_value()) << daemon.log();
  // The test's own Cyclone subscriber reads what raymapd says of the input.
  auto participant = dds::Participant::create(domain);
  ASSERT_TRUE(participant.has_value());
  auto diagnostics = driver::DiagnosticsListener::create(participant.value(), "rt/diagnostics");
  ASSERT_TRUE(diagnostics.has_value());

  PeerProcess peer(domain, "publish", {"--seconds", std::to_string(kPeerRun.count())});
  const auto number = [&](const std::string& key) {
    return diagnostics.value()->number("raymapd: " + key);
  };
  // Scans go in from the start; the latched transform too, though not necessarily first: Fast
  // DDS resends it to a reader that missed it at the match on its next heartbeat (every 3 s).
  const std::int64_t end = platform::monotonicNowNs() + 60'000'000'000;
  bool integrated = false;
  while (!integrated && peer.running() && platform::monotonicNowNs() < end) {
    platform::sleepUntilMonotonicNs(platform::monotonicNowNs() + 50'000'000);
    diagnostics.value()->poll();
    integrated = number("pipeline/scans_integrated").value_or(0.0) >= 10.0 &&
                 number("pipeline/tf_static_edges").value_or(0.0) >= 1.0;
  }
  const std::optional<int> status = peer.finish(seconds(0));
  ASSERT_TRUE(integrated) << "raymapd:\n" << daemon.log() << "\npeer:\n" << peer.log();

  // Every cloud decoded, from one lidar, placed by one pose source and the latched extrinsic.
  EXPECT_EQ(number("pipeline/clouds_malformed"), 0.0);
  EXPECT_EQ(number("pipeline/clouds_wrong_frame"), 0.0);
  EXPECT_EQ(number("pipeline/pose_publishers"), 1.0);
  EXPECT_GT(number("pipeline/poses_received").value_or(0.0), 0.0);
  EXPECT_GE(number("pipeline/tf_static_edges").value_or(0.0), 1.0) << "/tf_static not received";
  EXPECT_EQ(number("sensor lidar/publishers"), 1.0);

  ASSERT_EQ(status, 0) << peer.log();
  const std::optional<Json> result = peer.result();
  ASSERT_TRUE(result.has_value()) << peer.log();
  EXPECT_GE(numberAt(*result, {"clouds_published"}).value_or(0.0), 10.0);
  EXPECT_GT(numberAt(*result, {"points_per_cloud"}).value_or(0.0), 0.0);
  EXPECT_EQ(numberAt(*result, {"tf_static_published"}), 1.0);
  EXPECT_TRUE(numberAt(*result, {"tf_static_acknowledged_after_ms"}).has_value())
      << "raymapd never acknowledged /tf_static";
  EXPECT_GE(numberAt(*result, {"cloud_readers"}).value_or(0.0), 1.0);
  EXPECT_GE(numberAt(*result, {"odometry_readers"}).value_or(0.0), 1.0);
  EXPECT_GE(numberAt(*result, {"tf_static_readers"}).value_or(0.0), 1.0);
  expectCleanStop(daemon);
}

TEST(FastDdsPeer, AFastDdsSubscriberDecodesRaymapdsGridMapsCostmapsAndDiagnostics) {
  RAYMAP_SKIP_WITHOUT_FASTDDS_PEER();
  const std::uint32_t domain = uniqueDomain();
  RunningDaemon daemon(fastDdsConfig(domain), false);
  ASSERT_TRUE(daemon.notify.waitFor("READY=1", kStartWait).has_value()) << daemon.log();
  PeerProcess peer(domain, "subscribe", subscribeArgs());
  ASSERT_NO_FATAL_FAILURE(feedYardLidarWhileRunning(domain, peer, daemon));
  const std::optional<int> status = peer.finish(seconds(0));
  ASSERT_EQ(status, 0) << peer.log();
  const std::optional<Json> result = peer.result();
  ASSERT_TRUE(result.has_value()) << peer.log();
  expectMapsCostmapsAndDiagnostics(*result, "raymapd:\n" + daemon.log() + "\npeer:\n" + peer.log());
  expectCleanStop(daemon);
}

// ROS 2's default middleware with an SROS2 keystore made by `raymap security`: a Fast DDS 2.9
// lidar and planner with Fast DDS's built-in security plugins (set up as rmw_fastrtps does from
// an enclave) map the room through raymapd, encrypted end to end; a Fast DDS planner without
// credentials receives nothing. Fast DDS checks the keystore's certificates and signed documents
// with its own implementation: an independent check of the writer. (Every participant is a
// process of its own: see docs/security.md on one identity per process.)
TEST(FastDdsPeer, SecureFastDdsNodesWorkWithAKeystoreMadeByRaymapSecurity) {
  RAYMAP_SKIP_WITHOUT_FASTDDS_PEER();
  const std::uint32_t domain = uniqueDomain();
  const TempDir dir;
  const std::filesystem::path keystore = dir.path() / "keystore";
  security::KeystoreOptions options;
  options.domains = {domain, domain};
  ASSERT_TRUE(security::createKeystore(keystore, options));
  for (const char* enclave : {"/raymap/raymapd", "/robot/driver", "/nav2/planner"}) {
    ASSERT_TRUE(security::createEnclave(keystore, enclave,
                                        {options.domains, security::validityForDays(30)}));
  }
  const auto folder = [&](const char* enclave) {
    security::SecurityConfig config;
    config.keystore = keystore.string();
    config.enclave = enclave;
    return security::enclaveFolder(config).string();
  };
  std::string config = fastDdsConfig(domain);
  ASSERT_TRUE(replaceFirst(
      config, "dds: {domain: ", "dds: {security: {keystore: " + keystore.string() + "}, domain: "));
  RunningDaemon daemon(config, false);
  ASSERT_TRUE(daemon.notify.waitFor("READY=1", kStartWait).has_value()) << daemon.log();
  PeerProcess outsider(domain, "subscribe", {"--seconds", std::to_string(kPeerRun.count())});
  PeerProcess subscriber(domain, "subscribe", subscribeArgs(),
                         {"--enclave-dir", folder("/nav2/planner")});
  PeerProcess publisher(domain, "publish",
                        {"--seconds", std::to_string(kPeerRun.count()), "--clouds-after-tf-static"},
                        {"--enclave-dir", folder("/robot/driver")});
  expectTheRoomsFloorMapped(daemon, publisher, subscriber);
  outsider.finish(seconds(0));
  const std::optional<Json> outside = outsider.result();
  ASSERT_TRUE(outside.has_value()) << outsider.log();
  EXPECT_EQ(numberAt(*outside, {"maps"}), 0.0) << outsider.log();
  EXPECT_EQ(numberAt(*outside, {"costmaps"}), 0.0) << outsider.log();
  EXPECT_EQ(numberAt(*outside, {"diagnostics"}), 0.0) << outsider.log();
}

// A planner on a stock ROS 2 install: Fast DDS leaves its socket buffers at the OS default
// (208 KiB here), less than one of these GridMaps (20 m: 200 x 200 cells x 4 layers, 640 KB).
// raymapd sends each map whole and the subscriber loses what does not fit. Cyclone's own repairs
// (up to 1 MiB at once) overrun the buffer again, and with keep-last 1 a map not complete when
// the next is written is never delivered: 37 to 66 skipped while 25 arrived, in three runs here.
// raymapd resends in bursts of dds.repair_burst_kb (64 KiB) that the buffer holds, so each map
// completes (0 skipped). Counted, not timed: the maps skipped (gaps in the writer's sequence
// numbers) while at least 25 arrived. One in ten may be, for a receiver that a busy machine
// stalls for a period.
TEST(FastDdsPeer, AStockBufferSubscriberReceivesRaymapdsMapsWithoutSkipping) {
  RAYMAP_SKIP_WITHOUT_FASTDDS_PEER();
  const std::uint32_t domain = uniqueDomain();
  std::string config = fastDdsConfig(domain);
  ASSERT_TRUE(replaceFirst(config, "size: 12,", "size: 20,"));
  ASSERT_TRUE(replaceFirst(config, "window: [6, 6, 3]", "window: [8, 8, 3]"));
  RunningDaemon daemon(config, false);
  ASSERT_TRUE(daemon.notify.waitFor("READY=1", kStartWait).has_value()) << daemon.log();
  PeerProcess peer(
      domain, "subscribe",
      {"--seconds", std::to_string(kPeerRun.count()), "--until", "5", "--min-maps", "25"});
  ASSERT_NO_FATAL_FAILURE(feedYardLidarWhileRunning(domain, peer, daemon));
  const std::optional<int> status = peer.finish(seconds(0));
  ASSERT_EQ(status, 0) << peer.log();
  const std::optional<Json> result = peer.result();
  ASSERT_TRUE(result.has_value()) << peer.log();
  const double maps = numberAt(*result, {"maps"}).value_or(0.0);
  ASSERT_GE(maps, 25.0) << "raymapd:\n" << daemon.log() << "\npeer:\n" << peer.log();
  EXPECT_EQ(numberAt(*result, {"buffer_bytes"}), 0.0);  // the OS default
  EXPECT_EQ(textsAt(*result, {"last_map", "dim_sizes"}), (std::vector<std::string>{"200", "200"}));
  EXPECT_LE(numberAt(*result, {"maps_skipped"}).value_or(1e9), maps / 10.0) << peer.log();
  expectCleanStop(daemon);
}

TEST(FastDdsPeer, FastDdsAtBothEndsMapsTheRoomsFloor) {
  RAYMAP_SKIP_WITHOUT_FASTDDS_PEER();
  const std::uint32_t domain = uniqueDomain();
  RunningDaemon daemon(fastDdsConfig(domain), false);
  ASSERT_TRUE(daemon.notify.waitFor("READY=1", kStartWait).has_value()) << daemon.log();
  PeerProcess subscriber(domain, "subscribe", subscribeArgs());
  // The lidar starts once raymapd has the latched transform, as on a robot whose
  // robot_state_publisher ran first: then no scan goes in with the configured extrinsic
  // (identity), and the floor is where the transform puts it.
  PeerProcess publisher(
      domain, "publish",
      {"--seconds", std::to_string(kPeerRun.count()), "--clouds-after-tf-static"});

  expectTheRoomsFloorMapped(daemon, publisher, subscriber);
}

/// What raymapd did with the clouds it received.
struct ScanOutcomes {
  double integrated = 0.0;
  double accounted = 0.0;  ///< every outcome: integrated, dropped for want of a pose, shed, ...
};

/// Polls raymapd's diagnostics on `domain` until `clouds` received clouds each have an outcome
/// (at most 60 s). @return the last counts reported.
ScanOutcomes waitForOutcomes(std::uint32_t domain, double clouds) {
  ScanOutcomes outcomes;
  auto participant = dds::Participant::create(domain);
  EXPECT_TRUE(participant.has_value());
  if (!participant) {
    return outcomes;
  }
  auto diagnostics = driver::DiagnosticsListener::create(participant.value(), "rt/diagnostics");
  EXPECT_TRUE(diagnostics.has_value());
  if (!diagnostics) {
    return outcomes;
  }
  const auto count = [&](const char* key) {
    return diagnostics.value()->number(std::string("raymapd: pipeline/") + key).value_or(0.0);
  };
  const std::int64_t end = platform::monotonicNowNs() + 60'000'000'000;
  while (outcomes.accounted < clouds && platform::monotonicNowNs() < end) {
    platform::sleepUntilMonotonicNs(platform::monotonicNowNs() + 50'000'000);
    diagnostics.value()->poll();
    outcomes.integrated = count("scans_integrated");
    outcomes.accounted = outcomes.integrated + count("scans_dropped_no_pose") +
                         count("scans_empty") + count("scans_shed") +
                         count("clouds_dropped_overflow") + count("clouds_malformed") +
                         count("clouds_wrong_frame");
  }
  return outcomes;
}

/// The tests' raymapd configuration with the map saved to `map_path` when it stops.
std::string savingConfig(std::uint32_t domain, const std::string& map_path) {
  std::string config = fastDdsConfig(domain);
  replaceFirst(config, "map: {resolution: 0.1, window: [6, 6, 3]}",
               "map: {resolution: 0.1, window: [6, 6, 3], save_on_exit: '" + map_path + "'}");
  return config;
}

// The same lidar data gives the same map whichever middleware carried it: the Fast DDS peer's
// lidar (best effort, SensorDataQoS), odometry and /tf_static go into one raymapd while
// `raymap record` (Cyclone) records them; `raymap replay` sends the recording, the same bytes,
// through Cyclone into a second raymapd. Both integrate every cloud, and the saved maps agree
// voxel for voxel, bit for bit. Every cloud has its poses at both ends: the lidar starts once
// odometry reaches raymapd and the recorder, and odometry goes on 0.5 s (more than
// pose.max_wait_s) after the last cloud. (Without that tail the last cloud found its pose at one
// end and not at the other in one CI run; with the robot standing still most voxels are at their
// clamps after ten scans, but 119 of 128,014 mixed hit-and-miss voxels were not, and differed.)
TEST(FastDdsPeer, AFastDdsLidarGivesTheSameMapAsItsDataThroughCyclone) {
  RAYMAP_SKIP_WITHOUT_FASTDDS_PEER();
  TempDir dir;
  const std::string log = dir.file("room.rmlog");
  const std::string fastdds_map = dir.file("fastdds.rmap");
  const std::string cyclone_map = dir.file("cyclone.rmap");

  const std::uint32_t first = uniqueDomain();
  double clouds = 0.0;
  double integrated = 0.0;
  {
    RunningDaemon daemon(savingConfig(first, fastdds_map), false);
    ASSERT_TRUE(daemon.notify.waitFor("READY=1", kStartWait).has_value()) << daemon.log();
    DaemonProcess recorder(RAYMAP_CLI_PATH,
                           {"record", "-o", log, "--domain", std::to_string(first)}, {},
                           dir.file("record.log"));
    // The lidar starts once raymapd and the recorder both hold the transform and match the
    // clouds: both get every cloud.
    PeerProcess publisher(first, "publish",
                          {"--seconds", "4", "--clouds-after-tf-static", "--readers", "2",
                           "--odometry-tail-s", "0.5"});
    ASSERT_EQ(publisher.finish(kPeerRun), 0) << publisher.log();
    const std::optional<Json> result = publisher.result();
    ASSERT_TRUE(result.has_value()) << publisher.log();
    clouds = numberAt(*result, {"clouds_published"}).value_or(0.0);
    ASSERT_GE(clouds, 10.0) << publisher.log();
    const ScanOutcomes outcomes = waitForOutcomes(first, clouds);
    EXPECT_EQ(outcomes.accounted, clouds) << daemon.log();
    EXPECT_EQ(outcomes.integrated, clouds) << daemon.log();
    integrated = outcomes.integrated;
    const auto recorded = recorder.stop(SIGINT, kStopWait);
    ASSERT_TRUE(recorded.has_value());
    ASSERT_EQ(recorded->first, 0) << readFile(dir.file("record.log"));
    expectCleanStop(daemon);
  }

  const std::uint32_t second = uniqueDomain();
  {
    RunningDaemon daemon(savingConfig(second, cyclone_map), false);
    ASSERT_TRUE(daemon.notify.waitFor("READY=1", kStartWait).has_value()) << daemon.log();
    const auto [status, output] =
        runToCompletion(RAYMAP_CLI_PATH, {"replay", log, "--domain", std::to_string(second)});
    ASSERT_EQ(status, 0) << output;
    const ScanOutcomes outcomes = waitForOutcomes(second, clouds);
    EXPECT_EQ(outcomes.accounted, clouds) << daemon.log();
    EXPECT_EQ(outcomes.integrated, integrated) << daemon.log();
    expectCleanStop(daemon);
  }

  auto through_fastdds = io::loadMap(fastdds_map);
  ASSERT_TRUE(through_fastdds.has_value()) << through_fastdds.error().message;
  auto through_cyclone = io::loadMap(cyclone_map);
  ASSERT_TRUE(through_cyclone.has_value()) << through_cyclone.error().message;
  const MapComparison comparison = compareMaps(*through_fastdds, *through_cyclone);
  std::printf("%.0f scans integrated; %llu voxels compared, %llu in the same state, %llu exact\n",
              integrated, static_cast<unsigned long long>(comparison.compared),
              static_cast<unsigned long long>(comparison.same_state),
              static_cast<unsigned long long>(comparison.exact_value));
  EXPECT_GT(comparison.compared, 10000u);
  EXPECT_EQ(comparison.same_state, comparison.compared);
  EXPECT_EQ(comparison.exact_value, comparison.compared);
}

// As on a robot whose planner runs on another computer: raymapd in one network namespace, the
// Fast DDS lidar and planner in another, joined by a virtual Ethernet pair; both sides find
// each other by their default multicast discovery (Cyclone's SPDP and Fast DDS's, 239.255.0.1),
// with no peer list. Cyclone is only pinned to the robot's end of the pair.
TEST(FastDdsPeer, MulticastDiscoveryBetweenTwoHostsOfAVirtualEthernet) {
  RAYMAP_SKIP_WITHOUT_FASTDDS_PEER();
  std::string why;
  const std::unique_ptr<VethHosts> hosts = VethHosts::create(why);
  if (!hosts) {
    GTEST_SKIP() << "no network namespaces here: " << why;
  }
  const std::uint32_t domain = uniqueDomain();
  const std::string cyclone =
      "CYCLONEDDS_URI=<CycloneDDS><Domain Id=\"any\"><General><Interfaces>"
      "<NetworkInterface name=\"" +
      hosts->interfaceOf(VethHosts::Host::kRobot) +
      "\"/></Interfaces></General></Domain></CycloneDDS>";
  RunningDaemon daemon(fastDdsConfig(domain), false, hosts->launcher(VethHosts::Host::kRobot),
                       {cyclone});
  ASSERT_TRUE(daemon.notify.waitFor("READY=1", kStartWait).has_value()) << daemon.log();
  const std::vector<std::string> stock = {"--discovery", "stock"};
  const std::vector<std::string> planner = hosts->launcher(VethHosts::Host::kPlanner);
  PeerProcess subscriber(domain, "subscribe", subscribeArgs(), stock, planner);
  PeerProcess publisher(domain, "publish",
                        {"--seconds", std::to_string(kPeerRun.count()), "--clouds-after-tf-static"},
                        stock, planner);
  expectTheRoomsFloorMapped(daemon, publisher, subscriber);
}

}  // namespace
}  // namespace raymap::test
