// SPDX-License-Identifier: BSD-3-Clause
// raymap::Mapper with a rolling window (MapOptions::window, issue 55): the map raymapd keeps.
// Memory is the window; what leaves it is forgotten; rays outside it are counted, not integrated;
// options that do not fit are refused naming map.window.
#include <cstdint>
#include <string>
#include <vector>

#include "raymap/mapper.hpp"
#include <gtest/gtest.h>

namespace raymap {
namespace {

/// 4 x 4 x 2 regions of 8 voxels at 0.1 m: a window 3.2 m x 3.2 m x 1.6 m.
MapperConfig windowed() {
  MapperConfig c;
  c.map.resolution = 0.1;
  c.map.region_voxels = 8;
  c.map.window = Eigen::Vector3i(4, 4, 2);
  return c;
}

/// Rays from `origin` to a wall 1 m ahead along +x, spread over 0.4 m in y.
std::vector<WorldRay> wallAhead(const Eigen::Vector3d& origin) {
  std::vector<WorldRay> rays;
  for (int i = 0; i < 40; ++i) {
    WorldRay r;
    r.origin = origin;
    r.end = origin + Eigen::Vector3d(1.02, -0.2 + 0.01 * i, 0.02);
    rays.push_back(r);
  }
  return rays;
}

TEST(MapperWindow, TheWindowFollowsTheRobotAndForgetsWhatItLeaves) {
  auto mapper = Mapper::create(windowed());
  ASSERT_TRUE(mapper) << mapper.error().message;
  ASSERT_EQ(mapper->moveWindow(Eigen::Vector3d(0.0, 0.0, 0.0)).value_or(99), 0u);
  ASSERT_TRUE(mapper->integrate(wallAhead(Eigen::Vector3d(0.0, 0.0, 0.25))));
  ASSERT_TRUE(mapper->flush());
  const Eigen::Vector3d wall(1.05, 0.05, 0.25);
  EXPECT_EQ(mapper->occupancy(wall), VoxelState::kOccupied);
  // 10 m away, beyond the window: counted, not integrated.
  ASSERT_TRUE(mapper->integrate(wallAhead(Eigen::Vector3d(10.0, 0.0, 0.25))));
  ASSERT_TRUE(mapper->flush());
  EXPECT_EQ(mapper->counters().rays_out_of_bounds, 40u);
  EXPECT_EQ(mapper->occupancy(Eigen::Vector3d(11.05, 0.05, 0.25)), VoxelState::kUnobserved);

  auto recycled = mapper->moveWindow(Eigen::Vector3d(10.0, 0.0, 0.0));
  ASSERT_TRUE(recycled) << recycled.error().message;
  EXPECT_GT(*recycled, 0u);
  EXPECT_EQ(mapper->occupancy(wall), VoxelState::kUnobserved);  // forgotten with its region
  ASSERT_TRUE(mapper->integrate(wallAhead(Eigen::Vector3d(10.0, 0.0, 0.25))));
  ASSERT_TRUE(mapper->flush());
  EXPECT_EQ(mapper->occupancy(Eigen::Vector3d(11.05, 0.05, 0.25)), VoxelState::kOccupied);
  EXPECT_LE(mapper->counts().regions, 4u * 4u * 2u);
  EXPECT_EQ(mapper->mapOptions().window, Eigen::Vector3i(4, 4, 2));
}

TEST(MapperWindow, RaysWaitingInTheBatchGoInBeforeTheWindowMoves) {
  MapperConfig config = windowed();
  config.backend.batch_rays = 1 << 16;  // the scan stays in the batch until something flushes
  auto mapper = Mapper::create(config);
  ASSERT_TRUE(mapper) << mapper.error().message;
  ASSERT_TRUE(mapper->integrate(wallAhead(Eigen::Vector3d(0.0, 0.0, 0.25))));
  ASSERT_GT(mapper->counters().rays_pending, 0u);

  ASSERT_TRUE(mapper->moveWindow(Eigen::Vector3d(0.4, 0.0, 0.0)));

  EXPECT_EQ(mapper->counters().rays_pending, 0u);
  EXPECT_EQ(mapper->counters().rays_integrated, 40u);
  EXPECT_EQ(mapper->occupancy(Eigen::Vector3d(1.05, 0.05, 0.25)), VoxelState::kOccupied);
}

TEST(MapperWindow, AMapWithoutAWindowDoesNotMoveAndBadWindowsAreRefused) {
  auto global = Mapper::create(MapperConfig{});
  ASSERT_TRUE(global) << global.error().message;
  EXPECT_EQ(global->moveWindow(Eigen::Vector3d(5.0, 0.0, 0.0)).value_or(99), 0u);

  MapperConfig empty_axis = windowed();
  empty_axis.map.window = Eigen::Vector3i(4, 0, 2);
  MapperConfig tiered = windowed();
  tiered.map.tiers.enabled = true;
  auto a = Mapper::create(empty_axis);
  auto b = Mapper::create(tiered);

  ASSERT_FALSE(a);
  ASSERT_FALSE(b);
  EXPECT_NE(a.error().message.find("map.window must be 1 to 4096"), std::string::npos)
      << a.error().message;
  EXPECT_NE(b.error().message.find("map.window"), std::string::npos) << b.error().message;
  EXPECT_NE(b.error().message.find("map.tiers.enabled"), std::string::npos) << b.error().message;
}

}  // namespace
}  // namespace raymap
