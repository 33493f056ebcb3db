// SPDX-License-Identifier: BSD-3-Clause
// raymapd's steady state allocates nothing: the service runs in this process with the malloc
// family interposed, and every allocation made inside the real-time loops (platform::
// RealtimeScope; Cyclone DDS's own serialisation inside dds_write/dds_take excluded) is counted.
#include <gtest/gtest.h>

#include "platform/clock.hpp"
#include "src/service/daemon_config.hpp"
#include "src/service/service.hpp"
#include "tests/service/service_fixture.hpp"
#include "tests/support/alloc_counter.hpp"

namespace raymap::test {
namespace {

TEST(RaymapdSteadyState, MakesNoHeapAllocationAfterWarmUp) {
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
  ASSERT_TRUE(ros.waitForService(10.0));
  const driver::SimulatedLidar lidar = yardLidar(16, 1024, /*moving=*/false);
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
  // ... while the service did its whole job meanwhile.
  EXPECT_GE(maps.size() - maps_before, 15u);
  EXPECT_GT(ros.diagnostics->number("raymapd: pipeline/scans_integrated").value_or(0.0),
            scans_before + 20.0);
  // The counter is live: the warm-up did allocate inside the loops (the first height-map cycle
  // sizes its plan) or nothing at all; either way it never decreases.
  EXPECT_GE(after, before);
}

}  // namespace
}  // namespace raymap::test
