// SPDX-License-Identifier: BSD-3-Clause
// Decay-rate maps on a device backend: the traversal layer (metres of ray path per voxel,
// kernels/common/decay.h) of the constructed exact case, and against the CPU reference on random
// scans in both semantics, occupancy and NDT-OM, both walk directions, the region cache, shared
// memory and a cache smaller than the working set. Written once; linked into one executable per
// GPU API (test_unit_opencl runs it on PoCL in CI; test_cuda_device on an NVIDIA GPU).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <iostream>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "kernels/common/decay.h"
#include "tests/device/device_under_test.hpp"
#include "tests/support/test_rays.hpp"

namespace raymap::test {
namespace {

// The device adds each voxel's lengths with atomics in another order than the CPU: the sums
// differ by float rounding only (below 1e-6 of the total per add, decay.h), far below these.
constexpr double kTraversalRelative = 1e-4;
constexpr double kTraversalAbsolute = 1e-6;   // metres, for sums near zero
constexpr double kDecayMinAgreement = 0.999;  // fraction of voxels with path within tolerance

/// Traversal and sample counts of two maps, voxel by voxel over the union of their regions.
struct DecayComparison {
  std::uint64_t with_path = 0;      ///< voxels with path in either map
  std::uint64_t within = 0;         ///< of those: within the tolerance
  std::uint64_t count_differs = 0;  ///< voxels whose sample counts differ
  double max_relative = 0.0;        ///< largest |device - cpu| / cpu over voxels with cpu > 0
  double reference_metres = 0.0;    ///< total path in the reference
};

DecayComparison compareDecay(const VoxelMap& reference, const VoxelMap& map) {
  DecayComparison result;
  std::set<std::tuple<int, int, int>> regions;
  reference.store().forEachRegion([&](std::uint32_t, Vec3i r) { regions.insert({r.x, r.y, r.z}); });
  map.store().forEachRegion([&](std::uint32_t, Vec3i r) { regions.insert({r.x, r.y, r.z}); });
  const std::uint32_t n = map.store().voxelsPerRegion();
  for (const auto& [x, y, z] : regions) {
    for (std::uint32_t i = 0; i < n; ++i) {
      const Vec3i voxel = map.voxelAt({x, y, z}, i);
      result.count_differs += reference.mean(voxel).count != map.mean(voxel).count ? 1u : 0u;
      const double a = static_cast<double>(reference.traversal(voxel));
      const double b = static_cast<double>(map.traversal(voxel));
      if (a == 0.0 && b == 0.0) {
        continue;
      }
      ++result.with_path;
      result.reference_metres += a;
      const double difference = std::fabs(a - b);
      result.within += difference <= kTraversalRelative * a + kTraversalAbsolute ? 1u : 0u;
      if (a > 0.0) {
        result.max_relative = std::max(result.max_relative, difference / a);
      }
    }
  }
  return result;
}

std::string reportLine(const std::string& label, const DecayComparison& c,
                       const BackendStats& stats) {
  char line[512];
  std::snprintf(line, sizeof(line),
                "%s %s: traversal within tolerance %.4f %% of %llu voxels (%.1f m of path), max "
                "relative difference %.3g; sample counts differ in %llu; dropped %llu",
                deviceUnderTest().api, label.c_str(),
                100.0 * double(c.within) / double(std::max<std::uint64_t>(c.with_path, 1)),
                static_cast<unsigned long long>(c.with_path), c.reference_metres, c.max_relative,
                static_cast<unsigned long long>(c.count_differs),
                static_cast<unsigned long long>(stats.updates_dropped));
  return line;
}

// Rays along +x through the centres of the voxel row y = z = 0 (0.1 m voxels), as in
// tests/unit/map/test_decay_map.cpp: voxel 10 is crossed whole by three rays and entered by two
// that end in it, 3 * 0.1 + 0.03 + 0.07 = 0.4 m for 2 samples: 5 per metre. Walked forward
// (the left-out sample voxel is in the span flagged last) and reversed (flagged first); in
// occupancy maps of both semantics and in a map of decay rates only.
TEST(DeviceDecay, AVoxelCrossedByKnownPathsWithKnownHitsHasTheExactRate) {
  REQUIRE_DEVICE();
  const MapConfig configs[] = {decayConfig(Semantics::kPerRay), decayConfig(Semantics::kPerScan),
                               decayConfig(Semantics::kPerRay).forDecay()};
  for (const MapConfig& config : configs) {
    for (const bool reverse : {false, true}) {
      // Arrange
      const std::string label = std::string(toString(config.semantics)) + ", " +
                                mapModeName(config) + (reverse ? ", reverse" : ", forward");
      VoxelMap map = makeMap(config);
      auto device = createDeviceBackend(map);
      ASSERT_TRUE(device) << label;
      const Vec3d origin{0.05, 0.05, 0.05};
      std::vector<Ray> rays;
      for (const double end_x : {1.55, 1.65, 2.35, 1.03, 1.07}) {
        rays.push_back(makeRay(origin, {end_x, 0.05, 0.05}));
      }
      // A ray without a return ends in voxel 8 (x = 0.82 m): 0.02 m of it lies there.
      rays.push_back(makeRay({0.05, 0.05, 1.05}, {0.82, 0.05, 1.05}, kRayNoReturn));
      RayFilter filter;
      filter.reverse = reverse;

      // Act
      integrate(map, *device, rays, filter);
      ASSERT_TRUE(device->synchronise()) << label;

      // Assert
      EXPECT_NEAR(map.traversal({10, 0, 0}), 0.4f, 1e-6f) << label;
      EXPECT_EQ(map.mean({10, 0, 0}).count, 2u) << label;
      EXPECT_NEAR(decayRate(map, {10, 0, 0}), 5.0f, 1e-5f) << label;
      EXPECT_NEAR(map.traversal({0, 0, 0}), 5 * 0.05f, 1e-6f) << label;
      EXPECT_EQ(decayRate(map, {0, 0, 0}), 0.0f) << label;
      EXPECT_NEAR(map.traversal({15, 0, 0}), 0.25f, 1e-6f) << label;
      EXPECT_NEAR(decayRate(map, {15, 0, 0}), 4.0f, 1e-5f) << label;
      EXPECT_TRUE(std::isnan(decayRate(map, {30, 0, 0}))) << label;
      EXPECT_NEAR(map.traversal({8, 0, 10}), 0.02f, 1e-6f) << label;
      EXPECT_EQ(map.mean({8, 0, 10}).count, 0u) << label;
      EXPECT_EQ(device->stats().updates_dropped, 0u) << label;
    }
  }
}

struct DecayCase {
  Semantics semantics;
  MapMode mode;
  bool occupancy = true;  ///< false: decay rates only (MapConfig::forDecay)

  MapConfig config() const {
    const MapConfig c = decayConfig(semantics, mode);
    return occupancy ? c : c.forDecay();
  }
};

class DeviceDecay : public testing::TestWithParam<DecayCase> {};

TEST_P(DeviceDecay, AgreesWithTheCpuReferenceOnRandomScans) {
  REQUIRE_DEVICE();
  const DecayCase c = GetParam();
  const std::vector<Ray> rays = randomScans(31337, 4, 4000);
  for (const bool reverse : {false, true}) {
    // Arrange: clipped at 9 m, so rays without a return end inside a voxel too.
    RayFilter filter;
    filter.reverse = reverse;
    filter.max_range_m = 9.0;
    VoxelMap reference = makeMap(c.config());
    auto cpu = cpuBackend(reference, 1);
    integrate(reference, *cpu, rays, filter);
    for (DeviceMemory memory : {DeviceMemory::kCache, DeviceMemory::kShared}) {
      if (memory == DeviceMemory::kShared && !deviceUnderTest().shares_memory()) {
        continue;
      }
      VoxelMap map = makeMap(c.config());
      DeviceBackendOptions options;
      options.memory = memory;
      auto device = createDeviceBackend(map, options);
      ASSERT_TRUE(device);

      // Act
      integrate(map, *device, rays, filter);
      ASSERT_TRUE(device->synchronise());
      const DecayComparison cmp = compareDecay(reference, map);
      const BackendStats stats = device->stats();

      // Assert
      const std::string label = std::string(toString(c.semantics)) + ", " +
                                mapModeName(c.config()) + (reverse ? ", reverse" : ", forward") +
                                (memory == DeviceMemory::kCache ? ", region cache" : ", shared");
      std::cout << "[device-decay] " << reportLine(label, cmp, stats) << std::endl;
      EXPECT_GT(cmp.with_path, 100000u) << label;
      EXPECT_GE(double(cmp.within), kDecayMinAgreement * double(cmp.with_path)) << label;
      EXPECT_EQ(cmp.count_differs, 0u) << label;
      EXPECT_EQ(stats.updates_dropped, 0u) << label;
      EXPECT_EQ(stats.rays_skipped, 0u) << label;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Maps, DeviceDecay,
                         testing::Values(DecayCase{Semantics::kPerRay, MapMode::kOccupancy},
                                         DecayCase{Semantics::kPerScan, MapMode::kOccupancy},
                                         DecayCase{Semantics::kPerRay, MapMode::kNdtOm},
                                         DecayCase{Semantics::kPerRay, MapMode::kOccupancy,
                                                   /*occupancy=*/false}),
                         [](const testing::TestParamInfo<DecayCase>& param_info) {
                           const DecayCase& c = param_info.param;
                           if (!c.occupancy) {
                             return std::string("DecayOnly");
                           }
                           return std::string(c.semantics == Semantics::kPerRay ? "PerRay"
                                                                                : "PerScan") +
                                  (c.mode == MapMode::kNdtOm ? "NdtOm" : "Occupancy");
                         });

// Regions leave the device with their traversal and come back with it: the path of a voxel
// spread over several visits to the cache adds up as on the CPU.
TEST(DeviceDecay, CacheSmallerThanTheWorkingSetEvictsAndStillAgrees) {
  REQUIRE_DEVICE();
  const std::vector<Ray> rays = randomScans(11, 2, 1500);
  for (const Semantics semantics : {Semantics::kPerRay, Semantics::kPerScan}) {
    // Arrange: regions of 8^3 voxels, 60 of them on the device, against several hundred a scan.
    const MapConfig config = decayConfig(semantics, MapMode::kOccupancy, 8);
    VoxelMap reference = makeMap(config);
    auto cpu = cpuBackend(reference, 1);
    integrate(reference, *cpu, rays);
    VoxelMap map = makeMap(config);
    DeviceBackendOptions options;
    options.memory = DeviceMemory::kCache;
    options.cache_regions = 60;
    options.batch_rays = 1000;
    auto device = createDeviceBackend(map, options);
    ASSERT_TRUE(device);

    // Act
    integrate(map, *device, rays);
    ASSERT_TRUE(device->synchronise());
    const DecayComparison cmp = compareDecay(reference, map);
    const BackendStats stats = device->stats();

    // Assert
    const std::string label = std::string(toString(semantics)) + ", 60-region cache";
    std::cout << "[device-decay] " << reportLine(label, cmp, stats) << std::endl;
    EXPECT_EQ(stats.cache_slots, 60u) << label;
    EXPECT_GT(stats.cache_evictions, 200u) << label;
    EXPECT_GT(cmp.with_path, 10000u) << label;
    EXPECT_GE(double(cmp.within), kDecayMinAgreement * double(cmp.with_path)) << label;
    EXPECT_EQ(cmp.count_differs, 0u) << label;
    EXPECT_EQ(stats.updates_dropped, 0u) << label;
    EXPECT_EQ(stats.rays_skipped, 0u) << label;
  }
}

}  // namespace
}  // namespace raymap::test
