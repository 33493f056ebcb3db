// SPDX-License-Identifier: BSD-3-Clause
// RayBatcher: batches prepared on the CPU backend's threads are the batches one thread prepares
// (same map bit for bit, same counters), rejected rays and all.
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <gtest/gtest.h>

#include "src/map/cpu_backend.hpp"
#include "src/map/ray_batcher.hpp"
#include "tests/support/test_rays.hpp"

namespace raymap {
namespace {

/// Random scans with rays the preparer rejects spread through them (NaN, too short, beyond the
/// map's key range), so that the ranges prepared side by side leave gaps to close.
std::vector<Ray> raysWithRejects() {
  std::vector<Ray> rays = test::randomScans(4242, 2, 16000);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (std::size_t i = 0; i < rays.size(); i += 7) {
    switch (i % 3) {
      case 0:
        rays[i].sample.x = nan;
        break;
      case 1:
        rays[i].sample = rays[i].origin + Vec3d{0.01, 0.0, 0.0};  // under --min-range
        break;
      default:
        rays[i].origin = Vec3d{1e12, 0.0, 0.0};  // outside the key range
        rays[i].sample = Vec3d{1e12 + 1.0, 0.0, 0.0};
        break;
    }
  }
  return rays;
}

struct BatchedRun {
  RayCounters rays;
  BatcherCounters batches;
};

/// Feeds `rays` in chunks of 10,000 (runs cross chunk and batch boundaries) through a batcher of
/// 16,384 rays.
BatchedRun batchAll(VoxelMap& map, Backend& backend, const std::vector<Ray>& rays,
                    const RayFilter& filter) {
  RayPreparer preparer(map, filter);
  RayBatcher batcher(map, backend, 16384);
  for (std::size_t begin = 0; begin < rays.size(); begin += 10000) {
    const std::size_t n = std::min<std::size_t>(10000, rays.size() - begin);
    EXPECT_TRUE(batcher.add(preparer, std::span<const Ray>(rays.data() + begin, n)).has_value());
  }
  EXPECT_TRUE(batcher.flush().has_value());
  return {preparer.counters(), batcher.counters()};
}

void expectSameCounters(const RayCounters& a, const RayCounters& b) {
  EXPECT_EQ(a.rays_in, b.rays_in);
  EXPECT_EQ(a.rays_invalid, b.rays_invalid);
  EXPECT_EQ(a.rays_too_short, b.rays_too_short);
  EXPECT_EQ(a.rays_out_of_bounds, b.rays_out_of_bounds);
  EXPECT_EQ(a.rays_outside_window, b.rays_outside_window);
  EXPECT_EQ(a.rays_clipped, b.rays_clipped);
  EXPECT_EQ(a.rays_no_return, b.rays_no_return);
  EXPECT_EQ(a.rays_accepted, b.rays_accepted);
  EXPECT_EQ(a.pieces_out, b.pieces_out);
}

/// The CPU backend asks for small batches only where batch boundaries cannot change the map:
/// per ray (occupancy, decay, TSDF) a map from batches of 1,024 rays is the map from one batch;
/// per scan a batch holds a scan, and an NDT batch's misses come before its hits.
TEST(RayBatcher, TheCpuPrefersSmallBatchesOnlyWhereBoundariesDoNotMatter) {
  MapConfig ndt = test::smallConfig(Semantics::kPerRay);
  ndt.mode = MapMode::kNdtOm;
  VoxelMap ndt_map = test::makeMap(ndt);
  EXPECT_EQ(test::cpuBackend(ndt_map, 2)->preferredBatchRays(), Backend::kLargeBatchRays);
  VoxelMap per_scan = test::makeMap(test::smallConfig(Semantics::kPerScan));
  EXPECT_EQ(test::cpuBackend(per_scan, 2)->preferredBatchRays(), Backend::kLargeBatchRays);

  const std::vector<Ray> rays = test::randomScans(777, 3, 6000);
  RayFilter filter;
  filter.max_range_m = 9.0;
  VoxelMap one_batch = test::makeMap(test::smallConfig(Semantics::kPerRay));
  auto backend = test::cpuBackend(one_batch, 2);
  EXPECT_LT(backend->preferredBatchRays(), Backend::kLargeBatchRays);
  test::integrate(one_batch, *backend, rays, filter);
  VoxelMap small_batches = test::makeMap(test::smallConfig(Semantics::kPerRay));
  auto small_backend = test::cpuBackend(small_batches, 2);
  RayPreparer preparer(small_batches, filter);
  RayBatcher batcher(small_batches, *small_backend, 1024);
  ASSERT_TRUE(batcher.add(preparer, rays).has_value());
  ASSERT_TRUE(batcher.flush().has_value());
  EXPECT_GT(batcher.counters().batches, 10u);
  const test::MapComparison cmp = test::compareMaps(one_batch, small_batches);
  EXPECT_GT(cmp.compared, 10000u);
  EXPECT_EQ(cmp.exact_value, cmp.compared);
}

TEST(RayBatcher, RaysPreparedOnTheBackendsThreadsMakeTheSingleThreadedMap) {
  const std::vector<Ray> rays = raysWithRejects();
  RayFilter filter;
  filter.min_range_m = 0.1;
  filter.max_range_m = 9.0;
  for (Semantics semantics : {Semantics::kPerRay, Semantics::kPerScan}) {
    VoxelMap reference = test::makeMap(test::smallConfig(semantics));
    auto single = test::cpuBackend(reference, 1);
    const BatchedRun one = batchAll(reference, *single, rays, filter);
    EXPECT_EQ(one.batches.parallel_prepares, 0u);
    EXPECT_GT(one.rays.rays_invalid + one.rays.rays_too_short, 0u);
    EXPECT_GT(one.rays.rays_out_of_bounds, 0u);
    for (unsigned threads : {2u, 3u}) {
      VoxelMap map = test::makeMap(test::smallConfig(semantics));
      auto multi = test::cpuBackend(map, threads);
      const BatchedRun many = batchAll(map, *multi, rays, filter);
      EXPECT_GT(many.batches.parallel_prepares, 0u) << threads << " threads";
      expectSameCounters(one.rays, many.rays);
      EXPECT_EQ(one.batches.batches, many.batches.batches);
      EXPECT_EQ(one.batches.rays_integrated, many.batches.rays_integrated);
      EXPECT_EQ(one.batches.scans_split, many.batches.scans_split);
      const test::MapComparison cmp = test::compareMaps(reference, map);
      EXPECT_GT(cmp.compared, 100000u);
      EXPECT_EQ(cmp.exact_value, cmp.compared) << toString(semantics) << ", " << threads;
    }
  }
}

TEST(RayBatcher, SegmentedRaysArePreparedOnTheCallingThread) {
  // A segmented ray's piece count is known only once it is prepared: no ranges side by side.
  const std::vector<Ray> rays = test::randomScans(77, 2, 12000);
  RayFilter filter;
  filter.segment_length_m = 2.0;
  VoxelMap reference = test::makeMap(test::smallConfig(Semantics::kPerRay));
  auto single = test::cpuBackend(reference, 1);
  const BatchedRun one = batchAll(reference, *single, rays, filter);
  VoxelMap map = test::makeMap(test::smallConfig(Semantics::kPerRay));
  auto multi = test::cpuBackend(map, 2);
  const BatchedRun many = batchAll(map, *multi, rays, filter);
  EXPECT_EQ(many.batches.parallel_prepares, 0u);
  EXPECT_GT(many.rays.pieces_out, many.rays.rays_accepted);
  expectSameCounters(one.rays, many.rays);
  const test::MapComparison cmp = test::compareMaps(reference, map);
  EXPECT_EQ(cmp.exact_value, cmp.compared);
}

TEST(RayBatcher, ARayWithMorePiecesThanABatchIsCountedAndTheRestStillGoIn) {
  // Issue 52: one ray whose pieces did not fit an empty batch ended the run, uncounted.
  VoxelMap map = test::makeMap(test::smallConfig(Semantics::kPerRay));
  auto backend = test::cpuBackend(map, 1);
  RayFilter filter;
  filter.segment_length_m = 0.1;  // a 2 m ray: 20 pieces
  RayPreparer preparer(map, filter);
  RayBatcher batcher(map, *backend, 8);
  std::vector<Ray> rays(4);
  for (std::size_t i = 0; i < rays.size(); ++i) {
    rays[i].origin = Vec3d{0.05, 0.05 + 0.3 * static_cast<double>(i), 0.05};
    rays[i].sample = rays[i].origin + Vec3d{i == 1 ? 2.0 : 0.5, 0.0, 0.0};  // 20 or 5 pieces
  }
  ASSERT_TRUE(batcher.add(preparer, rays).has_value());
  ASSERT_TRUE(batcher.flush().has_value());
  EXPECT_EQ(batcher.counters().rays_too_many_pieces, 1u);
  EXPECT_EQ(batcher.counters().rays_integrated, 15u) << "the three others, 5 pieces each";
  EXPECT_EQ(map.state(map.voxelOf(rays[3].sample)), VoxelState::kOccupied);
}

TEST(RayBatcher, AStreamReadAgainWithTheSameBatcherStartsANewScan) {
  // A one-scan input integrated twice with one batcher (raymap bench --steady-state keeps it, as
  // a service does): its rays carry the same Ray::scan both times, yet the second pass is a scan
  // of its own.
  std::vector<Ray> rays = test::randomScans(5, 1, 3000);
  VoxelMap map = test::makeMap(test::smallConfig(Semantics::kPerScan));
  auto backend = test::cpuBackend(map, 1);
  RayPreparer preparer(map, RayFilter{});
  RayBatcher batcher(map, *backend, 16384);

  ASSERT_TRUE(batcher.add(preparer, rays).has_value());
  ASSERT_TRUE(batcher.flush().has_value());
  const BatcherCounters first = batcher.counters();
  ASSERT_TRUE(batcher.add(preparer, rays).has_value());  // without endStream(): the same scan
  ASSERT_TRUE(batcher.flush().has_value());
  const BatcherCounters second = batcher.counters();
  batcher.endStream();
  ASSERT_TRUE(batcher.add(preparer, rays).has_value());
  ASSERT_TRUE(batcher.flush().has_value());
  const BatcherCounters third = batcher.counters();

  EXPECT_EQ(first.scans, 1u);
  EXPECT_EQ(second.scans, 1u);
  EXPECT_EQ(third.scans, 2u);
  EXPECT_EQ(third.batches, 3u);
  EXPECT_EQ(third.rays_integrated, 3u * rays.size());
}

// The staging room (raymapd's integrator's batch): integrating it in slices gives the map and
// counters of add() and flush() of the same slices, on the backend's host threads too.
TEST(RayBatcher, StagedSlicesMakeTheMapOfAddAndFlush) {
  const std::vector<Ray> rays = raysWithRejects();
  RayFilter filter;
  filter.min_range_m = 0.3;
  filter.max_range_m = 9.0;
  for (const unsigned threads : {1u, 2u}) {
    VoxelMap added = test::makeMap(test::smallConfig(Semantics::kPerRay));
    VoxelMap staged = test::makeMap(test::smallConfig(Semantics::kPerRay));
    auto added_backend = test::cpuBackend(added, threads);
    auto staged_backend = test::cpuBackend(staged, threads);
    RayPreparer added_preparer(added, filter);
    RayPreparer staged_preparer(staged, filter);
    RayBatcher add_batcher(added, *added_backend, 16384);
    RayBatcher stage_batcher(staged, *staged_backend, 16384);
    const std::span<Ray> room = stage_batcher.staging();
    ASSERT_EQ(room.size(), 16384u);
    for (std::size_t begin = 0; begin < rays.size(); begin += room.size()) {
      const std::size_t n = std::min(room.size(), rays.size() - begin);
      std::copy_n(rays.begin() + static_cast<std::ptrdiff_t>(begin), n, room.begin());
      for (std::size_t done = 0; done < n; done += 5000) {
        const std::size_t slice = std::min<std::size_t>(5000, n - done);
        EXPECT_TRUE(add_batcher.add(added_preparer,
                                    std::span<const Ray>(rays).subspan(begin + done, slice)));
        EXPECT_TRUE(add_batcher.flush());
        EXPECT_TRUE(stage_batcher.integrateStaged(staged_preparer, done, slice));
        EXPECT_EQ(stage_batcher.pending(), 0u);
      }
    }
    expectSameCounters(staged_preparer.counters(), added_preparer.counters());
    EXPECT_EQ(stage_batcher.counters().batches, add_batcher.counters().batches);
    EXPECT_EQ(stage_batcher.counters().scans, add_batcher.counters().scans);
    EXPECT_EQ(stage_batcher.counters().rays_integrated, add_batcher.counters().rays_integrated);
    EXPECT_GT(stage_batcher.counters().rays_integrated, 0u);
    const test::MapComparison cmp = test::compareMaps(added, staged);
    EXPECT_GT(cmp.compared, 100000u);
    EXPECT_EQ(cmp.exact_value, cmp.compared) << threads << " threads";
  }
}

}  // namespace
}  // namespace raymap
