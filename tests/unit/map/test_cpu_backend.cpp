// SPDX-License-Identifier: BSD-3-Clause
// CPU backend: exact expectations on constructed scenes for both semantics, single- versus
// multi-threaded identity, store capacity, clipping and no-return rays.
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "src/map/cpu_backend.hpp"
#include "tests/support/test_rays.hpp"

namespace raymap {
namespace {

using test::makeRay;

struct RoomCase {
  Semantics semantics;
  unsigned threads;
  bool reverse;
  std::int32_t region_voxels;
  double segment_length;
};

std::string caseName(const ::testing::TestParamInfo<RoomCase>& info) {
  const RoomCase& c = info.param;
  return std::string(toString(c.semantics)) + "_t" + std::to_string(c.threads) +
         (c.reverse ? "_reverse" : "_forward") + "_n" + std::to_string(c.region_voxels) +
         (c.segment_length > 0 ? "_segmented" : "");
}

class ClosedRoom : public ::testing::TestWithParam<RoomCase> {};

TEST_P(ClosedRoom, WallsOccupiedInteriorFreeOutsideUnobserved) {
  const RoomCase& rc = GetParam();
  constexpr int kHalf = 20;
  constexpr double kRes = 0.1;
  VoxelMap map = test::makeMap(test::smallConfig(rc.semantics, rc.region_voxels));
  auto backend = test::cpuBackend(map, rc.threads);
  std::vector<Ray> rays = test::cubeRoomRays(kRes, kHalf);
  RayFilter filter;
  filter.reverse = rc.reverse;
  filter.segment_length_m = rc.segment_length;
  const RayCounters counters = test::integrate(map, *backend, rays, filter);
  EXPECT_EQ(counters.rays_accepted, rays.size());

  std::uint64_t occupied = 0;
  std::uint64_t free_interior = 0;
  for (int x = -kHalf - 2; x <= kHalf + 2; ++x) {
    for (int y = -kHalf - 2; y <= kHalf + 2; ++y) {
      for (int z = -kHalf - 2; z <= kHalf + 2; ++z) {
        const int ax = std::abs(x) == kHalf;
        const int ay = std::abs(y) == kHalf;
        const int az = std::abs(z) == kHalf;
        const bool inside = std::abs(x) < kHalf && std::abs(y) < kHalf && std::abs(z) < kHalf;
        const bool wall = ax + ay + az == 1 && std::abs(x) <= kHalf && std::abs(y) <= kHalf &&
                          std::abs(z) <= kHalf;
        const VoxelState s = map.state({x, y, z});
        if (wall) {
          ASSERT_EQ(s, VoxelState::kOccupied) << x << "," << y << "," << z;
          ++occupied;
          const rm_voxel_mean m = map.mean({x, y, z});
          ASSERT_EQ(m.count, 1u);
          const rm_vec3f mean = rm_mean_decode(m.packed, m.count);
          EXPECT_NEAR(mean.x, 0.5f, 1e-3f);
        } else if (inside) {
          ASSERT_NE(s, VoxelState::kOccupied) << x << "," << y << "," << z;
          free_interior += s == VoxelState::kFree ? 1u : 0u;
        } else {
          ASSERT_EQ(s, VoxelState::kUnobserved) << x << "," << y << "," << z;
        }
      }
    }
  }
  EXPECT_EQ(occupied, rays.size());
  EXPECT_EQ(map.state({0, 0, 0}), VoxelState::kFree);
  EXPECT_GT(free_interior, 20000u);
  const MapSummary summary = map.summarise();
  EXPECT_EQ(summary.voxels_occupied, occupied);
  EXPECT_EQ(summary.voxels_free, free_interior);
  // Per-ray: the sensor voxel saw every ray; per-scan: once.
  const float sensor = map.occupancyValue({0, 0, 0});
  const OccupancyParams p;
  if (rc.semantics == Semantics::kPerScan) {
    EXPECT_FLOAT_EQ(sensor, p.miss);
  } else {
    EXPECT_FLOAT_EQ(sensor, p.clamp_min);
  }
}

INSTANTIATE_TEST_SUITE_P(Cases, ClosedRoom,
                         ::testing::Values(RoomCase{Semantics::kPerRay, 1, false, 8, 0.0},
                                           RoomCase{Semantics::kPerRay, 1, true, 8, 0.0},
                                           RoomCase{Semantics::kPerRay, 2, false, 8, 0.0},
                                           RoomCase{Semantics::kPerRay, 3, true, 32, 0.0},
                                           RoomCase{Semantics::kPerRay, 1, false, 32, 0.7},
                                           RoomCase{Semantics::kPerScan, 1, false, 8, 0.0},
                                           RoomCase{Semantics::kPerScan, 1, true, 32, 0.0},
                                           RoomCase{Semantics::kPerScan, 2, false, 8, 0.0},
                                           RoomCase{Semantics::kPerScan, 4, true, 8, 0.7}),
                         caseName);

TEST(Semantics, PerRayCountsEveryCrossingPerScanOnce) {
  // Ray A ends in voxel (5,0,0); rays B and C pass through it. All in one scan.
  const std::vector<Ray> rays = {makeRay({0.05, 0.05, 0.05}, {0.55, 0.05, 0.05}),
                                 makeRay({0.05, 0.05, 0.05}, {1.05, 0.05, 0.05}),
                                 makeRay({0.05, 0.05, 0.05}, {1.25, 0.05, 0.05})};
  const OccupancyParams p;
  for (unsigned threads : {1u, 2u}) {
    VoxelMap per_ray = test::makeMap(test::smallConfig(Semantics::kPerRay));
    auto b1 = test::cpuBackend(per_ray, threads);
    test::integrate(per_ray, *b1, rays);
    EXPECT_FLOAT_EQ(per_ray.occupancyValue({5, 0, 0}), p.hit + 2 * p.miss);
    EXPECT_FLOAT_EQ(per_ray.occupancyValue({2, 0, 0}), 3 * p.miss);
    EXPECT_FLOAT_EQ(per_ray.occupancyValue({11, 0, 0}), p.miss);

    VoxelMap per_scan = test::makeMap(test::smallConfig(Semantics::kPerScan));
    auto b2 = test::cpuBackend(per_scan, threads);
    test::integrate(per_scan, *b2, rays);
    EXPECT_FLOAT_EQ(per_scan.occupancyValue({5, 0, 0}), p.hit);   // occupied wins
    EXPECT_FLOAT_EQ(per_scan.occupancyValue({2, 0, 0}), p.miss);  // once per scan
    EXPECT_FLOAT_EQ(per_scan.occupancyValue({12, 0, 0}), p.hit);
    // Hit twice in one scan: still one hit.
    const std::vector<Ray> twice = {makeRay({0.05, 0.05, 0.05}, {0.55, 0.05, 0.05}, 0, 7),
                                    makeRay({0.05, 0.05, 0.05}, {0.56, 0.06, 0.05}, 0, 7)};
    test::integrate(per_scan, *b2, twice);
    EXPECT_FLOAT_EQ(per_scan.occupancyValue({5, 0, 0}), std::min(2 * p.hit, p.clamp_max));
    EXPECT_EQ(per_scan.mean({5, 0, 0}).count, 3u);  // every sample feeds the mean
  }
}

TEST(Semantics, PerScanAppliesOnceInEachScan) {
  VoxelMap map = test::makeMap(test::smallConfig(Semantics::kPerScan));
  auto backend = test::cpuBackend(map, 1);
  std::vector<Ray> rays;
  for (std::uint64_t scan = 0; scan < 3; ++scan) {
    rays.push_back(makeRay({0.05, 0.05, 0.05}, {1.05, 0.05, 0.05}, 0, scan));
    rays.push_back(makeRay({0.05, 0.05, 0.05}, {1.05, 0.05, 0.05}, 0, scan));
  }
  test::integrate(map, *backend, rays);
  const OccupancyParams p;
  EXPECT_FLOAT_EQ(map.occupancyValue({3, 0, 0}), 3 * p.miss);
  EXPECT_FLOAT_EQ(map.occupancyValue({10, 0, 0}), std::min(3 * p.hit, p.clamp_max));
}

TEST(EndRules, ClippedAndNoReturnRaysClearUpToTheirEndVoxel) {
  VoxelMap map = test::makeMap(test::smallConfig(Semantics::kPerRay));
  auto backend = test::cpuBackend(map, 1);
  RayFilter filter;
  filter.max_range_m = 1.0;
  test::integrate(map, *backend,
                  std::vector<Ray>{makeRay({0.05, 0.05, 0.05}, {5.05, 0.05, 0.05}),
                                   makeRay({0.05, 0.05, 1.05}, {0.75, 0.05, 1.05}, kRayNoReturn)},
                  filter);
  EXPECT_EQ(map.state({9, 0, 0}), VoxelState::kFree);         // before the clip point
  EXPECT_EQ(map.state({10, 0, 0}), VoxelState::kUnobserved);  // holds the clip point: partly seen
  EXPECT_EQ(map.state({6, 0, 10}), VoxelState::kFree);        // before the no-return end
  EXPECT_EQ(map.state({7, 0, 10}), VoxelState::kUnobserved);  // no-return end voxel
  EXPECT_EQ(map.summarise().voxels_occupied, 0u);
  EXPECT_EQ(map.mean({10, 0, 0}).count, 0u);
}

TEST(EndRules, ZeroLengthRayIsAHitOnly) {
  VoxelMap map = test::makeMap(test::smallConfig(Semantics::kPerRay));
  auto backend = test::cpuBackend(map, 1);
  test::integrate(map, *backend, std::vector<Ray>{makeRay({0.12, 0.13, 0.14}, {0.12, 0.13, 0.14})});
  EXPECT_EQ(map.state({1, 1, 1}), VoxelState::kOccupied);
  const MapSummary s = map.summarise();
  EXPECT_EQ(s.voxels_occupied, 1u);
  EXPECT_EQ(s.voxels_free, 0u);
  const rm_vec3f m = rm_mean_decode(map.mean({1, 1, 1}).packed, 1u);
  EXPECT_NEAR(m.x, 0.2f, 1e-3f);
  EXPECT_NEAR(m.y, 0.3f, 1e-3f);
  EXPECT_NEAR(m.z, 0.4f, 1e-3f);
}

TEST(Threads, MultiThreadedMapIsBitIdenticalToSingleThreaded) {
  const std::vector<Ray> rays = test::randomScans(5489, 6, 4000);
  for (Semantics semantics : {Semantics::kPerRay, Semantics::kPerScan}) {
    for (bool reverse : {false, true}) {
      RayFilter filter;
      filter.reverse = reverse;
      filter.max_range_m = 9.0;
      VoxelMap reference = test::makeMap(test::smallConfig(semantics));
      auto single = test::cpuBackend(reference, 1);
      test::integrate(reference, *single, rays, filter);
      for (unsigned threads : {2u, 3u, 5u}) {
        VoxelMap map = test::makeMap(test::smallConfig(semantics));
        auto multi = test::cpuBackend(map, threads);
        test::integrate(map, *multi, rays, filter);
        const test::MapComparison cmp = test::compareMaps(reference, map);
        EXPECT_GT(cmp.compared, 100000u);
        EXPECT_EQ(cmp.exact_value, cmp.compared)
            << toString(semantics) << " threads " << threads << (reverse ? " reverse" : "");
        EXPECT_EQ(multi->stats().voxels_visited, single->stats().voxels_visited);
      }
    }
  }
}

TEST(Threads, StepTimesAccountForTheParallelBatchesOnly) {
  // What raymap bench reports as survey/serial/resolve/apply seconds and the apply balance: set
  // on several threads, zero on the single-threaded path, the workers' summed walk time within
  // threads x the step's wall time.
  const std::vector<Ray> rays = test::randomScans(7, 2, 4000);
  for (unsigned threads : {1u, 3u}) {
    VoxelMap map = test::makeMap(test::smallConfig(Semantics::kPerRay));
    auto backend = test::cpuBackend(map, threads);
    test::integrate(map, *backend, rays);
    const BackendStats s = backend->stats();
    if (threads == 1) {
      EXPECT_EQ(s.survey_seconds + s.serial_seconds + s.resolve_seconds + s.apply_seconds, 0.0);
      continue;
    }
    EXPECT_GT(s.survey_seconds, 0.0);
    EXPECT_GT(s.serial_seconds, 0.0);
    EXPECT_GT(s.resolve_seconds, 0.0);
    EXPECT_GT(s.apply_seconds, 0.0);
    EXPECT_GT(s.apply_busy_seconds, 0.0);
    EXPECT_LE(s.apply_busy_seconds, s.apply_seconds * threads);
  }
}

TEST(Threads, SpansOutsideTheWindowAreCountedOncePerSpan) {
  // Per scan, the workers walk the misses in the survey (MissPlanes) and count there.
  for (Semantics semantics : {Semantics::kPerRay, Semantics::kPerScan}) {
    MapConfig config = test::smallConfig(semantics);
    config.policy = StorePolicy::kRolling;
    config.window_regions = {4, 4, 4};
    const std::vector<Ray> rays = test::randomScans(11, 2, 3000);
    std::uint64_t single = 0;
    VoxelMap reference = test::makeMap(config);
    for (unsigned threads : {1u, 2u, 5u}) {
      VoxelMap map = test::makeMap(config);
      map.setWindowCentre({0, 0, 0});
      auto backend = test::cpuBackend(map, threads);
      test::integrate(map, *backend, rays);
      const std::uint64_t outside = backend->stats().spans_outside_window;
      if (threads == 1) {
        single = outside;
        EXPECT_GT(single, 0u);
        reference = std::move(map);
        continue;
      }
      EXPECT_EQ(outside, single) << toString(semantics) << " " << threads << " threads";
      const test::MapComparison cmp = test::compareMaps(reference, map);
      EXPECT_GT(cmp.compared, 1000u);
      EXPECT_EQ(cmp.exact_value, cmp.compared) << toString(semantics) << " " << threads;
    }
  }
}

TEST(Threads, ReverseAndForwardWalksAgree) {
  const std::vector<Ray> rays = test::randomScans(99, 4, 5000);
  VoxelMap forward = test::makeMap(test::smallConfig(Semantics::kPerRay));
  VoxelMap reverse = test::makeMap(test::smallConfig(Semantics::kPerRay));
  auto bf = test::cpuBackend(forward, 1);
  auto br = test::cpuBackend(reverse, 2);
  RayFilter rf;
  rf.reverse = true;
  test::integrate(forward, *bf, rays);
  test::integrate(reverse, *br, rays, rf);
  const test::MapComparison cmp = test::compareMaps(forward, reverse);
  EXPECT_GT(cmp.sameStateFraction(), 0.9999);
}

TEST(Capacity, FullStoreIsAnErrorNotASilentLoss) {
  for (Semantics semantics : {Semantics::kPerRay, Semantics::kPerScan}) {
    MapConfig config = test::smallConfig(semantics);
    config.memory_budget_bytes = 3u * 8u * 8u * 8u * 12u;  // three 0.8 m regions
    const std::vector<Ray> rays = {makeRay({0.1, 0.1, 0.1}, {0.5, 0.1, 0.1}),
                                   makeRay({0.1, 0.1, 0.1}, {5.0, 0.1, 0.1}, 0, 1)};
    for (unsigned threads : {1u, 2u}) {
      VoxelMap map = test::makeMap(config);
      auto backend = test::cpuBackend(map, threads);
      RayPreparer preparer(map, {});
      std::vector<PreparedRay> prepared(4);
      const auto p = preparer.prepare(rays, prepared);
      ASSERT_TRUE(backend->integrate(std::span<const PreparedRay>(prepared.data(), 1)));
      const MapSummary before = map.summarise();
      auto result =
          backend->integrate(std::span<const PreparedRay>(prepared.data() + 1, p.written - 1));
      ASSERT_FALSE(result);
      EXPECT_EQ(result.error(), IntegrateError::kStoreFull);
      if (threads > 1) {
        // The multi-threaded path checks capacity before touching any voxel.
        const MapSummary after = map.summarise();
        EXPECT_EQ(after.voxels_free, before.voxels_free);
        EXPECT_EQ(after.voxels_occupied, before.voxels_occupied);
      }
      EXPECT_EQ(map.state({5, 1, 1}), VoxelState::kOccupied)  // earlier data kept
          << toString(semantics) << " " << threads;
    }
  }
}

TEST(Rolling, OnlyTheWindowIsMapped) {
  MapConfig config = test::smallConfig(Semantics::kPerRay);
  config.policy = StorePolicy::kRolling;
  config.window_regions = {4, 4, 4};
  VoxelMap map = test::makeMap(config);
  map.setWindowCentre({0, 0, 0});
  auto backend = test::cpuBackend(map, 2);
  test::integrate(map, *backend,
                  std::vector<Ray>{makeRay({0.05, 0.05, 0.05}, {3.05, 0.05, 0.05}),
                                   makeRay({0.05, 0.05, 0.05}, {-1.55, 0.05, 0.05})});
  EXPECT_EQ(map.state({15, 0, 0}), VoxelState::kFree);
  EXPECT_EQ(map.state({-16, 0, 0}), VoxelState::kOccupied);
  EXPECT_EQ(map.state({16, 0, 0}), VoxelState::kUnobserved);
  EXPECT_EQ(map.summarise().voxels_occupied, 1u);
  // Follow the robot 1.6 m: the left part of the map is recycled, the ray end is now inside.
  map.setWindowCentre({1.6, 0, 0});
  test::integrate(map, *backend, std::vector<Ray>{makeRay({1.65, 0.05, 0.05}, {3.05, 0.05, 0.05})});
  EXPECT_EQ(map.state({30, 0, 0}), VoxelState::kOccupied);
  EXPECT_EQ(map.state({-16, 0, 0}), VoxelState::kUnobserved);  // its region was recycled
  EXPECT_EQ(map.state({5, 0, 0}), VoxelState::kFree);          // still in the window
  EXPECT_LE(map.store().size(), 64u);
}

}  // namespace
}  // namespace raymap
