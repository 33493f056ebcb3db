// SPDX-License-Identifier: BSD-3-Clause
// Ray preparation: rejection counters, clipping, no-return rays, segmentation, reverse walks.
#include <cmath>
#include <limits>
#include <vector>

#include <gtest/gtest.h>

#include "src/map/ray_preparer.hpp"
#include "tests/support/test_rays.hpp"

namespace raymap {
namespace {

using test::makeRay;

class Preparer : public ::testing::Test {
 protected:
  static MapConfig config() {
    MapConfig c;
    c.memory_budget_bytes = 16u << 20;
    return c;
  }
  std::vector<PreparedRay> run(const std::vector<Ray>& rays, const RayFilter& filter,
                               RayCounters* counters = nullptr) {
    RayPreparer preparer(map_, filter);
    std::vector<PreparedRay> out(rays.size() * RayFilter::kMaxPiecesPerRay + 8);
    const auto p = preparer.prepare(rays, out);
    EXPECT_EQ(p.consumed, rays.size());
    out.resize(p.written);
    if (counters != nullptr) {
      *counters = preparer.counters();
    }
    return out;
  }
  VoxelMap map_ = test::makeMap(config());
};

TEST_F(Preparer, InvalidRaysAreCountedNotFatal) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  const std::vector<Ray> rays = {makeRay({0, 0, 0}, {1, 0, 0}), makeRay({nan, 0, 0}, {1, 0, 0}),
                                 makeRay({0, 0, 0}, {1, inf, 0}), makeRay({0, 0, 0}, {0, 2, 0})};
  RayCounters c;
  const auto out = run(rays, {}, &c);
  EXPECT_EQ(out.size(), 2u);
  EXPECT_EQ(c.rays_in, 4u);
  EXPECT_EQ(c.rays_invalid, 2u);
  EXPECT_EQ(c.rays_accepted, 2u);
  EXPECT_EQ(c.rejected(), 2u);
}

TEST_F(Preparer, ShortRaysAreDropped) {
  RayFilter f;
  f.min_range_m = 0.5;
  RayCounters c;
  const auto out = run({makeRay({0, 0, 0}, {0.3, 0, 0}), makeRay({0, 0, 0}, {0.6, 0, 0})}, f, &c);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(c.rays_too_short, 1u);
  EXPECT_EQ(out[0].sample_voxel.x, 6);
}

TEST_F(Preparer, LongRaysAreClippedAndGiveNoHit) {
  RayFilter f;
  f.max_range_m = 2.0;
  RayCounters c;
  const auto out = run({makeRay({0.05, 0.05, 0.05}, {10.05, 0.05, 0.05})}, f, &c);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(c.rays_clipped, 1u);
  EXPECT_EQ(out[0].flags & RM_RAY_END_HIT, 0u);
  EXPECT_EQ(out[0].sample_voxel.x, 20);  // 2.05 m
  EXPECT_NEAR(out[0].sample_local.x, 0.5f, 1e-5f);
}

TEST_F(Preparer, NoReturnRaysClearWithoutHit) {
  RayCounters c;
  const auto out = run({makeRay({0, 0, 0}, {3, 0, 0}, kRayNoReturn)}, {}, &c);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(c.rays_no_return, 1u);
  EXPECT_EQ(out[0].flags & RM_RAY_END_HIT, 0u);
}

TEST_F(Preparer, KeysAreExactFarFromTheOrigin) {
  const auto out = run({makeRay({-3000.05, 7000.0, 2.0}, {-2990.0, 7000.25, 2.0})}, {});
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].origin_voxel.x, -30001);
  EXPECT_EQ(out[0].origin_voxel.y, 70000);
  EXPECT_NEAR(out[0].origin_local.x, 0.5f, 1e-4f);
  EXPECT_EQ(out[0].sample_voxel.x, -29900);
  EXPECT_NEAR(out[0].sample_local.y, 0.5f, 1e-4f);
}

TEST_F(Preparer, RaysBeyondTheKeyRangeAreRejected) {
  RayCounters c;
  const auto out = run({makeRay({0, 0, 0}, {1e8, 0, 0})}, {}, &c);
  EXPECT_TRUE(out.empty());
  EXPECT_EQ(c.rays_out_of_bounds, 1u);
}

TEST_F(Preparer, ShortRaysAreKeptUpToTheKeyRangeOnEveryAxisAndSide) {
  // Short rays (not rejected by their length) just inside and just outside the map's key range
  // (VoxelMap::maxVoxelCoord voxels from the origin, exclusive), on each axis, both sides.
  const double resolution = map_.geometry().resolution;
  const std::int32_t limit = map_.maxVoxelCoord();
  const double inside = (limit - 1.5) * resolution;   // in voxel limit - 2 (or 1 - limit)
  const double outside = (limit + 0.5) * resolution;  // in voxel limit (or -limit - 1)
  for (int axis = 0; axis < 3; ++axis) {
    for (double side : {1.0, -1.0}) {
      Vec3d near_origin{0.05, 0.05, 0.05};
      Vec3d far_origin = near_origin;
      near_origin[axis] = side * inside;
      far_origin[axis] = side * outside;
      Vec3d near_sample = near_origin;
      Vec3d far_sample = far_origin;
      near_sample[(axis + 1) % 3] += 0.5;
      far_sample[(axis + 1) % 3] += 0.5;
      RayCounters c;
      const auto out =
          run({makeRay(near_origin, near_sample), makeRay(far_origin, far_sample)}, {}, &c);
      ASSERT_EQ(out.size(), 1u) << "axis " << axis << " side " << side;
      EXPECT_EQ(c.rays_out_of_bounds, 1u);
      const rm_vec3i kept = out[0].origin_voxel;
      EXPECT_EQ(axis == 0 ? kept.x : (axis == 1 ? kept.y : kept.z),
                side > 0 ? limit - 2 : 1 - limit);
    }
  }
}

TEST_F(Preparer, SegmentsJoinAndOnlyTheLastOneHits) {
  RayFilter f;
  f.segment_length_m = 1.0;
  RayCounters c;
  const auto out = run({makeRay({0.05, 0.05, 0.05}, {3.55, 0.05, 0.05})}, f, &c);
  ASSERT_EQ(out.size(), 4u);  // 3.5 m in equal pieces of at most 1 m
  EXPECT_EQ(c.pieces_out, 4u);
  EXPECT_EQ(c.rays_accepted, 1u);
  for (std::size_t i = 0; i + 1 < out.size(); ++i) {
    EXPECT_EQ(out[i].flags & RM_RAY_END_HIT, 0u) << "piece " << i;
    EXPECT_EQ(out[i].sample_voxel.x, out[i + 1].origin_voxel.x);
    EXPECT_FLOAT_EQ(out[i].sample_local.x, out[i + 1].origin_local.x);
  }
  EXPECT_EQ(out.back().flags & RM_RAY_END_HIT, RM_RAY_END_HIT);
  EXPECT_EQ(out.back().sample_voxel.x, 35);
}

TEST_F(Preparer, ReverseFlagsEveryPiece) {
  RayFilter f;
  f.reverse = true;
  f.segment_length_m = 1.0;
  const auto out = run({makeRay({0, 0, 0}, {2.5, 0, 0})}, f);
  ASSERT_EQ(out.size(), 3u);
  for (const PreparedRay& r : out) {
    EXPECT_NE(r.flags & RM_RAY_REVERSE, 0u);
  }
}

TEST_F(Preparer, StopsWhenTheOutputIsFullAndResumes) {
  RayPreparer preparer(map_, {});
  const std::vector<Ray> rays(5, makeRay({0, 0, 0}, {1, 1, 1}));
  std::vector<PreparedRay> out(3);
  auto p = preparer.prepare(rays, out);
  EXPECT_EQ(p.consumed, 3u);
  EXPECT_EQ(p.written, 3u);
  p = preparer.prepare(std::span<const Ray>(rays).subspan(3), out);
  EXPECT_EQ(p.consumed, 2u);
  EXPECT_EQ(preparer.counters().rays_in, 5u);
}

TEST(PreparerRolling, RaysAreClippedToTheWindow) {
  MapConfig c;
  c.geometry.region_voxels = 8;  // 0.8 m regions
  c.policy = StorePolicy::kRolling;
  c.window_regions = {4, 4, 4};  // 3.2 m cube
  VoxelMap map = test::makeMap(c);
  map.setWindowCentre({0, 0, 0});  // window [-1.6, 1.6)^3
  RayPreparer preparer(map, {});
  const std::vector<Ray> rays = {makeRay({0, 0, 0}, {5, 0, 0}), makeRay({0, 0, 0}, {1, 0, 0}),
                                 makeRay({10, 10, 10}, {11, 10, 10}),
                                 makeRay({-5, 0.05, 0.05}, {0.05, 0.05, 0.05})};
  std::vector<PreparedRay> out(8);
  const auto p = preparer.prepare(rays, out);
  ASSERT_EQ(p.written, 3u);
  EXPECT_EQ(preparer.counters().rays_outside_window, 1u);
  EXPECT_EQ(preparer.counters().rays_clipped, 2u);
  EXPECT_EQ(out[0].sample_voxel.x, 16);  // first voxel outside the window: left out
  EXPECT_EQ(out[0].flags & RM_RAY_END_HIT, 0u);
  EXPECT_EQ(out[1].flags & RM_RAY_END_HIT, RM_RAY_END_HIT);
  EXPECT_EQ(out[2].origin_voxel.x, -17);  // origin moved half a voxel outside the window face
  EXPECT_EQ(out[2].flags & RM_RAY_END_HIT, RM_RAY_END_HIT);
}

// TSDF maps (truncation 0.3 m): a ray with a return is walked on 0.3 m past its sample and takes
// no hit; each prepared ray carries its signed distance at its end: -tau, the distance still to
// go for a piece or a window-clipped ray, or RM_TSDF_FREE for rays that only clear.
TEST(PreparerTsdf, RaysGoOnPastTheirSampleAndCarryTheDistanceAtTheirEnd) {
  MapConfig c = test::smallConfig(Semantics::kPerRay).forTsdf();
  c.tsdf.truncation_m = 0.3;
  VoxelMap map = test::makeMap(c);
  RayFilter filter;
  filter.max_range_m = 5.0;
  filter.segment_length_m = 1.0;
  RayPreparer preparer(map, filter);
  const std::vector<Ray> rays = {makeRay({0.05, 0.05, 0.05}, {1.55, 0.05, 0.05}),
                                 makeRay({0.05, 0.05, 0.05}, {0.05, 0.75, 0.05}, kRayNoReturn),
                                 makeRay({0.05, 0.05, 0.05}, {0.05, 0.05, 9.05})};
  std::vector<PreparedRay> out(16);
  const auto p = preparer.prepare(rays, out);
  // 1.8 m in 2 pieces, 0.7 m in 1, 5 m (clipped) in 5.
  ASSERT_EQ(p.written, 8u);
  EXPECT_EQ(out[1].sample_voxel.x, 18);  // 1.55 + 0.3 = 1.85 m
  EXPECT_NEAR(out[1].tsdf_end_m, -0.3f, 1e-6f);
  EXPECT_NEAR(out[0].tsdf_end_m, 0.9f - 0.3f, 1e-6f);  // the first piece ends 0.9 m before
  for (const PreparedRay& ray : out) {
    EXPECT_EQ(ray.flags & RM_RAY_END_HIT, 0u);
  }
  EXPECT_EQ(out[2].sample_voxel.y, 7);  // no return: not extended
  EXPECT_GE(out[2].tsdf_end_m, 1e29f);
  EXPECT_EQ(out[7].sample_voxel.z, 50);  // clipped at 5 m: not extended, clears only
  EXPECT_GE(out[7].tsdf_end_m, 1e29f);
}

TEST(RayFilterValidation, NamesTheOption) {
  RayFilter f;
  f.min_range_m = -1.0;
  ASSERT_FALSE(f.validate());
  // By configuration key (MapperConfig::rays.min_range); raymap shows it as --min-range.
  EXPECT_NE(f.validate().error().message.find("rays.min_range"), std::string::npos);
  f = RayFilter();
  f.min_range_m = 5.0;
  f.max_range_m = 2.0;
  ASSERT_FALSE(f.validate());
  EXPECT_EQ(f.validate().error().message, "rays.max_range must be larger than rays.min_range");
}

}  // namespace
}  // namespace raymap
