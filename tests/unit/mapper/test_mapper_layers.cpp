// SPDX-License-Identifier: BSD-3-Clause
// raymap::Mapper::voxel() reports the NDT, TSDF and decay-rate layers in metres: each checked
// against values computed here from the rays the test gives.
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "raymap/mapper.hpp"
#include <gtest/gtest.h>

namespace raymap {
namespace {

MapperConfig layerMapper(MapMode mode) {
  MapperConfig config;
  config.map.mode = mode;
  config.map.region_voxels = 8;
  config.map.max_memory_bytes = std::uint64_t{256} << 20;
  config.backend.threads = 1;
  return config;
}

/// Rays from the sensor at (0.05, 0.05, 0.05) along +x to `count` returns scattered inside the
/// voxel (40, 0, 0), [4.0, 4.1) x [0, 0.1) x [0, 0.1) m, with intensities 10, 11, ...
std::vector<WorldRay> raysIntoOneVoxel(int count) {
  std::vector<WorldRay> rays;
  for (int i = 0; i < count; ++i) {
    WorldRay r;
    r.origin = Eigen::Vector3d(0.05, 0.05, 0.05);
    r.end =
        Eigen::Vector3d(4.01 + 0.08 * ((i * 37) % 101) / 100.0,
                        0.01 + 0.08 * ((i * 53) % 97) / 96.0, 0.03 + 0.04 * ((i * 29) % 89) / 88.0);
    r.intensity = 10.0f + static_cast<float>(i);
    rays.push_back(r);
  }
  return rays;
}

TEST(MapperLayers, AnNdtVoxelIsItsSamplesMeanAndCovarianceInMetres) {
  for (const MapMode mode : {MapMode::kNdtOm, MapMode::kNdtTm}) {
    auto mapper = Mapper::create(layerMapper(mode));
    ASSERT_TRUE(mapper) << mapper.error().message;
    const std::vector<WorldRay> rays = raysIntoOneVoxel(60);
    ASSERT_TRUE(mapper->integrate(std::span<const WorldRay>(rays)));
    ASSERT_TRUE(mapper->flush());
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const WorldRay& r : rays) {
      mean += r.end;
    }
    mean /= static_cast<double>(rays.size());
    Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
    for (const WorldRay& r : rays) {
      covariance += (r.end - mean) * (r.end - mean).transpose();
    }
    covariance /= static_cast<double>(rays.size());

    const VoxelInfo info = mapper->voxel(VoxelKey(40, 0, 0));
    ASSERT_TRUE(info.ndt.has_value());
    EXPECT_EQ(info.ndt->samples, rays.size());
    // The layer keeps floats in voxel units: a few parts in 10^6 of a 0.1 m voxel.
    EXPECT_LT((info.ndt->mean - mean).norm(), 1e-6);
    EXPECT_LT((info.ndt->covariance - covariance).cwiseAbs().maxCoeff(), 1e-8)
        << info.ndt->covariance << "\nexpected\n"
        << covariance;
    EXPECT_TRUE(info.ndt->covariance.isApprox(info.ndt->covariance.transpose()));
    EXPECT_FALSE(info.tsdf || info.decay);
    if (mode == MapMode::kNdtTm) {
      ASSERT_TRUE(info.ndt->hits && info.ndt->misses && info.ndt->intensity_mean);
      // Every return lies in one compact cluster: nearly all fall on the surfel, and a ray that
      // ends in the voxel is never a pass-through.
      EXPECT_LE(*info.ndt->hits, rays.size());
      EXPECT_GE(*info.ndt->hits, rays.size() - 6);
      EXPECT_EQ(*info.ndt->misses, 0u);
      EXPECT_NEAR(*info.ndt->intensity_mean, 10.0 + 59.0 / 2.0, 1e-3);  // mean of 10 ... 69
    } else {
      EXPECT_FALSE(info.ndt->hits || info.ndt->intensity_mean);
    }
    // A voxel the rays crossed holds no Gaussian (no sample fell in it).
    EXPECT_FALSE(mapper->voxel(VoxelKey(20, 0, 0)).ndt);
  }
}

TEST(MapperLayers, ATsdfVoxelHasItsSignedDistanceToTheWall) {
  auto mapper = Mapper::create(layerMapper(MapMode::kTsdf));
  ASSERT_TRUE(mapper) << mapper.error().message;
  // A wall at x = 4.05 m (the middle of voxel column 40) seen head-on from x = 0.05.
  std::vector<WorldRay> rays;
  for (int j = -5; j <= 5; ++j) {
    for (int k = -5; k <= 5; ++k) {
      WorldRay r;
      r.origin = Eigen::Vector3d(0.05, 0.05, 0.05);
      r.end = Eigen::Vector3d(4.05, 0.05 + 0.02 * j, 0.05 + 0.02 * k);
      rays.push_back(r);
    }
  }
  ASSERT_TRUE(mapper->integrate(std::span<const WorldRay>(rays)));
  ASSERT_TRUE(mapper->flush());
  const double truncation = 0.3;  // 3 voxel edges by default
  const auto distance_at = [&](int x) {
    const VoxelInfo info = mapper->voxel(VoxelKey(x, 0, 0));
    EXPECT_TRUE(info.tsdf.has_value()) << "voxel " << x;
    EXPECT_FALSE(info.ndt || info.decay);
    EXPECT_EQ(info.state, VoxelState::kUnobserved);  // a TSDF map has no occupancy
    return info.tsdf ? static_cast<double>(info.tsdf->distance_m) : 0.0;
  };
  // Voxel centres 0.1 m and 0.2 m in front of the wall, on it, and 0.1 m behind it.
  EXPECT_NEAR(distance_at(39), 0.1, 0.02);
  EXPECT_NEAR(distance_at(38), 0.2, 0.02);
  EXPECT_NEAR(distance_at(40), 0.0, 0.02);
  EXPECT_NEAR(distance_at(41), -0.1, 0.02);
  const VoxelInfo far = mapper->voxel(VoxelKey(10, 0, 0));
  ASSERT_TRUE(far.tsdf.has_value());
  EXPECT_FLOAT_EQ(far.tsdf->distance_m, static_cast<float>(truncation));  // truncated
  EXPECT_GT(far.tsdf->weight, 0.0f);
  EXPECT_FALSE(mapper->voxel(VoxelKey(60, 0, 0)).tsdf);   // beyond the reach behind the wall
  EXPECT_FALSE(mapper->voxel(VoxelKey(20, 30, 0)).tsdf);  // no ray near
}

TEST(MapperLayers, ADecayVoxelHasItsPathLengthSamplesAndRate) {
  MapperConfig config = layerMapper(MapMode::kOccupancy);
  config.map.decay_rate = true;
  config.map.occupancy = false;
  auto mapper = Mapper::create(config);
  ASSERT_TRUE(mapper) << mapper.error().message;
  // Ten rays along the voxel row's axis: each crosses voxel 20 whole (0.1 m of path) and ends in
  // voxel 40 at x = 4.05 (0.05 m of path inside it).
  std::vector<WorldRay> rays(10);
  for (WorldRay& r : rays) {
    r.origin = Eigen::Vector3d(0.05, 0.05, 0.05);
    r.end = Eigen::Vector3d(4.05, 0.05, 0.05);
  }
  ASSERT_TRUE(mapper->integrate(std::span<const WorldRay>(rays)));
  ASSERT_TRUE(mapper->flush());
  const VoxelInfo crossed = mapper->voxel(VoxelKey(20, 0, 0));
  ASSERT_TRUE(crossed.decay.has_value());
  EXPECT_NEAR(crossed.decay->traversal_m, 1.0, 1e-4);
  EXPECT_EQ(crossed.decay->samples, 0u);
  EXPECT_EQ(crossed.decay->rate_per_m, 0.0f);
  const VoxelInfo hit = mapper->voxel(VoxelKey(40, 0, 0));
  ASSERT_TRUE(hit.decay.has_value());
  EXPECT_NEAR(hit.decay->traversal_m, 0.5, 1e-4);
  EXPECT_EQ(hit.decay->samples, 10u);
  EXPECT_NEAR(hit.decay->rate_per_m, 20.0, 1e-2);         // 10 samples over 0.5 m
  EXPECT_FALSE(mapper->voxel(VoxelKey(20, 5, 0)).decay);  // no ray entered: rate unknown
  EXPECT_FALSE(hit.ndt || hit.tsdf);
}

TEST(MapperLayers, AnOccupancyMapReportsNoOtherLayer) {
  auto mapper = Mapper::create(layerMapper(MapMode::kOccupancy));
  ASSERT_TRUE(mapper);
  const std::vector<WorldRay> rays = raysIntoOneVoxel(5);
  ASSERT_TRUE(mapper->integrate(std::span<const WorldRay>(rays)));
  ASSERT_TRUE(mapper->flush());
  const VoxelInfo info = mapper->voxel(VoxelKey(40, 0, 0));
  EXPECT_EQ(info.state, VoxelState::kOccupied);
  EXPECT_FALSE(info.ndt || info.tsdf || info.decay);
}

}  // namespace
}  // namespace raymap
