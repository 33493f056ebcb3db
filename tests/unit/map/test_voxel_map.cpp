// SPDX-License-Identifier: BSD-3-Clause
// VoxelMap: configuration, memory footprint, global capacity and the rolling window.
#include <gtest/gtest.h>

#include "src/map/voxel_map.hpp"
#include "tests/support/test_rays.hpp"

namespace raymap {
namespace {

TEST(VoxelMapConfig, SchemaFollowsTheOptions) {
  MapConfig config;
  EXPECT_TRUE(config.schema().has(LayerKind::kOccupancy));
  EXPECT_TRUE(config.schema().has(LayerKind::kVoxelMean));
  EXPECT_FALSE(config.schema().has(LayerKind::kScanMark));
  config.semantics = Semantics::kPerScan;
  config.voxel_mean = false;
  EXPECT_TRUE(config.schema().has(LayerKind::kScanMark));
  EXPECT_FALSE(config.schema().has(LayerKind::kVoxelMean));
  config.device_scan_marks = false;  // a map for the CPU only
  EXPECT_FALSE(config.schema().has(LayerKind::kScanMark));
}

// A per-scan map the CPU integrates needs no scan-mark layer (the CPU's once-per-scan rule is a
// bit per voxel outside the map): without it the same budget holds more regions, and the map is
// the same, bit for bit, on one thread and on three.
TEST(VoxelMapConfig, PerScanMapsForTheCpuNeedNoScanMarks) {
  MapConfig with_marks = test::smallConfig(Semantics::kPerScan);
  with_marks.memory_budget_bytes = std::uint64_t{384} << 20;  // 8^3-voxel regions: 49,152 or 65,536
  MapConfig without = with_marks;
  without.device_scan_marks = false;
  // Occupancy 4 + mean 8 bytes a voxel, against 16 with the marks.
  EXPECT_EQ(without.capacityRegions() * 3, with_marks.capacityRegions() * 4);
  const std::vector<Ray> rays = test::randomScans(77, 4, 2000);
  for (const unsigned threads : {1u, 3u}) {
    VoxelMap a = test::makeMap(with_marks);
    VoxelMap b = test::makeMap(without);
    ASSERT_GE(a.scanMarkLayer(), 0);
    ASSERT_LT(b.scanMarkLayer(), 0);
    auto cpu_a = test::cpuBackend(a, threads);
    auto cpu_b = test::cpuBackend(b, threads);
    test::integrate(a, *cpu_a, rays);
    test::integrate(b, *cpu_b, rays);
    const test::MapComparison cmp = test::compareMaps(a, b);
    EXPECT_GT(cmp.compared, 10000u);
    EXPECT_EQ(cmp.exact_value, cmp.compared) << threads << " threads";
  }
}

TEST(VoxelMapConfig, BudgetSetsTheCapacity) {
  MapConfig config;  // 32^3 voxels x 12 bytes = 384 KiB per region
  config.memory_budget_bytes = 10u * 384u * 1024u + 1000u;
  EXPECT_EQ(config.capacityRegions(), 10u);
  const VoxelMap map = test::makeMap(config);
  EXPECT_EQ(map.store().capacity(), 10u);
  EXPECT_EQ(map.store().poolBytes(), 10u * 384u * 1024u);
}

TEST(VoxelMapConfig, BadValuesAreNamed) {
  MapConfig config;
  config.geometry.resolution = 0.0;
  auto bad = VoxelMap::create(config);
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("resolution"), std::string::npos);
  config = MapConfig();
  config.geometry.region_voxels = 300;
  bad = VoxelMap::create(config);
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("map.region_voxels"), std::string::npos);
  config = MapConfig();
  config.memory_budget_bytes = 1000;
  bad = VoxelMap::create(config);
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("holds no region"), std::string::npos);
}

TEST(VoxelMap, GlobalMapRefusesRegionsBeyondCapacity) {
  MapConfig config;
  config.geometry.region_voxels = 8;
  config.memory_budget_bytes = 2u * 8u * 8u * 8u * 12u;  // two regions
  VoxelMap map = test::makeMap(config);
  ASSERT_TRUE(map.acquireRegion({0, 0, 0}));
  ASSERT_TRUE(map.acquireRegion({1, 0, 0}));
  auto full = map.acquireRegion({2, 0, 0});
  ASSERT_FALSE(full);
  EXPECT_EQ(full.error(), StoreError::kFull);
}

class RollingWindow : public ::testing::Test {
 protected:
  static MapConfig config() {
    MapConfig c;
    c.geometry.resolution = 0.1;
    c.geometry.region_voxels = 8;  // 0.8 m regions
    c.policy = StorePolicy::kRolling;
    c.window_regions = {4, 4, 2};
    return c;
  }
  VoxelMap map_ = test::makeMap(config());
};

TEST_F(RollingWindow, PoolHoldsExactlyTheWindow) {
  EXPECT_EQ(map_.store().capacity(), 32u);
  map_.setWindowCentre({0.0, 0.0, 0.0});
  EXPECT_EQ(map_.windowMinRegion(), (Vec3i{-2, -2, -1}));
  EXPECT_EQ(map_.windowMaxRegion(), (Vec3i{1, 1, 0}));
  const auto [lo, hi] = map_.windowBounds();
  EXPECT_NEAR(lo.x, -1.6, 1e-12);
  EXPECT_NEAR(hi.z, 0.8, 1e-12);
  // The whole window can be created; nothing outside it.
  for (int x = -2; x <= 1; ++x) {
    for (int y = -2; y <= 1; ++y) {
      for (int z = -1; z <= 0; ++z) {
        ASSERT_TRUE(map_.acquireRegion({x, y, z}));
      }
    }
  }
  auto outside = map_.acquireRegion({2, 0, 0});
  ASSERT_FALSE(outside);
  EXPECT_EQ(outside.error(), StoreError::kOutsideWindow);
}

TEST_F(RollingWindow, MovingRecyclesLeavingRegionsWhichStartUnobserved) {
  map_.setWindowCentre({0.0, 0.0, 0.0});
  auto slot = map_.acquireRegion({-2, 0, 0});
  ASSERT_TRUE(slot);
  const std::uint32_t first_slot = *slot;
  map_.store().layerData<float>(first_slot, map_.occupancyLayer())[0] = 2.0f;
  const Vec3i voxel{-16, 0, 0};  // voxel 0 of region (-2, 0, 0)
  EXPECT_EQ(map_.state(voxel), VoxelState::kOccupied);
  // Move 1.6 m along +x: regions x = -2 and -1 leave, x = 2 and 3 enter.
  const std::uint32_t recycled = map_.setWindowCentre({1.6, 0.0, 0.0});
  EXPECT_EQ(recycled, 1u);  // only one region was stored
  EXPECT_EQ(map_.windowMinRegion(), (Vec3i{0, -2, -1}));
  EXPECT_EQ(map_.state(voxel), VoxelState::kUnobserved);
  EXPECT_EQ(map_.store().size(), 0u);
  // The recycled slot serves a region that entered; its voxels start unobserved.
  auto entered = map_.acquireRegion({3, 1, 0});
  ASSERT_TRUE(entered);
  EXPECT_EQ(*entered, first_slot);
  EXPECT_EQ(map_.state({24, 8, 0}), VoxelState::kUnobserved);
}

TEST_F(RollingWindow, SmallMovesKeepTheWindow) {
  map_.setWindowCentre({0.0, 0.0, 0.0});
  ASSERT_TRUE(map_.acquireRegion({0, 0, 0}));
  EXPECT_EQ(map_.setWindowCentre({0.3, -0.3, 0.2}), 0u);
  EXPECT_EQ(map_.windowMinRegion(), (Vec3i{-2, -2, -1}));
  EXPECT_EQ(map_.store().size(), 1u);
}

TEST(VoxelMap, ScanSequenceWrapsSafely) {
  MapConfig config;
  config.semantics = Semantics::kPerScan;
  config.geometry.region_voxels = 8;
  config.memory_budget_bytes = 1u << 20;
  VoxelMap map = test::makeMap(config);
  EXPECT_EQ(map.beginScan(), 1u);
  EXPECT_EQ(map.beginScan(), 2u);
}

}  // namespace
}  // namespace raymap
