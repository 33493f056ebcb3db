// SPDX-License-Identifier: BSD-3-Clause
// A device backend against the CPU reference: random scans in both semantics and walk directions,
// adversarial rays, a device cache smaller than a batch's working set, a moving rolling window,
// sync back to the host store and a saved map. Written once; linked into one executable per GPU
// API (test_unit_opencl runs it on PoCL in CI; test_cuda_device on an NVIDIA GPU).
#include <cstdio>
#include <cstring>
#include <random>
#include <set>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "src/io/map_file.hpp"
#include "tests/device/device_under_test.hpp"
#include "tests/support/file_bytes.hpp"
#include "tests/support/temp_dir.hpp"
#include "tests/support/test_rays.hpp"

namespace raymap::test {
namespace {

using test::makeRay;

/// Voxel means that differ between two maps (packed word or count), over the union of regions.
std::uint64_t meanDifferences(const VoxelMap& a, const VoxelMap& b) {
  std::set<std::tuple<int, int, int>> regions;
  a.store().forEachRegion([&](std::uint32_t, Vec3i r) { regions.insert({r.x, r.y, r.z}); });
  b.store().forEachRegion([&](std::uint32_t, Vec3i r) { regions.insert({r.x, r.y, r.z}); });
  const std::uint32_t n = a.store().voxelsPerRegion();
  std::uint64_t differing = 0;
  for (const auto& [x, y, z] : regions) {
    for (std::uint32_t i = 0; i < n; ++i) {
      const Vec3i voxel = a.voxelAt({x, y, z}, i);
      const rm_voxel_mean ma = a.mean(voxel);
      const rm_voxel_mean mb = b.mean(voxel);
      differing += (ma.count != mb.count || (ma.count != 0 && ma.packed != mb.packed)) ? 1u : 0u;
    }
  }
  return differing;
}

struct Built {
  VoxelMap map;
  BackendStats stats;
};

Built buildCpu(const MapConfig& config, const std::vector<Ray>& rays, const RayFilter& filter) {
  VoxelMap map = test::makeMap(config);
  auto backend = test::cpuBackend(map, 1);
  test::integrate(map, *backend, rays, filter);
  return {std::move(map), backend->stats()};
}

TEST(DeviceBackend, AgreesWithTheCpuReferenceOnRandomScans) {
  REQUIRE_DEVICE();
  const std::vector<Ray> rays = test::randomScans(5489, 6, 4000);
  for (Semantics semantics : {Semantics::kPerRay, Semantics::kPerScan}) {
    for (bool reverse : {false, true}) {
      RayFilter filter;
      filter.reverse = reverse;
      filter.max_range_m = 9.0;
      const Built cpu = buildCpu(test::smallConfig(semantics), rays, filter);
      // Region cache with reverse walks, shared memory with forward walks: every combination of
      // semantics, walk and memory is covered without running all eight.
      VoxelMap map = test::makeMap(test::smallConfig(semantics));
      DeviceBackendOptions options;
      options.memory = reverse || !deviceUnderTest().shares_memory() ? DeviceMemory::kCache
                                                                     : DeviceMemory::kShared;
      auto backend = createDeviceBackend(map, options);
      ASSERT_TRUE(backend);
      test::integrate(map, *backend, rays, filter);
      ASSERT_TRUE(backend->synchronise());
      const test::MapComparison cmp = test::compareMaps(cpu.map, map);
      const std::string label = std::string(toString(semantics)) +
                                (reverse ? " reverse, cache" : " forward, shared memory");
      EXPECT_GT(cmp.compared, 100000u) << label;
      // Per scan: one writer per voxel and scan, hits before misses as on the CPU. Per ray: the
      // voxels with samples replay their updates in ray order. Both exactly equal.
      EXPECT_EQ(cmp.exact_value, cmp.compared) << label;
      EXPECT_EQ(meanDifferences(cpu.map, map), 0u) << label;
      const BackendStats s = backend->stats();
      EXPECT_EQ(s.updates_dropped, 0u) << label;
      EXPECT_EQ(s.voxels_visited, cpu.stats.voxels_visited) << label;
      EXPECT_EQ(s.rays_skipped, 0u);
      EXPECT_GT(s.bytes_to_device, 0u);
      if (options.memory == DeviceMemory::kShared) {
        EXPECT_EQ(s.region_bytes_to_device + s.region_bytes_from_device, 0u) << label;
      }
    }
  }
}

TEST(DeviceBackend, PerRayReplaysHitsAndMissesInRayOrderEvenInSmallBatches) {
  REQUIRE_DEVICE();
  const std::vector<Ray> rays = test::randomScans(77, 3, 6000);
  const Built cpu = buildCpu(test::smallConfig(Semantics::kPerRay), rays, {});
  VoxelMap map = test::makeMap(test::smallConfig(Semantics::kPerRay));
  DeviceBackendOptions options;
  options.per_ray_batch_rays = 700;  // many batches, each with voxels hit by several rays
  auto backend = createDeviceBackend(map, options);
  ASSERT_TRUE(backend);
  test::integrate(map, *backend, rays);
  ASSERT_TRUE(backend->synchronise());
  EXPECT_GT(backend->stats().batches, 0u);
  const test::MapComparison cmp = test::compareMaps(cpu.map, map);
  EXPECT_GT(cmp.compared, 50000u);
  EXPECT_EQ(cmp.exact_value, cmp.compared);
  EXPECT_EQ(meanDifferences(cpu.map, map), 0u);
}

TEST(DeviceBackend, AdversarialRaysTerminateAndAgree) {
  REQUIRE_DEVICE();
  // Endpoints on a lattice of quarter voxels (faces, edges, corners), axis-aligned rays from
  // corners, zero-length rays, and long rays far from the origin.
  std::vector<Ray> rays = test::latticeRays(4242, 20000, 0.025);
  for (int axis = 0; axis < 3; ++axis) {
    for (double sign : {-1.0, 1.0}) {
      Vec3d end{0.2, -0.3, 0.5};
      (axis == 0 ? end.x : axis == 1 ? end.y : end.z) += sign * 2.4;
      rays.push_back(makeRay({0.2, -0.3, 0.5}, end));
    }
  }
  rays.push_back(makeRay({0.3, 0.3, 0.3}, {0.3, 0.3, 0.3}));
  rays.push_back(makeRay({1500.0, -2000.0, 30.0}, {1530.5, -1990.25, 31.0}));
  for (bool reverse : {false, true}) {
    RayFilter filter;
    filter.reverse = reverse;
    const Built cpu = buildCpu(test::smallConfig(Semantics::kPerScan), rays, filter);
    VoxelMap map = test::makeMap(test::smallConfig(Semantics::kPerScan));
    auto backend = createDeviceBackend(map);
    ASSERT_TRUE(backend);
    test::integrate(map, *backend, rays, filter);
    ASSERT_TRUE(backend->synchronise());
    const test::MapComparison cmp = test::compareMaps(cpu.map, map);
    EXPECT_EQ(cmp.exact_value, cmp.compared);
    EXPECT_EQ(backend->stats().voxels_visited, cpu.stats.voxels_visited);
  }
}

TEST(DeviceBackend, CacheSmallerThanTheWorkingSetEvictsAndStillAgrees) {
  REQUIRE_DEVICE();
  const std::vector<Ray> rays = test::randomScans(11, 2, 1500);
  for (Semantics semantics : {Semantics::kPerRay, Semantics::kPerScan}) {
    const Built cpu = buildCpu(test::smallConfig(semantics), rays, {});
    VoxelMap map = test::makeMap(test::smallConfig(semantics));
    DeviceBackendOptions options;
    options.memory = DeviceMemory::kCache;
    // 8^3 voxels of 4 + 8 (+ 4) bytes: 60 regions, against several hundred per scan.
    options.cache_bytes = 60u * map.store().schema().bytesPerRegion(512);
    options.batch_rays = 1000;
    auto backend = createDeviceBackend(map, options);
    ASSERT_TRUE(backend);
    test::integrate(map, *backend, rays);
    ASSERT_TRUE(backend->synchronise());
    const BackendStats s = backend->stats();
    EXPECT_EQ(s.cache_slots, 60u);
    EXPECT_GT(s.cache_evictions, 200u);
    EXPECT_GT(s.region_bytes_from_device, 0u);
    EXPECT_GT(s.region_bytes_to_device, 0u);
    EXPECT_EQ(s.rays_skipped, 0u);
    EXPECT_EQ(s.updates_dropped, 0u);
    const test::MapComparison cmp = test::compareMaps(cpu.map, map);
    EXPECT_GE(cmp.sameStateFraction(), 0.999) << toString(semantics);
    EXPECT_EQ(meanDifferences(cpu.map, map), 0u);
  }
}

TEST(DeviceBackend, RegionMovesThroughAStagingRingOfFourRegionsWaitButLoseNothing) {
  REQUIRE_DEVICE();
  // Region moves go through a staging ring (gpu::TransferStaging) freed batch by batch. With room
  // for four regions and a cache far smaller than a scan, batches wait for the device, and
  // evicted regions are wanted back while their downloads are still in the ring: the map must
  // be the one the 64 MiB ring gives, bit for bit, and per ray the CPU's (both walk in reverse;
  // per scan, a scan whose regions do not fit the cache is integrated in parts, architecture.md).
  const std::vector<Ray> rays = test::randomScans(11, 3, 1500);
  RayFilter filter;
  filter.reverse = true;
  for (Semantics semantics : {Semantics::kPerRay, Semantics::kPerScan}) {
    const Built cpu = buildCpu(test::smallConfig(semantics), rays, filter);
    DeviceBackendOptions options;
    options.memory = DeviceMemory::kCache;
    options.cache_regions = 60;
    options.batch_rays = 1000;
    std::vector<VoxelMap> maps;
    std::vector<BackendStats> stats;
    for (const std::uint64_t ring : {std::uint64_t{0}, std::uint64_t{1}}) {
      options.transfer_staging_bytes = ring;  // 0: 64 MiB; 1: raised to the floor, four regions
      maps.push_back(test::makeMap(test::smallConfig(semantics)));
      auto backend = createDeviceBackend(maps.back(), options);
      ASSERT_TRUE(backend);
      test::integrate(maps.back(), *backend, rays, filter);
      ASSERT_TRUE(backend->synchronise());
      stats.push_back(backend->stats());
    }
    const std::string label = toString(semantics);
    EXPECT_GT(stats[1].cache_evictions, 200u) << label;
    EXPECT_EQ(stats[1].cache_evictions, stats[0].cache_evictions) << label;
    EXPECT_GT(stats[1].transfer_stalls, stats[0].transfer_stalls) << label;
    std::printf(
        "[device-ring] %s %s: %llu evictions; waits: %llu with 64 MiB, %llu with four "
        "regions\n",
        deviceUnderTest().api, label.c_str(),
        static_cast<unsigned long long>(stats[1].cache_evictions),
        static_cast<unsigned long long>(stats[0].transfer_stalls),
        static_cast<unsigned long long>(stats[1].transfer_stalls));
    const test::MapComparison rings = test::compareMaps(maps[0], maps[1]);
    EXPECT_GT(rings.compared, 10000u) << label;
    EXPECT_EQ(rings.exact_value, rings.compared) << label;
    EXPECT_EQ(meanDifferences(maps[0], maps[1]), 0u) << label;
    if (semantics == Semantics::kPerRay) {
      const test::MapComparison cmp = test::compareMaps(cpu.map, maps[1]);
      EXPECT_EQ(cmp.exact_value, cmp.compared) << label;
      EXPECT_EQ(meanDifferences(cpu.map, maps[1]), 0u) << label;
    }
  }
}

TEST(DeviceBackend, RayLongerThanTheCacheIsSkippedAndCounted) {
  REQUIRE_DEVICE();
  VoxelMap map = test::makeMap(test::smallConfig(Semantics::kPerRay));
  DeviceBackendOptions options;
  options.memory = DeviceMemory::kCache;
  options.cache_bytes = 4u * map.store().schema().bytesPerRegion(512);  // 4 regions of 0.8 m
  auto backend = createDeviceBackend(map, options);
  ASSERT_TRUE(backend);
  test::integrate(map, *backend,
                  std::vector<Ray>{makeRay({0.1, 0.1, 0.1}, {9.0, 0.1, 0.1}),
                                   makeRay({0.1, 0.1, 0.1}, {0.5, 0.3, 0.1})});
  ASSERT_TRUE(backend->synchronise());
  EXPECT_EQ(backend->stats().rays_skipped, 1u);
  EXPECT_EQ(map.state({5, 3, 1}), VoxelState::kOccupied);  // the short ray still went in
  EXPECT_EQ(map.state({80, 1, 1}), VoxelState::kUnobserved);
}

/// Each test runs with the device region cache and with shared memory (skipped on devices that
/// do not share memory with the host).
class DeviceMemoryMode : public ::testing::TestWithParam<DeviceMemory> {
 protected:
  void SetUp() override {
    if (GetParam() == DeviceMemory::kShared && deviceUnderTest().unavailable().empty() &&
        !deviceUnderTest().shares_memory()) {
      GTEST_SKIP() << "the device does not share memory with the host";
    }
  }
};

TEST_P(DeviceMemoryMode, MovingRollingWindowMatchesTheCpu) {
  REQUIRE_DEVICE();
  MapConfig config = test::smallConfig(Semantics::kPerRay);
  config.policy = StorePolicy::kRolling;
  config.window_regions = {6, 6, 3};
  VoxelMap cpu_map = test::makeMap(config);
  VoxelMap map = test::makeMap(config);
  auto cpu = test::cpuBackend(cpu_map, 1);
  DeviceBackendOptions options;
  options.memory = GetParam();
  auto backend = createDeviceBackend(map, options);
  ASSERT_TRUE(backend);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int step = 0; step < 8; ++step) {
    const Vec3d robot{0.6 * step, 0.2 * step, 0.3};
    cpu_map.setWindowCentre(robot);
    map.setWindowCentre(robot);
    std::vector<Ray> rays;
    for (int i = 0; i < 3000; ++i) {
      Vec3d d{u(rng), u(rng), u(rng) * 0.3};
      d = d * (4.0 / d.norm());
      rays.push_back(makeRay(robot, robot + d));
    }
    test::integrate(cpu_map, *cpu, rays);
    test::integrate(map, *backend, rays);
  }
  ASSERT_TRUE(backend->synchronise());
  const test::MapComparison cmp = test::compareMaps(cpu_map, map);
  EXPECT_GT(cmp.compared, 10000u);
  EXPECT_EQ(cmp.exact_value, cmp.compared);
  EXPECT_EQ(backend->stats().spans_outside_window, cpu->stats().spans_outside_window);
  EXPECT_EQ(backend->stats().updates_dropped, 0u);
  // The window fits the cache: regions entering it are created on the device, never copied.
  EXPECT_EQ(backend->stats().region_bytes_to_device, 0u);
  EXPECT_EQ(backend->stats().cache_evictions, 0u);
}

TEST_P(DeviceMemoryMode, SavedMapEqualsTheCpuMap) {
  REQUIRE_DEVICE();
  const std::vector<Ray> rays = test::randomScans(8, 3, 3000);
  const Built cpu = buildCpu(test::smallConfig(Semantics::kPerScan), rays, {});
  VoxelMap map = test::makeMap(test::smallConfig(Semantics::kPerScan));
  DeviceBackendOptions options;
  options.memory = GetParam();
  auto backend = createDeviceBackend(map, options);
  ASSERT_TRUE(backend);
  test::integrate(map, *backend, rays);
  ASSERT_TRUE(backend->synchronise());
  test::TempDir dir;
  const std::string path = (dir.path() / "gpu.rmap").string();
  ASSERT_TRUE(io::saveMap(map, path));
  auto loaded = io::loadMap(path);
  ASSERT_TRUE(loaded) << loaded.error().message;
  const test::MapComparison cmp = test::compareMaps(cpu.map, *loaded);
  EXPECT_EQ(cmp.exact_value, cmp.compared);
  EXPECT_EQ(meanDifferences(cpu.map, *loaded), 0u);
}

TEST_P(DeviceMemoryMode, AMapLargerThanItsPoolStreamsThroughTheTiersAndEqualsTheCpuMap) {
  REQUIRE_DEVICE();
  // docs/large-maps.md: a pool of an eighth of the map, a compressed tier of a few dozen
  // regions. Regions leave the pool while the device still holds (cache) or wrote (shared) them:
  // the backend writes them back first, and the saved file is the CPU's, byte for byte.
  test::TempDir dir;
  const std::vector<Ray> rays = test::corridorDrive(120.0, 0.5);
  for (const Semantics semantics : {Semantics::kPerRay, Semantics::kPerScan}) {
    const MapConfig config = test::smallConfig(semantics, 16);
    VoxelMap cpu = test::makeMap(config);
    auto cpu_backend = test::cpuBackend(cpu, 1);
    test::integrateEachScan(cpu, *cpu_backend, rays);
    const MapConfig tiered =
        test::withTiers(config, cpu.regionCount() / 8, 64u << 10, dir.path().string());
    VoxelMap map = test::makeMap(tiered);
    DeviceBackendOptions options;
    options.memory = GetParam();
    auto backend = createDeviceBackend(map, options);
    ASSERT_TRUE(backend);
    test::integrateEachScan(map, *backend, rays);
    ASSERT_FALSE(map.tierFailure().has_value()) << map.tierFailure()->message;
    EXPECT_GT(map.tierStats()->evictions, cpu.regionCount() / 2);
    ASSERT_TRUE(io::saveMap(cpu, (dir.path() / "cpu.rmap").string()));
    ASSERT_TRUE(io::saveMap(map, (dir.path() / "device.rmap").string()));
    EXPECT_EQ(test::readFileBytes((dir.path() / "device.rmap").string()),
              test::readFileBytes((dir.path() / "cpu.rmap").string()))
        << toString(semantics);
  }
}

INSTANTIATE_TEST_SUITE_P(DeviceBackend, DeviceMemoryMode,
                         ::testing::Values(DeviceMemory::kCache, DeviceMemory::kShared),
                         [](const ::testing::TestParamInfo<DeviceMemory>& param_info) {
                           return std::string(param_info.param == DeviceMemory::kCache
                                                  ? "RegionCache"
                                                  : "SharedMemory");
                         });

}  // namespace
}  // namespace raymap::test
