// SPDX-License-Identifier: BSD-3-Clause
// The device height-map generator in its integration backend's context (one context per
// process): it reads the map where integration left it, and its height maps equal the CPU
// generator's on the same map, cell for cell, while the rolling window moves every cycle, in
// both memory modes, and when the device cache is too small for the box. Written once; linked
// into one executable per GPU API (test_unit_opencl runs it on PoCL in CI; test_cuda_device on
// an NVIDIA GPU).
#include <cmath>
#include <cstdint>
#include <cstring>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "src/heightmap/heightmap_generator.hpp"
#include "src/heightmap/heightmap_plan.hpp"
#include "tests/device/device_under_test.hpp"
#include "tests/support/test_rays.hpp"

namespace raymap::test {
namespace {

using heightmap::HeightMap;
using heightmap::HeightmapOptions;
using heightmap::HeightmapPlan;

constexpr double kSensorHeight = 0.6;  // metres above the ground
constexpr double kBoxHeight = 0.45;    // metres: the obstacles' tops

/// Ground at z = 0 with boxes 0.6 m square on a 2 m grid (every third cell left free): the
/// height of the surface at (x, y).
double surfaceHeight(double x, double y) {
  const double cx = std::floor(x / 2.0);
  const double cy = std::floor(y / 2.0);
  const bool box_cell = static_cast<long>(cx + 3 * cy) % 3 != 0;
  const bool inside = x - 2.0 * cx < 0.6 && y - 2.0 * cy < 0.6;
  return box_cell && inside ? kBoxHeight : 0.0;
}

/// One scan from a sensor above `robot`: rays to the surface in a disc of 5 m, every 13th a
/// no-return ray (free space to its end).
std::vector<Ray> scanAt(Vec3d robot, std::uint64_t scan, std::mt19937_64& rng, int count = 6000) {
  std::uniform_real_distribution<double> radius(0.3, 5.0);
  std::uniform_real_distribution<double> angle(0.0, 6.283185307179586);
  const Vec3d sensor{robot.x, robot.y, kSensorHeight};
  std::vector<Ray> rays;
  for (int i = 0; i < count; ++i) {
    const double r = radius(rng);
    const double a = angle(rng);
    const double x = robot.x + r * std::cos(a);
    const double y = robot.y + r * std::sin(a);
    const bool no_return = i % 13 == 0;
    rays.push_back(
        makeRay(sensor, {x, y, surfaceHeight(x, y)}, no_return ? kRayNoReturn : 0u, scan));
  }
  return rays;
}

/// Cells whose layers differ (NaN equals NaN: the device may write another NaN payload).
int differingCells(const HeightMap& a, const HeightMap& b) {
  if (a.cellCount() != b.cellCount() || a.has_normals != b.has_normals) {
    return -1;
  }
  auto same = [](float x, float y) { return (std::isnan(x) && std::isnan(y)) || x == y; };
  int differing = 0;
  for (std::size_t n = 0; n < a.cellCount(); ++n) {
    bool equal = same(a.elevation[n], b.elevation[n]) && same(a.clearance[n], b.clearance[n]) &&
                 a.kind[n] == b.kind[n] && a.observed_count[n] == b.observed_count[n] &&
                 same(a.reference[n], b.reference[n]);
    if (a.has_normals) {
      equal = equal && same(a.normal_x[n], b.normal_x[n]) && same(a.normal_y[n], b.normal_y[n]) &&
              same(a.normal_z[n], b.normal_z[n]);
    }
    differing += equal ? 0 : 1;
  }
  return differing;
}

/// Cells the height map found a surface in (so that a comparison is not of empty maps).
int surfaceCells(const HeightMap& h) {
  int cells = 0;
  for (std::size_t n = 0; n < h.cellCount(); ++n) {
    cells += std::isnan(h.elevation[n]) ? 0 : 1;
  }
  return cells;
}

std::unique_ptr<heightmap::HeightmapGenerator> residentGenerator(Backend& backend) {
  auto generator = deviceUnderTest().create_heightmap(backend);
  EXPECT_TRUE(generator) << (generator ? "" : generator.error().message);
  return generator ? std::move(*generator) : nullptr;
}

/// Memory mode x map mode (occupancy with voxel means; NDT-OM, whose height maps have normals).
class DeviceHeightmap : public ::testing::TestWithParam<std::tuple<DeviceMemory, MapMode>> {
 protected:
  void SetUp() override {
    if (std::get<0>(GetParam()) == DeviceMemory::kShared &&
        deviceUnderTest().unavailable().empty() && !deviceUnderTest().shares_memory()) {
      GTEST_SKIP() << "the device does not share memory with the host";
    }
  }
};

TEST_P(DeviceHeightmap, EqualsTheCpuGeneratorWhileTheWindowMovesEveryCycle) {
  REQUIRE_DEVICE();
  const auto [memory, mode] = GetParam();
  // NDT maps integrate per ray (each ray's miss depends on where it crosses a Gaussian).
  MapConfig config =
      smallConfig(mode == MapMode::kOccupancy ? Semantics::kPerScan : Semantics::kPerRay);
  config.mode = mode;
  config.voxel_mean = true;
  config.policy = StorePolicy::kRolling;
  config.window_regions = {10, 10, 6};  // 8 x 8 x 4.8 m of 0.8 m regions
  VoxelMap map = makeMap(config);
  // Regions the host holds before the device sees them, in an order no ray follows: a region's
  // cache slot then differs from its host slot, as it does on a robot after a while.
  map.setWindowCentre({0.0, 0.0, 0.0});
  for (int x = 4; x >= -4; --x) {
    ASSERT_TRUE(map.acquireRegion({x, -x / 2, 0}));
  }
  DeviceBackendOptions options;
  options.memory = memory;
  auto backend = createDeviceBackend(map, options);
  ASSERT_TRUE(backend);
  auto device = residentGenerator(*backend);
  ASSERT_TRUE(device);
  EXPECT_FALSE(device->readsHostStore());
  auto cpu = heightmap::makeCpuHeightmapGenerator();

  HeightmapOptions request;
  request.size = 4.0;
  HeightmapPlan plan;
  HeightMap on_device;
  HeightMap on_cpu;
  std::mt19937_64 rng(11);
  int compared = 0;
  for (int step = 0; step < 12; ++step) {
    // As raymapd's cycle: a scan is integrated, the robot moves on (0.9 m: more than a region,
    // so the window moves every cycle), the window follows it and the height map is generated.
    const Vec3d robot{0.9 * step, 0.35 * step, 0.0};
    integrate(map, *backend, scanAt(robot, static_cast<std::uint64_t>(step), rng));
    const Vec3d next{0.9 * (step + 1), 0.35 * (step + 1), 0.0};
    map.setWindowCentre(next);
    request.centre = next;
    ASSERT_TRUE(heightmap::planHeightmap(map, request, plan));
    const BackendStats before = backend->stats();
    const std::uint64_t copied = device->bytesCopied();
    auto generated = device->generate(map, plan, on_device);
    ASSERT_TRUE(generated) << generated.error().message;
    const BackendStats after = backend->stats();
    // The window fits the device (cache or shared pool): no region moves for the height map.
    EXPECT_EQ(after.region_bytes_from_device, before.region_bytes_from_device) << "step " << step;
    EXPECT_EQ(after.region_bytes_to_device, before.region_bytes_to_device) << "step " << step;
    // Copied: the region table, the slot table and the output layers, nothing of the map.
    const std::uint64_t layers = on_device.has_normals ? 8 : 5;
    EXPECT_EQ(device->bytesCopied() - copied,
              4 * (plan.region_table.size() + std::max<std::size_t>(plan.region_slots.size(), 1) +
                   layers * on_device.cellCount()))
        << "step " << step;
    if (step % 2 == 1) {
      // Every other cycle only, so that cycles also run on a map nobody synchronised.
      ASSERT_TRUE(backend->synchronise());
      ASSERT_TRUE(cpu->generate(map, plan, on_cpu));
      EXPECT_EQ(differingCells(on_device, on_cpu), 0) << "step " << step;
      EXPECT_GT(surfaceCells(on_cpu), static_cast<int>(on_cpu.cellCount() / 2)) << "step " << step;
      ++compared;
    }
  }
  EXPECT_EQ(compared, 6);
  EXPECT_GT(map.regionsRecycled(), 100u);
}

INSTANTIATE_TEST_SUITE_P(
    MemoryAndMode, DeviceHeightmap,
    ::testing::Combine(::testing::Values(DeviceMemory::kShared, DeviceMemory::kCache),
                       ::testing::Values(MapMode::kOccupancy, MapMode::kNdtOm)),
    [](const ::testing::TestParamInfo<std::tuple<DeviceMemory, MapMode>>& p) {
      return std::string(std::get<0>(p.param) == DeviceMemory::kShared ? "Shared" : "Cache") +
             (std::get<1>(p.param) == MapMode::kOccupancy ? "Occupancy" : "NdtOm");
    });

/// A device cache smaller than the map: the height map's regions are brought back onto the
/// device (evicting others), or, when the cache cannot hold the box at once, read from the
/// synchronised host store. Both give the CPU generator's height map.
TEST(DeviceHeightmapCache, RegionsOutsideTheCacheAreReadCorrectly) {
  REQUIRE_DEVICE();
  MapConfig config = smallConfig(Semantics::kPerScan);
  config.voxel_mean = true;
  std::mt19937_64 rng(5);
  std::vector<Ray> rays;
  for (int step = 0; step < 10; ++step) {
    const std::vector<Ray> scan =
        scanAt({1.2 * step, 0.0, 0.0}, static_cast<std::uint64_t>(step), rng, 3000);
    rays.insert(rays.end(), scan.begin(), scan.end());
  }
  auto cpu = heightmap::makeCpuHeightmapGenerator();
  HeightmapOptions request;
  request.size = 6.0;
  request.centre = {3.0, 0.0, 0.0};  // where the drive began: long evicted from a small cache
  // The box covers about 100 of the map's 335 regions: 60 slots cannot hold it at once (the
  // fallback), 200 hold it but not the map (regions brought back, evicting others).
  for (const std::uint32_t cache_regions : {60u, 200u}) {
    VoxelMap map = makeMap(config);
    DeviceBackendOptions options;
    options.memory = DeviceMemory::kCache;
    options.cache_regions = cache_regions;
    auto backend = createDeviceBackend(map, options);
    ASSERT_TRUE(backend);
    auto device = residentGenerator(*backend);
    ASSERT_TRUE(device);
    integrate(map, *backend, rays);
    EXPECT_GT(backend->stats().cache_evictions, 0u) << cache_regions;
    HeightmapPlan plan;
    ASSERT_TRUE(heightmap::planHeightmap(map, request, plan));
    HeightMap on_device;
    ASSERT_GT(plan.region_slots.size(), 60u);
    ASSERT_LT(plan.region_slots.size(), 200u);
    ASSERT_EQ(backend->stats().sync_seconds, 0.0);
    auto generated = device->generate(map, plan, on_device);
    ASSERT_TRUE(generated) << generated.error().message;
    // Only the cache that cannot hold the box synchronised (and read the host store).
    EXPECT_EQ(backend->stats().sync_seconds > 0.0, cache_regions == 60u) << cache_regions;
    // Integration goes on after the read (the regions it pinned are given back).
    integrate(map, *backend, scanAt({2.0, 0.5, 0.0}, 99, rng));
    ASSERT_TRUE(heightmap::planHeightmap(map, request, plan));
    generated = device->generate(map, plan, on_device);
    ASSERT_TRUE(generated) << generated.error().message;
    ASSERT_TRUE(backend->synchronise());
    HeightMap on_cpu;
    ASSERT_TRUE(cpu->generate(map, plan, on_cpu));
    EXPECT_EQ(differingCells(on_device, on_cpu), 0) << cache_regions;
    EXPECT_GT(surfaceCells(on_cpu), static_cast<int>(on_cpu.cellCount() / 2)) << cache_regions;
  }
}

TEST(DeviceHeightmapCache, RefusesAMapItsBackendDoesNotIntegrate) {
  REQUIRE_DEVICE();
  VoxelMap map = makeMap(smallConfig(Semantics::kPerScan));
  VoxelMap other = makeMap(smallConfig(Semantics::kPerScan));
  auto backend = createDeviceBackend(map, {});
  ASSERT_TRUE(backend);
  auto device = residentGenerator(*backend);
  ASSERT_TRUE(device);
  std::mt19937_64 rng(1);
  integrate(other, *cpuBackend(other, 1), scanAt({0.0, 0.0, 0.0}, 0, rng));
  HeightmapOptions request;
  request.size = 2.0;
  HeightmapPlan plan;
  ASSERT_TRUE(heightmap::planHeightmap(other, request, plan));
  HeightMap out;
  auto generated = device->generate(other, plan, out);
  ASSERT_FALSE(generated);
  EXPECT_NE(generated.error().message.find("not the one its backend integrates into"),
            std::string::npos)
      << generated.error().message;
}

}  // namespace
}  // namespace raymap::test
