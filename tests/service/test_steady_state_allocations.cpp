// SPDX-License-Identifier: BSD-3-Clause
// raymapd's steady state allocates nothing: the service runs in this process with the malloc
// family interposed, and every allocation made inside the real-time loops (platform::
// RealtimeScope; Cyclone DDS's own serialisation inside dds_write/dds_take excluded) is counted.
#include <gtest/gtest.h>

#include "platform/clock.hpp"
#include "src/driver/depth_playback.hpp"
#include "src/service/daemon_config.hpp"
#include "src/service/service.hpp"
#include "tests/service/service_fixture.hpp"
#include "tests/support/alloc_counter.hpp"

namespace raymap::test {
namespace {

/// The lidar test, standing still or driving the yard's path (issue 52: the window moves, regions
/// leave the pool and new ones are created). Each play() starts the path over: the measured 4 s
/// drive the 10 m of the yard at 4 m/s from its start (a pose jump back, then the window moving
/// across three region boundaries).
void expectNoSteadyStateAllocationWithTheLidar(bool moving) {
  if (!allocationCountingAvailable()) {
    GTEST_SKIP() << "sanitizer build: the sanitizer owns malloc";
  }
  const std::uint32_t domain = uniqueDomain();
  // Normal scheduling and no mlockall: this is the test process.
  auto config = service::parseDaemonConfig(
      serviceConfig(domain,
                    "realtime: {lock_memory: false, ingest: {priority: 0}, "
                    "integrator: {priority: 0}, publisher: {priority: 0}}\n"),
      "test.yaml");
  ASSERT_TRUE(config.has_value()) << config.error().message;
  auto service = service::Service::create(config.value());
  ASSERT_TRUE(service.has_value()) << service.error().message;
  service.value()->start();

  RosSide ros(domain, 70000);
  ASSERT_TRUE(ros.waitForService(kStartWaitS));
  const driver::SimulatedLidar lidar = yardLidar(16, 1024, moving);
  std::vector<driver::ReceivedGridMap> maps;
  ros.play(lidar, driver::PlaybackOptions{}, 3.0, maps);  // warm-up: first cycles size buffers
  const double scans_before =
      ros.diagnostics->number("raymapd: pipeline/scans_integrated").value_or(0.0);
  const std::size_t maps_before = maps.size();
  const std::uint64_t before = realtimeAllocations();
  ros.play(lidar, driver::PlaybackOptions{}, 4.0, maps);
  const std::uint64_t after = realtimeAllocations();
  ros.settle(1.2);
  service.value()->stop();

  EXPECT_EQ(after - before, 0u) << "allocations in the steady-state loops";
  // ... while the service did its whole job meanwhile: publishing throughout the 4 s.
  EXPECT_GE(maps.size() - maps_before, fewestMaps(4.0, 0.0));
  EXPECT_GT(ros.diagnostics->number("raymapd: pipeline/scans_integrated").value_or(0.0),
            scans_before + 20.0);
  // The counter is live: the warm-up did allocate inside the loops (the first height-map cycle
  // sizes its plan) or nothing at all; either way it never decreases.
  EXPECT_GE(after, before);
}

TEST(RaymapdSteadyState, MakesNoHeapAllocationAfterWarmUp) {
  expectNoSteadyStateAllocationWithTheLidar(false);
}

TEST(RaymapdSteadyState, AMovingRobotMakesNoHeapAllocationAfterWarmUp) {
  expectNoSteadyStateAllocationWithTheLidar(true);
}

/// The depth-camera test, standing in front of the stairs or walking up to them.
void expectNoSteadyStateAllocationWithADepthCamera(bool moving) {
  if (!allocationCountingAvailable()) {
    GTEST_SKIP() << "sanitizer build: the sanitizer owns malloc";
  }
  const std::uint32_t domain = uniqueDomain();
  // Images and their CameraInfo every frame: decoded into the slots, the pixel rays built once.
  auto config = service::parseDaemonConfig(
      "map: {resolution: 0.1, window: [6, 6, 3]}\n"
      "backend: {name: cpu, threads: 2}\n"
      "pose: {source: odometry, topic: rt/odom}\n"
      "sensors:\n"
      "  - {name: body_front, kind: depth, topic: rt/body_front/depth/image_rect_raw,\n"
      "     max_range: 2.0, downsample: 2}\n"
      "heightmap: {rate_hz: 5, size: 8, base_height: 0.55}\n"
      "dds: {domain: " +
          std::to_string(domain) +
          "}\n"
          "realtime: {lock_memory: false, ingest: {priority: 0}, integrator: {priority: 0}, "
          "publisher: {priority: 0}}\n",
      "depth.yaml");
  ASSERT_TRUE(config.has_value()) << config.error().message;
  auto service = service::Service::create(config.value());
  ASSERT_TRUE(service.has_value()) << service.error().message;
  service.value()->start();

  RosSide ros(domain, 1024);
  auto file = sim::loadSceneFile(std::string(RAYMAP_SCENES_DIR) + "/stairs_depth.yaml");
  ASSERT_TRUE(file.has_value());
  // Standing in front of the stairs (as the lidar test stands in the yard).
  const sim::SensorPath still = sim::SensorPath::fromPoses({file->simulation.path.at(4.0)}).value();
  auto created = driver::DepthPlayback::create(
      *ros.publisher_participant, *ros.publisher, file->scene, file->depth_cameras,
      moving ? file->simulation.path : still, file->simulation.seed, {});
  ASSERT_TRUE(created.has_value()) << created.error().message;
  driver::DepthPlayback& playback = *created.value();
  const std::int64_t give_up = startWaitEndNs();
  while (!(playback.matched() && ros.grid_maps->matchedWriters() > 0) &&
         platform::monotonicNowNs() < give_up) {
    platform::sleepUntilMonotonicNs(platform::monotonicNowNs() + 20000000);
  }
  const std::int64_t t0 = platform::monotonicNowNs();
  playback.start(t0, platform::realtimeNowNs());
  std::vector<driver::ReceivedGridMap> maps;
  const auto playUntil = [&](double seconds) {
    const std::int64_t end = t0 + static_cast<std::int64_t>(seconds * 1e9);
    for (std::int64_t now = platform::monotonicNowNs(); now < end;
         now = platform::monotonicNowNs()) {
      const std::int64_t due = playback.publishDue(now);
      ros.grid_maps->poll(0, maps);
      ros.diagnostics->poll();
      platform::sleepUntilMonotonicNs(std::min(due, now + 5000000));
    }
  };
  playUntil(3.0);  // warm-up: the first CameraInfo builds the pixel rays
  const std::uint64_t before = realtimeAllocations();
  const std::size_t maps_before = maps.size();
  playUntil(7.0);
  const std::uint64_t after = realtimeAllocations();
  ros.settle(1.2);
  service.value()->stop();

  EXPECT_EQ(after - before, 0u) << "allocations in the steady-state loops";
  EXPECT_GE(maps.size() - maps_before, fewestMaps(4.0, 0.0));
  EXPECT_GE(ros.diagnostics->number("raymapd: sensor body_front/scans_integrated").value_or(0.0),
            25.0);
}

TEST(RaymapdSteadyState, ADepthCameraMakesNoHeapAllocationAfterWarmUp) {
  expectNoSteadyStateAllocationWithADepthCamera(false);
}

TEST(RaymapdSteadyState, AWalkingDepthCameraMakesNoHeapAllocationAfterWarmUp) {
  expectNoSteadyStateAllocationWithADepthCamera(true);
}

}  // namespace
}  // namespace raymap::test
