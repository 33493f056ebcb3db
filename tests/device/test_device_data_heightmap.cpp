// SPDX-License-Identifier: BSD-3-Clause
// The device height-map generator in its backend's context on the shared Ouster data: a rolling
// map integrated on the device in tenths, the window moved every cycle (a region or more), and
// each height map equal to the CPU generator's on the same map, cell for cell, in both memory
// modes. Written once; linked into test_opencl_data and test_cuda_data. Skips without the data
// or the device.
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "src/heightmap/heightmap_generator.hpp"
#include "src/heightmap/heightmap_plan.hpp"
#include "src/map/ray_preparer.hpp"
#include "tests/device/device_under_test.hpp"
#include "tests/support/shared_data.hpp"
#include "tests/support/test_rays.hpp"

namespace raymap::test {
namespace {

using heightmap::HeightMap;

/// Cells whose layers differ (NaN equals NaN: the device may write another NaN payload).
int differingCells(const HeightMap& a, const HeightMap& b) {
  auto same = [](float x, float y) { return (std::isnan(x) && std::isnan(y)) || x == y; };
  int differing = 0;
  for (std::size_t n = 0; n < a.cellCount(); ++n) {
    differing += same(a.elevation[n], b.elevation[n]) && same(a.clearance[n], b.clearance[n]) &&
                         a.kind[n] == b.kind[n] && a.observed_count[n] == b.observed_count[n] &&
                         same(a.reference[n], b.reference[n])
                     ? 0
                     : 1;
  }
  return differing;
}

class DeviceDataHeightmap : public ::testing::TestWithParam<DeviceMemory> {};

TEST_P(DeviceDataHeightmap, OusterHeightMapsEqualTheCpuGeneratorWhileTheWindowMoves) {
  REQUIRE_DEVICE();
  if (GetParam() == DeviceMemory::kShared && !deviceUnderTest().shares_memory()) {
    GTEST_SKIP() << "the device does not share memory with the host";
  }
  const DataFiles files = dataFiles(sharedDataSets()[0]);  // the Ouster drive
  if (!files.missing.empty()) {
    GTEST_SKIP() << files.missing;
  }
  const std::vector<Ray> rays = loadRays(files.file, files.trajectory);
  ASSERT_GT(rays.size(), 300000u);

  // raymapd's map at 0.1 m, with 1.6 m regions so that the shifts below move the window.
  MapConfig config;
  config.geometry.resolution = 0.1;
  config.geometry.region_voxels = 16;
  config.semantics = Semantics::kPerRay;
  config.voxel_mean = true;
  config.policy = StorePolicy::kRolling;
  config.window_regions = {16, 16, 6};  // 25.6 x 25.6 x 9.6 m
  VoxelMap map = makeMap(config);
  // Regions the host holds before the device sees them, in an order no ray follows: a region's
  // cache slot then differs from its host slot, as it does on a robot after a while.
  map.setWindowCentre(rays.front().origin);
  const Vec3i first = map.regionOfVoxel(map.voxelOf(rays.front().origin));
  for (int x = 5; x >= -5; --x) {
    ASSERT_TRUE(map.acquireRegion({first.x + x, first.y - x / 2, first.z}));
  }
  DeviceBackendOptions options;
  options.memory = GetParam();
  auto backend = createDeviceBackend(map, options);
  ASSERT_TRUE(backend);
  auto created = deviceUnderTest().create_heightmap(*backend);
  ASSERT_TRUE(created) << created.error().message;
  heightmap::HeightmapGenerator& device = **created;
  auto cpu = heightmap::makeCpuHeightmapGenerator();

  RayFilter filter;
  filter.max_range_m = 20.0;
  RayPreparer preparer(map, filter);
  std::vector<PreparedRay> prepared;
  heightmap::HeightmapOptions request;
  request.size = 20.0;
  heightmap::HeightmapPlan plan;
  HeightMap on_device;
  HeightMap on_cpu;
  const std::size_t tenth = rays.size() / 10 + 1;
  int cycles = 0;
  int surfaces = 0;
  std::uint64_t recycled = map.regionsRecycled();
  int moves = 0;
  for (std::size_t begin = 0; begin < rays.size(); begin += tenth) {
    const std::size_t end = std::min(rays.size(), begin + tenth);
    const std::span<const Ray> part(rays.data() + begin, end - begin);
    prepared.resize(part.size() * 2);
    const RayPreparer::Progress progress = preparer.prepare(part, prepared);
    ASSERT_EQ(progress.consumed, part.size());
    ASSERT_TRUE(
        backend->integrate(std::span<const PreparedRay>(prepared.data(), progress.written)));
    // The sensor, shifted by a region or more in a different direction each cycle.
    const Vec3d sensor = rays[end - 1].origin;
    const Vec3d centre{sensor.x + 1.7 * static_cast<double>(cycles % 3 - 1),
                       sensor.y + 1.7 * static_cast<double>((cycles + 1) % 3 - 1), sensor.z};
    map.setWindowCentre(centre);
    moves += map.regionsRecycled() != recycled ? 1 : 0;
    recycled = map.regionsRecycled();
    request.centre = {centre.x, centre.y, sensor.z - 1.2};
    ASSERT_TRUE(heightmap::planHeightmap(map, request, plan));
    auto generated = device.generate(map, plan, on_device);
    ASSERT_TRUE(generated) << generated.error().message;
    ASSERT_TRUE(backend->synchronise());
    ASSERT_TRUE(cpu->generate(map, plan, on_cpu));
    EXPECT_EQ(differingCells(on_device, on_cpu), 0) << "cycle " << cycles;
    for (std::size_t n = 0; n < on_cpu.cellCount(); ++n) {
      surfaces += std::isnan(on_cpu.elevation[n]) ? 0 : 1;
    }
    ++cycles;
  }
  EXPECT_EQ(cycles, 10);
  EXPECT_GE(moves, 6) << "the window moved in too few cycles";
  EXPECT_GT(surfaces, 10 * 5000) << "too few surface cells compared";
}

INSTANTIATE_TEST_SUITE_P(Memory, DeviceDataHeightmap,
                         ::testing::Values(DeviceMemory::kShared, DeviceMemory::kCache),
                         [](const ::testing::TestParamInfo<DeviceMemory>& p) {
                           return std::string(p.param == DeviceMemory::kShared ? "Shared"
                                                                               : "Cache");
                         });

}  // namespace
}  // namespace raymap::test
