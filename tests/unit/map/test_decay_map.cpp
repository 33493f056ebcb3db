// SPDX-License-Identifier: BSD-3-Clause
// Decay-rate maps on the CPU backend: the traversal layer holds the exact metres of ray path in
// each voxel (including the partial lengths in the origin, sample and clipped end voxels), the
// rate is samples per metre, and random "foliage" of a known reflection rate is recovered.
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "kernels/common/decay.h"
#include "src/map/cpu_backend.hpp"
#include "tests/support/test_rays.hpp"

namespace raymap {
namespace {

using test::decayConfig;
using test::decayRate;

TEST(DecayMap, TheTraversalLayerIsOnlyInDecayRateMapsAndNeedsTheMean) {
  EXPECT_FALSE(test::smallConfig(Semantics::kPerRay).schema().has(LayerKind::kTraversal));
  EXPECT_TRUE(decayConfig().schema().has(LayerKind::kTraversal));
  MapConfig no_mean = decayConfig();
  no_mean.voxel_mean = false;
  const auto ok = no_mean.validate();
  ASSERT_FALSE(ok);
  EXPECT_NE(ok.error().message.find("voxel-mean"), std::string::npos) << ok.error().message;
}

TEST(DecayMap, AMapOfDecayRatesOnlyKeepsTheMeanAndTraversalAndNeedsPerRaySemantics) {
  const MapConfig config = decayConfig().forDecay();
  ASSERT_TRUE(config.validate());
  const LayerSchema schema = config.schema();
  EXPECT_FALSE(schema.has(LayerKind::kOccupancy));
  EXPECT_TRUE(schema.has(LayerKind::kVoxelMean));
  EXPECT_TRUE(schema.has(LayerKind::kTraversal));
  EXPECT_EQ(schema.size(), 2);
  EXPECT_EQ(mapModeName(config), "decay");
  EXPECT_EQ(mapModeName(decayConfig()), "occupancy+decay");
  EXPECT_EQ(mapModeName(decayConfig(Semantics::kPerRay, MapMode::kNdtOm)), "ndt-om+decay");

  MapConfig per_scan = config;
  per_scan.semantics = Semantics::kPerScan;
  auto ok = per_scan.validate();
  ASSERT_FALSE(ok);
  EXPECT_NE(ok.error().message.find("per-ray"), std::string::npos) << ok.error().message;

  MapConfig nothing = test::smallConfig(Semantics::kPerRay);
  nothing.occupancy_layer = false;
  ok = nothing.validate();
  ASSERT_FALSE(ok);
  EXPECT_NE(ok.error().message.find("nothing to integrate"), std::string::npos)
      << ok.error().message;
}

// A map of decay rates only walks the same path and folds the same samples as an occupancy map
// with decay rates: equal traversal floats and sample counts, serially and on several workers.
TEST(DecayMap, AMapOfDecayRatesOnlyMatchesTheOccupancyMapsDecayRates) {
  const std::vector<Ray> rays = test::randomScans(41, 3, 3000);
  for (const unsigned threads : {1u, 3u}) {
    VoxelMap combined = test::makeMap(decayConfig());
    VoxelMap only = test::makeMap(decayConfig().forDecay());
    auto a = test::cpuBackend(combined, threads);
    auto b = test::cpuBackend(only, threads);
    test::integrate(combined, *a, rays);
    test::integrate(only, *b, rays);
    EXPECT_EQ(only.occupancyLayer(), -1);
    int crossed = 0;
    combined.store().forEachRegion([&](std::uint32_t, Vec3i region) {
      for (std::uint32_t i = 0; i < combined.geometry().voxelsPerRegion(); ++i) {
        const Vec3i v = combined.voxelAt(region, i);
        ASSERT_EQ(combined.traversal(v), only.traversal(v)) << v.x << "," << v.y << "," << v.z;
        ASSERT_EQ(combined.mean(v).count, only.mean(v).count) << v.x << "," << v.y << "," << v.z;
        ASSERT_EQ(combined.mean(v).packed, only.mean(v).packed);
        crossed += combined.traversal(v) > 0.0f ? 1 : 0;
      }
    });
    EXPECT_GT(crossed, 10000) << threads << " threads";
    EXPECT_EQ(only.state({0, 0, 0}), VoxelState::kUnobserved);
  }
}

// Rays along +x through the centres of the voxel row y = z = 0 (0.1 m voxels): voxel 10
// (x in [1.0, 1.1) m) is crossed whole by three rays and entered by two that end in it at
// x = 1.03 and 1.07 m. Its path is 3 * 0.1 + 0.03 + 0.07 = 0.4 m for 2 samples: 5 per metre.
TEST(DecayMap, AVoxelCrossedByKnownPathsWithKnownHitsHasTheExactRate) {
  const MapConfig configs[] = {decayConfig(Semantics::kPerRay), decayConfig(Semantics::kPerScan),
                               decayConfig(Semantics::kPerRay).forDecay()};
  for (const MapConfig& config : configs) {
    VoxelMap map = test::makeMap(config);
    auto backend = test::cpuBackend(map, 1);
    const Vec3d origin{0.05, 0.05, 0.05};
    std::vector<Ray> rays;
    for (const double end_x : {1.55, 1.65, 2.35, 1.03, 1.07}) {
      rays.push_back(test::makeRay(origin, {end_x, 0.05, 0.05}));
    }
    test::integrate(map, *backend, rays);
    EXPECT_NEAR(map.traversal({10, 0, 0}), 0.4f, 1e-6f);
    EXPECT_EQ(map.mean({10, 0, 0}).count, 2u);
    EXPECT_NEAR(decayRate(map, {10, 0, 0}), 5.0f, 1e-5f);
    // The origin voxel holds 0.05 m of each ray (from x = 0.05 to its face at 0.1), no sample.
    EXPECT_NEAR(map.traversal({0, 0, 0}), 5 * 0.05f, 1e-6f);
    EXPECT_EQ(decayRate(map, {0, 0, 0}), 0.0f);
    // The voxel of the 1.55 m sample: 0.1 m from the two longer rays, 0.05 m from its own.
    EXPECT_NEAR(map.traversal({15, 0, 0}), 0.25f, 1e-6f);
    EXPECT_NEAR(decayRate(map, {15, 0, 0}), 4.0f, 1e-5f);
    // Beyond every ray: unknown.
    EXPECT_TRUE(std::isnan(decayRate(map, {30, 0, 0})));
  }
}

TEST(DecayMap, ARayWithoutAReturnAddsItsPathToItsEndVoxelButNoSample) {
  VoxelMap map = test::makeMap(decayConfig());
  auto backend = test::cpuBackend(map, 1);
  test::integrate(
      map, *backend,
      std::vector<Ray>{test::makeRay({0.05, 0.05, 0.05}, {0.82, 0.05, 0.05}, kRayNoReturn)});
  EXPECT_NEAR(map.traversal({8, 0, 0}), 0.02f, 1e-6f);
  EXPECT_EQ(map.mean({8, 0, 0}).count, 0u);
  EXPECT_EQ(decayRate(map, {8, 0, 0}), 0.0f);
}

// Every ray's voxel lengths add up to its length, whatever its direction, however many regions
// it crosses, with or without a return, and with the map's walk in either direction.
TEST(DecayMap, TheLengthsOfARaysVoxelsAddUpToTheRay) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> coord(-3.0, 3.0);
  for (int i = 0; i < 200; ++i) {
    VoxelMap map = test::makeMap(decayConfig());
    auto backend = test::cpuBackend(map, 1);
    const Vec3d origin{coord(rng), coord(rng), coord(rng) * 0.3};
    const Vec3d sample{coord(rng), coord(rng), coord(rng) * 0.3};
    const std::uint32_t flags = i % 3 == 0 ? kRayNoReturn : 0u;
    test::integrate(map, *backend, std::vector<Ray>{test::makeRay(origin, sample, flags)});
    double total = 0.0;
    const RegionStore& store = map.store();
    store.forEachRegion([&](std::uint32_t slot, Vec3i) {
      const float* t = store.layerData<float>(slot, map.traversalLayer());
      for (std::uint32_t v = 0; v < map.geometry().voxelsPerRegion(); ++v) {
        total += double(t[v]);
      }
    });
    const double length = (sample - origin).norm();
    EXPECT_NEAR(total, length, 1e-5 * (1.0 + length)) << "ray " << i;
  }
}

// "Foliage": every metre of ray path reflects with probability rate * dl, everywhere. A ray's
// return is at an exponentially distributed range; past 3 m it has no return. Each voxel's
// samples over metres is then an unbiased estimate of the rate, and summed over the voxels around
// the sensor it is within 5 % of the truth.
TEST(DecayMap, UniformFoliageOfAKnownDensityGivesItsRate) {
  constexpr double kRate = 2.0;  // reflections per metre
  constexpr double kMaxRange = 3.0;
  VoxelMap map = test::makeMap(decayConfig());
  auto backend = test::cpuBackend(map, 2);
  std::mt19937_64 rng(11);
  std::exponential_distribution<double> free_path(kRate);
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::vector<Ray> rays;
  const Vec3d origin{0.05, 0.05, 0.05};
  for (int i = 0; i < 200000; ++i) {
    Vec3d d{gauss(rng), gauss(rng), gauss(rng)};
    d = d * (1.0 / d.norm());
    const double s = free_path(rng);
    rays.push_back(s < kMaxRange ? test::makeRay(origin, origin + d * s)
                                 : test::makeRay(origin, origin + d * kMaxRange, kRayNoReturn));
  }
  test::integrate(map, *backend, rays);
  // Shells of voxels around the sensor: no bias with range, and within 5 % in each.
  const double shells[] = {0.3, 0.6, 0.9, 1.2};
  for (int shell = 0; shell < 3; ++shell) {
    double samples = 0.0;
    double metres = 0.0;
    int voxels = 0;
    for (int x = -12; x <= 12; ++x) {
      for (int y = -12; y <= 12; ++y) {
        for (int z = -12; z <= 12; ++z) {
          const double r = std::sqrt(double(x * x + y * y + z * z)) * 0.1;
          if (r < shells[shell] || r >= shells[shell + 1]) {
            continue;
          }
          samples += map.mean({x, y, z}).count;
          metres += double(map.traversal({x, y, z}));
          ++voxels;
        }
      }
    }
    const double estimate = samples / metres;
    std::printf(
        "foliage %.1f-%.1f m: %.0f samples over %.1f m in %d voxels: %.4f per metre "
        "(truth %.1f)\n",
        shells[shell], shells[shell + 1], samples, metres, voxels, estimate, kRate);
    EXPECT_NEAR(estimate, kRate, 0.05 * kRate) << "shell " << shell;
  }
}

TEST(DecayMap, NdtAndDecayRateCombineAndOneWorkerOrSeveralAgree) {
  const std::vector<Ray> rays = test::randomScans(23, 3, 3000);
  for (const MapMode mode : {MapMode::kOccupancy, MapMode::kNdtOm}) {
    VoxelMap serial = test::makeMap(decayConfig(Semantics::kPerRay, mode));
    VoxelMap parallel = test::makeMap(decayConfig(Semantics::kPerRay, mode));
    auto one = test::cpuBackend(serial, 1);
    auto four = test::cpuBackend(parallel, 4);
    test::integrate(serial, *one, rays);
    test::integrate(parallel, *four, rays);
    int compared = 0;
    serial.store().forEachRegion([&](std::uint32_t, Vec3i region) {
      const Vec3i base{region.x * 16, region.y * 16, region.z * 16};
      for (int z = 0; z < 16; ++z) {
        for (int y = 0; y < 16; ++y) {
          for (int x = 0; x < 16; ++x) {
            const Vec3i v = base + Vec3i{x, y, z};
            const float a = serial.traversal(v);
            ASSERT_EQ(a, parallel.traversal(v)) << v.x << "," << v.y << "," << v.z;
            compared += a > 0.0f ? 1 : 0;
          }
        }
      }
    });
    EXPECT_GT(compared, 10000) << toString(mode);
  }
}

}  // namespace
}  // namespace raymap
