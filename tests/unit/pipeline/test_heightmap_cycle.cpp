// SPDX-License-Identifier: BSD-3-Clause
// HeightmapCycle on a real rolling map with the CPU backend and generator: no pose, a flat floor
// under the robot, the window following the robot, and the latency bookkeeping.
#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

#include <gtest/gtest.h>

#include "platform/pi_mutex.hpp"
#include "src/heightmap/heightmap_generator.hpp"
#include "src/map/voxel_map.hpp"
#include "src/pipeline/heightmap_cycle.hpp"
#include "src/pipeline/pipeline_stats.hpp"
#include "src/pipeline/pose_update.hpp"
#include "tests/support/nanoseconds.hpp"
#include "tests/support/test_rays.hpp"

namespace raymap::pipeline {
namespace {

using test::kMs;
constexpr double kFloorZ = -0.95;              // floor samples: the centre of voxel layer z = -10
constexpr double kBaseHeight = 0.9;            // base above the ground
constexpr double kElevationTolerance = 0.051;  // half a voxel

/// 0.1 m voxels, 1.6 m regions, a window of 6 x 6 x 2 regions; a 4 m height map.
struct CycleRig {
  explicit CycleRig(double base_height = kBaseHeight)
      : map(test::makeMap(mapConfig())),
        backend(test::cpuBackend(map, 1)),
        generator(heightmap::makeCpuHeightmapGenerator()),
        arrivals(64),
        cycle(map, *backend, mutex, *generator, options(), base_height, latest, arrivals, stats) {}

  static MapConfig mapConfig() {
    MapConfig c;
    c.geometry.resolution = 0.1;
    c.geometry.region_voxels = 16;
    c.policy = StorePolicy::kRolling;
    c.window_regions = {6, 6, 2};
    return c;
  }
  static heightmap::HeightmapOptions options() {
    heightmap::HeightmapOptions o;
    o.size = 4.0;
    o.mode = heightmap::HeightmapMode::kPlanar;
    o.min_clearance = 0.5;
    return o;
  }

  /// A flat floor at kFloorZ seen from a sensor 1 m above it, within `radius` of (cx, cy).
  void integrateFloor(double cx, double cy, double radius) {
    map.setWindowCentre({cx, cy, 0.0});
    std::vector<Ray> rays;
    const Vec3d origin{cx + 0.05, cy + 0.05, kFloorZ + 1.0};
    for (double dx = -radius; dx <= radius; dx += 0.1) {
      for (double dy = -radius; dy <= radius; dy += 0.1) {
        rays.push_back(test::makeRay(origin, {cx + dx + 0.05, cy + dy + 0.05, kFloorZ}));
      }
    }
    test::integrate(map, *backend, rays);
  }

  VoxelMap map;
  std::unique_ptr<Backend> backend;
  std::unique_ptr<heightmap::HeightmapGenerator> generator;
  platform::PiMutex mutex;
  LatestPosition latest;
  ArrivalQueue arrivals;
  PipelineStats stats;
  HeightmapCycle cycle;
};

TEST(HeightmapCycle, NoPoseYetNoHeightMap) {
  auto rig = std::make_unique<CycleRig>();
  const Vec3i window_before = rig->map.windowMinRegion();

  auto result = rig->cycle.generate();

  ASSERT_FALSE(result);
  EXPECT_EQ(result.error(), CycleError::kNoPose);
  EXPECT_STREQ(toString(result.error()), "no pose yet");
  EXPECT_EQ(rig->map.windowMinRegion(), window_before);
  DurationHistogram::Snapshot s;
  rig->stats.generate_us.snapshot(&s);
  EXPECT_EQ(s.total, 0u);
}

TEST(HeightmapCycle, FlatFloorGivesItsElevationAroundTheRobot) {
  auto rig = std::make_unique<CycleRig>();
  rig->integrateFloor(0.0, 0.0, 2.5);
  rig->latest.store(100 * kMs, {0.0, 0.0, kFloorZ + kBaseHeight});

  auto result = rig->cycle.generate();

  ASSERT_TRUE(result) << toString(result.error());
  const heightmap::HeightMap& hm = rig->cycle.heightMap();
  ASSERT_EQ(hm.cells_x, 40);
  ASSERT_EQ(hm.cells_y, 40);
  ASSERT_EQ(hm.elevation.size(), hm.cellCount());
  EXPECT_NEAR(hm.centre_x, 0.0, 0.1);
  EXPECT_NEAR(hm.centre_y, 0.0, 0.1);
  int surfaces = 0;
  for (int j = 0; j < hm.cells_y; ++j) {
    for (int i = 0; i < hm.cells_x; ++i) {
      const Vec3d c = hm.cellCentre(i, j);
      if (std::abs(c.x) > 1.5 || std::abs(c.y) > 1.5) {
        continue;  // well inside the floor patch
      }
      ASSERT_EQ(hm.kindAt(i, j), heightmap::CellKind::kSurface) << i << ", " << j;
      EXPECT_NEAR(hm.elevation[hm.index(i, j)], kFloorZ, kElevationTolerance) << i << ", " << j;
      ++surfaces;
    }
  }
  EXPECT_GE(surfaces, 900);  // 30 x 30 cells
  DurationHistogram::Snapshot s;
  rig->stats.generate_us.snapshot(&s);
  EXPECT_EQ(s.total, 1u);
  // One lock hold per cycle; on the CPU nothing crosses a bus.
  rig->stats.heightmap_lock_hold_us.snapshot(&s);
  EXPECT_EQ(s.total, 1u);
  for (const DurationHistogram* bytes :
       {&rig->stats.sync_copy_bytes, &rig->stats.heightmap_copy_bytes}) {
    bytes->snapshot(&s);
    EXPECT_EQ(s.total, 1u);
    EXPECT_EQ(s.max_us, 0u);
  }
}

TEST(HeightmapCycle, WindowFollowsTheRobotWhenItMovesFar) {
  auto rig = std::make_unique<CycleRig>();
  rig->integrateFloor(0.0, 0.0, 2.5);
  const double z = kFloorZ + kBaseHeight;
  rig->latest.store(100 * kMs, {0.0, 0.0, z});
  ASSERT_TRUE(rig->cycle.generate());
  const Vec3i window_at_origin = rig->map.windowMinRegion();
  const std::uint64_t recycled_at_origin = rig->map.regionsRecycled();

  // A short move keeps the window (it is centred to the nearest region).
  rig->latest.store(200 * kMs, {0.3, -0.2, z});
  ASSERT_TRUE(rig->cycle.generate());
  EXPECT_EQ(rig->map.windowMinRegion(), window_at_origin);
  EXPECT_EQ(rig->map.regionsRecycled(), recycled_at_origin);
  EXPECT_NEAR(rig->cycle.heightMap().centre_x, 0.3, 0.1) << "the height map follows anyway";

  // 10 m along x: the window moves with the robot and the floor behind it is recycled.
  rig->latest.store(300 * kMs, {10.0, 0.0, z});
  auto far = rig->cycle.generate();

  ASSERT_TRUE(far) << toString(far.error());
  EXPECT_EQ(rig->map.windowMinRegion(), (Vec3i{3, window_at_origin.y, window_at_origin.z}));
  EXPECT_GT(rig->map.regionsRecycled(), recycled_at_origin);
  EXPECT_NEAR(rig->cycle.heightMap().centre_x, 10.0, 0.1);
  EXPECT_NEAR(rig->cycle.heightMap().centre_y, 0.0, 0.1);
  int i = 0;
  int j = 0;
  ASSERT_TRUE(rig->cycle.heightMap().cellOf(10.0, 0.0, &i, &j));
  EXPECT_EQ(rig->cycle.heightMap().kindAt(i, j), heightmap::CellKind::kUnknown)
      << "nothing was seen there";
  EXPECT_EQ(rig->map.state(rig->map.voxelOf({0.05, 0.05, kFloorZ})), VoxelState::kUnobserved)
      << "the floor left the window";
}

TEST(HeightmapCycle, RequestOutsideTheWindowIsAPlanError) {
  auto rig = std::make_unique<CycleRig>(/*base_height=*/100.0);
  rig->latest.store(100 * kMs, {0.0, 0.0, 0.0});

  auto result = rig->cycle.generate();

  ASSERT_FALSE(result);
  EXPECT_EQ(result.error(), CycleError::kPlan);
}

TEST(HeightmapCycle, PublishedMapRecordsTheLatencyOfTheScansItContains) {
  auto rig = std::make_unique<CycleRig>();
  rig->latest.store(100 * kMs, {0.0, 0.0, kFloorZ + kBaseHeight});
  rig->stats.newest_scan_stamp_ns.store(123456);
  ASSERT_TRUE(rig->arrivals.push(1 * kMs));  // integrated before the map was generated
  ASSERT_TRUE(rig->arrivals.push(2 * kMs));

  ASSERT_TRUE(rig->cycle.generate());
  ASSERT_TRUE(rig->arrivals.push(3 * kMs));  // integrated after: not in this map
  rig->cycle.recordPublished(10 * kMs);

  EXPECT_EQ(rig->cycle.dataStampNs(), 123456);
  DurationHistogram::Snapshot s;
  rig->stats.latency_us.snapshot(&s);
  EXPECT_EQ(s.total, 2u);
  EXPECT_EQ(s.max_us, 9000u);  // 10 ms - 1 ms
  EXPECT_EQ(rig->arrivals.read_available(), 1u);

  // The next map contains the third scan.
  ASSERT_TRUE(rig->cycle.generate());
  rig->cycle.recordPublished(20 * kMs);
  rig->stats.latency_us.snapshot(&s);
  EXPECT_EQ(s.total, 3u);
  EXPECT_EQ(s.max_us, 17000u);
  EXPECT_EQ(rig->arrivals.read_available(), 0u);
  // A map published without a new generate() records nothing more.
  rig->cycle.recordPublished(30 * kMs);
  rig->stats.latency_us.snapshot(&s);
  EXPECT_EQ(s.total, 3u);
}

TEST(HeightmapCycle, ErrorNamesAreStable) {
  EXPECT_STREQ(toString(CycleError::kNoPose), "no pose yet");
  EXPECT_STREQ(toString(CycleError::kSynchronise), "device synchronise failed");
  EXPECT_STREQ(toString(CycleError::kPlan), "height-map request does not fit the map");
  EXPECT_STREQ(toString(CycleError::kGenerate), "height-map generation failed");
}

}  // namespace
}  // namespace raymap::pipeline
