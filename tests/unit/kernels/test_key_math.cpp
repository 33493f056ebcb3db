// SPDX-License-Identifier: BSD-3-Clause
// Keys and quantisation: voxels, regions, local indices.
#include <random>

#include <gtest/gtest.h>

#include "kernels/common/key_math.h"
#include "src/map/voxel_map.hpp"
#include "tests/support/test_rays.hpp"

namespace raymap {
namespace {

TEST(KeyMath, FloorDivisionRoundsDown) {
  EXPECT_EQ(rm_floor_div(0, 32), 0);
  EXPECT_EQ(rm_floor_div(31, 32), 0);
  EXPECT_EQ(rm_floor_div(32, 32), 1);
  EXPECT_EQ(rm_floor_div(-1, 32), -1);
  EXPECT_EQ(rm_floor_div(-32, 32), -1);
  EXPECT_EQ(rm_floor_div(-33, 32), -2);
  EXPECT_EQ(rm_floor_div(-33, 7), -5);
}

TEST(KeyMath, RegionAndLocalRebuildTheVoxel) {
  std::mt19937 rng(5489);
  std::uniform_int_distribution<int> coord(-100000, 100000);
  for (int n : {4, 7, 8, 32, 128}) {
    for (int i = 0; i < 20000; ++i) {
      const rm_vec3i v{coord(rng), coord(rng), coord(rng)};
      const rm_vec3i r = rm_region_of_voxel(v, n);
      const rm_vec3i l = rm_local_of_voxel(v, n);
      ASSERT_GE(l.x, 0);
      ASSERT_LT(l.x, n);
      ASSERT_GE(l.y, 0);
      ASSERT_LT(l.y, n);
      ASSERT_GE(l.z, 0);
      ASSERT_LT(l.z, n);
      EXPECT_EQ(r.x * n + l.x, v.x);
      EXPECT_EQ(r.y * n + l.y, v.y);
      EXPECT_EQ(r.z * n + l.z, v.z);
    }
  }
}

TEST(KeyMath, LocalIndexIsXFastestAndDense) {
  const int n = 5;
  std::vector<int> seen(n * n * n, 0);
  for (int z = 0; z < n; ++z) {
    for (int y = 0; y < n; ++y) {
      for (int x = 0; x < n; ++x) {
        const rm_u32 i = rm_local_index(rm_vec3i{x, y, z}, n);
        ASSERT_LT(i, static_cast<rm_u32>(n * n * n));
        ++seen[i];
        EXPECT_EQ(i, static_cast<rm_u32>(x + n * (y + n * z)));
      }
    }
  }
  for (int s : seen) {
    EXPECT_EQ(s, 1);
  }
}

TEST(Keys, VoxelFacesLieOnMultiplesOfTheResolution) {
  MapConfig config;
  config.memory_budget_bytes = 16u << 20;
  const VoxelMap map = test::makeMap(config);
  EXPECT_EQ(map.voxelOf({0.0, 0.0, 0.0}), (Vec3i{0, 0, 0}));
  EXPECT_EQ(map.voxelOf({0.0999, -0.0001, 0.1}), (Vec3i{0, -1, 1}));
  // 0.3 m is a voxel face at 0.1 m: it belongs to voxel 3, as in OctoMap (p * (1/res)).
  EXPECT_EQ(map.voxelOf({0.3, -0.3, 0.7}), (Vec3i{3, -3, 7}));
  EXPECT_EQ(map.voxelOf({-1000.05, 2500.0, 12.34}), (Vec3i{-10001, 25000, 123}));
  const Vec3d c = map.voxelCentre({-3, 0, 7});
  EXPECT_NEAR(c.x, -0.25, 1e-12);
  EXPECT_NEAR(c.y, 0.05, 1e-12);
  EXPECT_NEAR(c.z, 0.75, 1e-12);
  EXPECT_EQ(map.regionOfVoxel({-1, 31, 32}), (Vec3i{-1, 0, 1}));
}

TEST(Keys, RangeLimitRejectsUnindexableCoordinates) {
  MapConfig config;
  config.memory_budget_bytes = 16u << 20;
  const VoxelMap map = test::makeMap(config);
  EXPECT_TRUE(map.voxelInRange({1.0e5, -1.0e5, 0.0}));       // 100 km
  EXPECT_FALSE(map.voxelInRange({1.0e7, 0.0, 0.0}));         // beyond the 21-bit region index
  EXPECT_FALSE(map.voxelInRange({0.0, std::nan(""), 0.0}));  // NaN is never in range
}

}  // namespace
}  // namespace raymap
