// SPDX-License-Identifier: BSD-3-Clause
// raymapd's start-up checks: every fixed pool sized before any is allocated and compared with
// the memory the machine leaves, and map.save_on_exit's folder checked, with the key named.
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include "src/service/daemon_config.hpp"
#include "src/service/startup_checks.hpp"
#include "tests/support/temp_dir.hpp"

namespace raymap::service {
namespace {

constexpr double kGB = 1e9;

DaemonConfig parsed(const std::string& yaml) {
  auto config = parseDaemonConfig(yaml, "robot.yaml");
  EXPECT_TRUE(config) << config.error().message;
  return config ? config.value() : DaemonConfig{};
}

platform::MemoryLimit limit(double bytes) {
  platform::MemoryLimit l;
  l.bytes = static_cast<std::uint64_t>(bytes);
  l.source = "MemAvailable in /proc/meminfo";
  return l;
}

double poolBytes(const DaemonConfig& c, const std::string& key) {
  for (const PoolEstimate& p : estimatePools(c)) {
    if (p.key == key) {
      return p.bytes;
    }
  }
  ADD_FAILURE() << "no pool " << key;
  return 0.0;
}

TEST(StartupChecks, PoolsOfTheDefaultsAreSizedAndFitAGigabyte) {
  const DaemonConfig c = parsed("{}\n");
  // 8 x 8 x 3 regions of 32^3 voxels with occupancy (4 bytes a voxel) and the voxel mean.
  EXPECT_GT(poolBytes(c, "map.window"), 192.0 * 32768 * 4);
  // 5 slots of 262,144 points of 24 bytes.
  EXPECT_EQ(poolBytes(c, "queues.scan_slots x sensors[].max_points"), 5.0 * 262144 * 24);
  EXPECT_TRUE(checkStartup(c, limit(1 * kGB)));
}

TEST(StartupChecks, AWindowThatCannotFitIsRefusedNamingItsKeyAndBytes) {
  // 64 x 64 x 16 regions: 25.8 GB.
  const DaemonConfig c = parsed("map: {window: [64, 64, 16]}\n");
  auto result = checkStartup(c, limit(16 * kGB));
  ASSERT_FALSE(result);
  const std::string& m = result.error().message;
  EXPECT_EQ(result.error().code, ErrorCode::kCapacity);
  EXPECT_NE(m.find("robot.yaml: line 1: map.window"), std::string::npos) << m;
  EXPECT_NE(m.find("25.8 GB"), std::string::npos) << m;
  EXPECT_NE(m.find("MemAvailable"), std::string::npos) << m;
  // [256, 256, 256] overflows 32-bit region counts: still refused, with its size.
  auto huge = checkStartup(parsed("map: {window: [256, 256, 256]}\n"), limit(16 * kGB));
  ASSERT_FALSE(huge);
  EXPECT_NE(huge.error().message.find("map.window"), std::string::npos);
  EXPECT_NE(huge.error().message.find("TB"), std::string::npos) << huge.error().message;
}

TEST(StartupChecks, ScanSlotsTimesMaxPointsIsNamedWhenItIsTheLargest) {
  const DaemonConfig c = parsed("queues: {scan_slots: 256}\nsensors:\n  - max_points: 16777216\n");
  auto result = checkStartup(c, limit(16 * kGB));
  ASSERT_FALSE(result);
  EXPECT_NE(result.error().message.find("queues.scan_slots x sensors[].max_points"),
            std::string::npos)
      << result.error().message;
  EXPECT_NE(result.error().message.find("103.5 GB"), std::string::npos) << result.error().message;
}

TEST(StartupChecks, SaveOnExitNeedsAnExistingWritableFolder) {
  test::TempDir dir;
  const std::string missing = (dir.path() / "no" / "such" / "map.rmap").string();
  auto result = checkStartup(parsed("map: {save_on_exit: " + missing + "}\n"), limit(1 * kGB));
  ASSERT_FALSE(result);
  EXPECT_NE(result.error().message.find("map.save_on_exit"), std::string::npos);
  EXPECT_NE(result.error().message.find("does not exist"), std::string::npos)
      << result.error().message;
  const std::string fine = (dir.path() / "map.rmap").string();
  EXPECT_TRUE(checkStartup(parsed("map: {save_on_exit: " + fine + "}\n"), limit(1 * kGB)));
}

TEST(StartupChecks, TheMachinesLimitIsReadAndNamed) {
  const platform::MemoryLimit l = platform::availableMemory();
  EXPECT_GT(l.bytes, 0u);
  EXPECT_FALSE(l.source.empty());
}

}  // namespace
}  // namespace raymap::service
