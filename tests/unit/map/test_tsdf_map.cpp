// SPDX-License-Identifier: BSD-3-Clause
// TSDF maps on the CPU backend: the zero crossing of a simulated plane, sphere and box lies within
// 0.25 voxel of the true surface, signs are right on both sides of it within the truncation band
// (the walk goes on behind the sample), weights saturate at the maximum, rays without a return
// only clear, and the result is compared with Voxblox's fusion rule.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include <gtest/gtest.h>

#include "kernels/common/tsdf.h"
#include "src/map/cpu_backend.hpp"
#include "src/map/tsdf_surface.hpp"
#include "tests/support/test_rays.hpp"
#include "tests/support/tsdf_scenes.hpp"

namespace raymap {
namespace {

constexpr double kResolution = 0.1;

using test::tsdfConfig;

struct SceneCheck {
  std::size_t crossings = 0;
  double worst_crossing_voxels = 0.0;  // largest |truth| at a zero crossing, voxel edges
  std::size_t signed_voxels = 0;       // voxels checked for sign
  std::size_t wrong_signs = 0;
  std::size_t negative_voxels = 0;  // checked voxels inside the shape
};

// Checks voxels and crossings with at least `min_weight` of weight.
SceneCheck checkScene(const VoxelMap& map, const test::TsdfScene& scene, float min_weight) {
  SceneCheck check;
  for (const TsdfSurfacePoint& p : tsdfZeroCrossings(map, min_weight)) {
    if (!scene.checked(p.p_world)) {
      continue;
    }
    ++check.crossings;
    check.worst_crossing_voxels =
        std::max(check.worst_crossing_voxels, std::fabs(scene.truth(p.p_world)) / kResolution);
  }
  const double tau = map.config().tsdf.truncationMetres(kResolution);
  map.store().forEachRegion([&](std::uint32_t slot, Vec3i region) {
    const auto* tsdf = map.store().layerData<rm_tsdf_voxel>(slot, map.tsdfLayer());
    for (std::uint32_t i = 0; i < map.store().voxelsPerRegion(); ++i) {
      if (tsdf[i].weight < min_weight) {
        continue;
      }
      const Vec3i voxel = map.voxelAt(region, i);
      if (!scene.checked(map.voxelCentre(voxel))) {
        continue;
      }
      const double truth = scene.truth(map.voxelCentre(voxel));
      // Within the band, away from the surface by a quarter voxel (the tolerance of the
      // crossing itself).
      if (std::fabs(truth) < 0.25 * kResolution || std::fabs(truth) >= tau) {
        continue;
      }
      ++check.signed_voxels;
      check.negative_voxels += truth < 0.0 ? 1u : 0u;
      check.wrong_signs += (tsdf[i].distance >= 0.0f) != (truth >= 0.0) ? 1u : 0u;
    }
  });
  std::printf(
      "%s: %zu rays, %zu crossings, worst %.3f voxel; %zu voxels signed (%zu inside), "
      "%zu wrong\n",
      scene.name.c_str(), scene.rays.size(), check.crossings, check.worst_crossing_voxels,
      check.signed_voxels, check.negative_voxels, check.wrong_signs);
  return check;
}

void expectSurface(const test::TsdfScene& scene, unsigned threads) {
  VoxelMap map = test::makeMap(tsdfConfig());
  auto backend = test::cpuBackend(map, threads);
  test::integrate(map, *backend, scene.rays);
  // Voxels and crossings with 50 rays or more: a single ray's distance is off by up to the
  // voxel's offset from the ray times the tangent of the incidence (the projective distance is
  // taken at the voxel centre's projection), and such errors average out over rays.
  const SceneCheck check = checkScene(map, scene, 50.0f);
  EXPECT_GT(check.crossings, 100u);
  EXPECT_LE(check.worst_crossing_voxels, 0.25);
  EXPECT_GT(check.signed_voxels, 500u);
  EXPECT_EQ(check.wrong_signs, 0u);
  // The walk goes on behind the sample: the inside of the band is populated too.
  EXPECT_GT(check.negative_voxels, check.signed_voxels / 4);
}

TEST(TsdfMap, ATsdfMapHoldsOnlyTheDistanceLayer) {
  const MapConfig config = tsdfConfig();
  ASSERT_TRUE(config.validate());
  EXPECT_TRUE(config.schema().has(LayerKind::kTsdf));
  EXPECT_EQ(config.schema().size(), 1);
  MapConfig with_occupancy = config;
  with_occupancy.occupancy_layer = true;
  const auto ok = with_occupancy.validate();
  ASSERT_FALSE(ok);
  EXPECT_NE(ok.error().message.find("tsdf"), std::string::npos) << ok.error().message;
  MapConfig bad = config;
  bad.tsdf.dropoff_m = 0.5;  // beyond the 0.3 m truncation
  ASSERT_FALSE(bad.validate());
  EXPECT_NE(bad.validate().error().message.find("dropoff"), std::string::npos);
  EXPECT_EQ(mapModeName(config), "tsdf");
}

TEST(TsdfMap, ThePlanesZeroCrossingIsWithinAQuarterVoxelWithSignsRightOnBothSides) {
  expectSurface(test::planeScene(12000), 1);
}

TEST(TsdfMap, TheSpheresZeroCrossingIsWithinAQuarterVoxelWithSignsRightOnBothSides) {
  expectSurface(test::sphereScene(12000), 1);
}

TEST(TsdfMap, TheBoxsZeroCrossingIsWithinAQuarterVoxelWithSignsRightOnBothSides) {
  expectSurface(test::boxScene(12000, 0.3), 2);
}

TEST(TsdfMap, SerialAndParallelIntegrationGiveTheSameField) {
  const test::TsdfScene scene = test::sphereScene(1500);
  VoxelMap serial = test::makeMap(tsdfConfig());
  VoxelMap parallel = test::makeMap(tsdfConfig());
  auto one = test::cpuBackend(serial, 1);
  auto two = test::cpuBackend(parallel, 2);
  test::integrate(serial, *one, scene.rays);
  test::integrate(parallel, *two, scene.rays);
  std::size_t compared = 0;
  serial.store().forEachRegion([&](std::uint32_t slot, Vec3i region) {
    const auto* a = serial.store().layerData<rm_tsdf_voxel>(slot, serial.tsdfLayer());
    for (std::uint32_t i = 0; i < serial.store().voxelsPerRegion(); ++i) {
      const rm_tsdf_voxel b = parallel.tsdf(serial.voxelAt(region, i));
      ASSERT_EQ(a[i].distance, b.distance);
      ASSERT_EQ(a[i].weight, b.weight);
      compared += a[i].weight > 0.0f ? 1u : 0u;
    }
  });
  EXPECT_GT(compared, 1000u);
}

TEST(TsdfMap, WeightsSaturateAtTheMaximum) {
  const test::TsdfScene scene = test::planeScene(12000);
  VoxelMap map = test::makeMap(tsdfConfig(20.0));
  auto backend = test::cpuBackend(map, 1);
  test::integrate(map, *backend, scene.rays);
  std::size_t saturated = 0;
  float largest = 0.0f;
  map.store().forEachRegion([&](std::uint32_t slot, Vec3i) {
    const auto* tsdf = map.store().layerData<rm_tsdf_voxel>(slot, map.tsdfLayer());
    for (std::uint32_t i = 0; i < map.store().voxelsPerRegion(); ++i) {
      largest = std::max(largest, tsdf[i].weight);
      saturated += tsdf[i].weight == 20.0f ? 1u : 0u;
    }
  });
  EXPECT_EQ(largest, 20.0f);
  EXPECT_GT(saturated, 1000u);
  // Still a surface where it was.
  EXPECT_LE(checkScene(map, scene, 20.0f).worst_crossing_voxels, 0.25);
}

// A ray straight down onto z = 0.537 m through voxel column (3, 3): distances along it are exact.
TEST(TsdfMap, OneRayGivesTheProjectiveDistanceInFrontAndBehindTheSurface) {
  VoxelMap map = test::makeMap(tsdfConfig());
  auto backend = test::cpuBackend(map, 1);
  test::integrate(map, *backend,
                  std::vector<Ray>{test::makeRay({0.35, 0.35, 1.5}, {0.35, 0.35, 0.537})});
  // Voxel z = 5 (centre 0.55 m): 0.013 m in front. z = 4 (0.45 m): 0.087 m behind. z = 3
  // (0.35 m): 0.187 m behind, weight dropped off to (0.3 - 0.187) / (0.3 - 0.1).
  EXPECT_NEAR(map.tsdf({3, 3, 5}).distance, 0.013f, 1e-5f);
  EXPECT_EQ(map.tsdf({3, 3, 5}).weight, 1.0f);
  EXPECT_NEAR(map.tsdf({3, 3, 4}).distance, -0.087f, 1e-5f);
  EXPECT_EQ(map.tsdf({3, 3, 4}).weight, 1.0f);
  EXPECT_NEAR(map.tsdf({3, 3, 3}).distance, -0.187f, 1e-5f);
  EXPECT_NEAR(map.tsdf({3, 3, 3}).weight, (0.3f - 0.187f) / 0.2f, 1e-5f);
  // In front beyond the band: truncated to +tau. The voxel holding the walk's end (0.237 m) and
  // everything beyond: untouched.
  EXPECT_NEAR(map.tsdf({3, 3, 10}).distance, 0.3f, 1e-6f);
  EXPECT_EQ(map.tsdf({3, 3, 2}).weight, 0.0f);
  EXPECT_EQ(map.tsdf({3, 3, 1}).weight, 0.0f);
}

TEST(TsdfMap, RaysWithoutAReturnOrBeyondMaxRangeOnlyClearFreeSpace) {
  VoxelMap map = test::makeMap(tsdfConfig());
  auto backend = test::cpuBackend(map, 1);
  RayFilter filter;
  filter.max_range_m = 1.0;
  test::integrate(
      map, *backend,
      std::vector<Ray>{test::makeRay({0.35, 0.35, 1.5}, {0.35, 0.35, 0.537}, kRayNoReturn),
                       test::makeRay({0.65, 0.35, 1.5}, {0.65, 0.35, 0.237})},
      filter);
  for (int z = 0; z <= 15; ++z) {
    for (const int x : {3, 6}) {
      const rm_tsdf_voxel v = map.tsdf({x, 3, z});
      if (v.weight > 0.0f) {
        EXPECT_NEAR(v.distance, 0.3f, 1e-6f) << "x " << x << " z " << z;
      }
    }
  }
  EXPECT_GT(map.tsdf({3, 3, 7}).weight, 0.0f);
  EXPECT_EQ(map.tsdf({3, 3, 5}).weight, 0.0f);  // the no-return end voxel: partly seen
}

TEST(TsdfMap, SegmentedRaysGiveTheSameFieldAsWholeOnes) {
  const test::TsdfScene scene = test::sphereScene(500);
  VoxelMap whole = test::makeMap(tsdfConfig());
  VoxelMap cut = test::makeMap(tsdfConfig());
  auto a = test::cpuBackend(whole, 1);
  auto b = test::cpuBackend(cut, 1);
  test::integrate(whole, *a, scene.rays);
  RayFilter segmented;
  segmented.segment_length_m = 0.35;
  test::integrate(cut, *b, scene.rays, segmented);
  std::size_t compared = 0;
  whole.store().forEachRegion([&](std::uint32_t slot, Vec3i region) {
    const auto* t = whole.store().layerData<rm_tsdf_voxel>(slot, whole.tsdfLayer());
    for (std::uint32_t i = 0; i < whole.store().voxelsPerRegion(); ++i) {
      const rm_tsdf_voxel other = cut.tsdf(whole.voxelAt(region, i));
      if (t[i].weight > 0.0f) {
        ++compared;
        // Each piece measures from its own end, which carries the distance still to go: the
        // same field up to float rounding.
        EXPECT_NEAR(t[i].distance, other.distance, 1e-4f);
        EXPECT_NEAR(t[i].weight, other.weight, 1e-3f);
      }
    }
  });
  EXPECT_GT(compared, 1000u);
}

// Voxblox fuses each ray's raw (untruncated) distance and truncates the average: side by side
// on the plane, both put the surface in the same place; but one ray passing well in front of a
// well-observed surface voxel drags it to +tau in Voxblox's rule, while raymap's moves it by
// tau / (W + 1).
TEST(TsdfMap, ComparedWithVoxbloxsRule) {
  const rm_tsdf_params p = tsdfConfig().tsdf.toKernel(kResolution);
  const auto voxblox = [&](rm_tsdf_voxel v, double sdf) {
    const double tau = static_cast<double>(p.truncation);
    const double eps = static_cast<double>(p.dropoff);
    double w = 1.0;
    if (eps > 0.0 && sdf < -eps) {
      w = std::max((tau + sdf) / (tau - eps), 0.0);
    }
    const double weight = static_cast<double>(v.weight);
    const double total = weight + w;
    const double d = (sdf * w + static_cast<double>(v.distance) * weight) / total;
    return rm_tsdf_voxel{static_cast<float>(std::clamp(d, -tau, tau)),
                         static_cast<float>(std::min(total, static_cast<double>(p.max_weight)))};
  };
  // Inside the band both rules are the same average.
  rm_tsdf_voxel ours{0.0f, 0.0f};
  rm_tsdf_voxel theirs{0.0f, 0.0f};
  for (const double sdf : {0.02, -0.05, 0.11, -0.29, 0.0, 0.2}) {
    rm_tsdf_update(&ours, static_cast<float>(sdf), p);
    theirs = voxblox(theirs, sdf);
    EXPECT_NEAR(ours.distance, theirs.distance, 1e-6f);
    EXPECT_NEAR(ours.weight, theirs.weight, 1e-6f);
  }
  // A surface voxel seen 100 times at 0.01 m, then one ray passing 40 m in front of it.
  rm_tsdf_voxel surface{0.01f, 100.0f};
  rm_tsdf_update(&surface, 40.0f, p);
  EXPECT_NEAR(surface.distance, (0.01f * 100.0f + 0.3f) / 101.0f, 1e-6f);
  EXPECT_NEAR(voxblox(rm_tsdf_voxel{0.01f, 100.0f}, 40.0).distance, 0.3f, 1e-6f);
}

}  // namespace
}  // namespace raymap
