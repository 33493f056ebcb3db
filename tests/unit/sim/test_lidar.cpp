// SPDX-License-Identifier: BSD-3-Clause
// The simulated lidar: sensor paths, per-column motion, determinism for a seed, dropout,
// no-return and blind-zone rays, and the built-in yard on top of it.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>

#include "src/sim/lidar.hpp"
#include "src/sim/yard_scan.hpp"

namespace raymap::sim {
namespace {

constexpr double kTolerance = 1e-9;

/// A closed box room (every ray returns): 10 m x 10 m x 3 m around the origin.
Scene closedRoom() {
  Scene scene;
  scene.boxes.push_back({{-5.2, -5.2, 0.0}, {5.2, -5.0, 3.2}});
  scene.boxes.push_back({{-5.2, 5.0, 0.0}, {5.2, 5.2, 3.2}});
  scene.boxes.push_back({{-5.2, -5.0, 0.0}, {-5.0, 5.0, 3.2}});
  scene.boxes.push_back({{5.0, -5.0, 0.0}, {5.2, 5.0, 3.2}});
  scene.boxes.push_back({{-5.2, -5.2, 3.0}, {5.2, 5.2, 3.2}});
  return scene;
}

SimulationConfig smallConfig(int scans) {
  SimulationConfig config;
  config.lidar.beams = 8;
  config.lidar.columns = 64;
  config.lidar.elevation_min_deg = -30.0;
  config.lidar.elevation_max_deg = 30.0;
  config.scans = scans;
  auto path = SensorPath::fromWaypoints(std::vector<Vec3d>{{-2, 0, 1}, {2, 0, 1}}, 2.0);
  EXPECT_TRUE(path.has_value());
  config.path = *path;
  return config;
}

std::size_t noReturns(const std::vector<Ray>& rays) {
  return static_cast<std::size_t>(std::count_if(
      rays.begin(), rays.end(), [](const Ray& r) { return (r.flags & kRayNoReturn) != 0; }));
}

// ---- paths ----

TEST(SensorPath, WaypointsAtConstantSpeedHeadingAlongTheWay) {
  const auto path = SensorPath::fromWaypoints(
      std::vector<Vec3d>{{0.0, 0.0, 1.0}, {4.0, 0.0, 1.0}, {4.0, 2.0, 1.0}}, 2.0);
  ASSERT_TRUE(path.has_value()) << path.error().message;

  EXPECT_EQ(path->startTime(), 0.0);
  EXPECT_NEAR(path->endTime(), 3.0, kTolerance);
  const SensorPose mid_first = path->at(1.0);
  EXPECT_NEAR(mid_first.position.x, 2.0, kTolerance);
  EXPECT_NEAR(mid_first.yaw_rad, 0.0, kTolerance);
  const SensorPose mid_second = path->at(2.5);
  EXPECT_NEAR(mid_second.position.x, 4.0, kTolerance);
  EXPECT_NEAR(mid_second.position.y, 1.0, kTolerance);
  EXPECT_NEAR(mid_second.yaw_rad, std::numbers::pi / 2.0, kTolerance);
  // At rest before the start and after the end.
  EXPECT_EQ(path->at(-1.0).position, (Vec3d{0.0, 0.0, 1.0}));
  EXPECT_EQ(path->at(10.0).position, (Vec3d{4.0, 2.0, 1.0}));
}

TEST(SensorPath, PosesInterpolateTheHeadingAlongTheShorterArc) {
  const double deg = std::numbers::pi / 180.0;
  const auto path = SensorPath::fromPoses(
      {{0.0, {0.0, 0.0, 0.0}, 170.0 * deg}, {1.0, {1.0, 0.0, 0.0}, -170.0 * deg}});
  ASSERT_TRUE(path.has_value());

  const SensorPose mid = path->at(0.5);

  EXPECT_NEAR(std::abs(std::remainder(mid.yaw_rad, 2.0 * std::numbers::pi)), std::numbers::pi,
              kTolerance);
  EXPECT_NEAR(mid.position.x, 0.5, kTolerance);
}

TEST(SensorPath, RejectsBadInput) {
  EXPECT_FALSE(SensorPath::fromPoses({}).has_value());
  EXPECT_FALSE(SensorPath::fromPoses({{1.0, {}, 0.0}, {1.0, {}, 0.0}}).has_value());
  EXPECT_FALSE(SensorPath::fromWaypoints(std::vector<Vec3d>{}, 1.0).has_value());
  EXPECT_FALSE(SensorPath::fromWaypoints(std::vector<Vec3d>{{0, 0, 0}}, 0.0).has_value());
  EXPECT_FALSE(
      SensorPath::fromWaypoints(std::vector<Vec3d>{{0, 0, std::nan("")}}, 1.0).has_value());
}

// ---- the recording ----

TEST(SimulateScans, OneRayPerBeamAndColumnWithTimesAndScans) {
  const SimulationConfig config = smallConfig(3);

  const std::vector<Ray> rays = simulateScans(closedRoom(), config);

  ASSERT_EQ(rays.size(), 3u * 64u * 8u);
  EXPECT_EQ(rays.front().scan, 0u);
  EXPECT_EQ(rays.back().scan, 2u);
  EXPECT_EQ(rays.front().time_s, 0.0);
  EXPECT_NEAR(rays.back().time_s, 2 * 0.1 + 0.1 * 63.0 / 64.0, kTolerance);
  EXPECT_TRUE(std::is_sorted(rays.begin(), rays.end(),
                             [](const Ray& a, const Ray& b) { return a.time_s < b.time_s; }));
  EXPECT_EQ(noReturns(rays), 0u);
}

TEST(SimulateScans, TheSensorMovesDuringAScan) {
  const SimulationConfig config = smallConfig(1);

  const std::vector<Ray> rays = simulateScans(closedRoom(), config);
  const std::vector<SensorPose> poses = columnPoses(config);

  ASSERT_EQ(poses.size(), 64u);
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const SensorPose& pose = poses[i / 8];
    ASSERT_EQ(rays[i].origin, pose.position);
    ASSERT_EQ(rays[i].time_s, pose.time_s);
  }
  // 2 m/s for most of 0.1 s.
  EXPECT_NEAR(rays.back().origin.x - rays.front().origin.x, 2.0 * 0.1 * 63.0 / 64.0, kTolerance);
}

TEST(SimulateScans, PerScanSamplingHoldsThePoseForTheRevolution) {
  SimulationConfig config = smallConfig(2);
  config.sampling = PoseSampling::kPerScan;

  const std::vector<Ray> rays = simulateScans(closedRoom(), config);

  EXPECT_EQ(rays.front().origin, rays[64 * 8 - 1].origin);
  EXPECT_NEAR(rays.back().origin.x, -2.0 + 2.0 * 0.1, kTolerance);
}

TEST(SimulateScans, NoiselessReturnsLieOnTheSurfaces) {
  SimulationConfig config = smallConfig(1);
  config.lidar.range_noise_m = 0.0;
  const Scene scene = closedRoom();

  for (const Ray& ray : simulateScans(scene, config)) {
    const Vec3d d = ray.sample - ray.origin;
    const double range = d.norm();
    ASSERT_NEAR(castRay(scene, ray.origin, d * (1.0 / range)), range, 1e-6);
    ASSERT_GT(ray.intensity, 0.0f);
  }
}

TEST(SimulateScans, HeadingTurnsTheFirstColumn) {
  SimulationConfig config = smallConfig(1);
  config.lidar.beams = 1;
  config.lidar.elevation_min_deg = 0.0;
  auto path = SensorPath::fromPoses({{0.0, {0.0, 0.0, 1.0}, std::numbers::pi / 2.0}});
  ASSERT_TRUE(path.has_value());
  config.path = *path;

  const std::vector<Ray> rays = simulateScans(closedRoom(), config);

  ASSERT_FALSE(rays.empty());
  EXPECT_NEAR(rays.front().sample.x, 0.0, 0.05);
  EXPECT_NEAR(rays.front().sample.y, 5.0, 0.05);  // the +y wall
}

TEST(SimulateScans, SameSeedSameRaysOtherSeedOtherNoise) {
  SimulationConfig config = smallConfig(2);
  config.lidar.dropout = 0.1;

  const std::vector<Ray> a = simulateScans(closedRoom(), config);
  const std::vector<Ray> b = simulateScans(closedRoom(), config);
  config.seed = 2;
  const std::vector<Ray> c = simulateScans(closedRoom(), config);

  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].sample, b[i].sample) << i;
    ASSERT_EQ(a[i].flags, b[i].flags) << i;
  }
  ASSERT_EQ(a.size(), c.size());
  std::size_t differ = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].origin, c[i].origin);
    differ += a[i].sample == c[i].sample ? 0u : 1u;
  }
  EXPECT_GT(differ, a.size() / 2);
}

TEST(SimulateScans, DropoutTurnsThatShareOfReturnsIntoNoReturns) {
  SimulationConfig config = smallConfig(10);
  config.lidar.dropout = 0.2;

  const std::vector<Ray> rays = simulateScans(closedRoom(), config);

  // 5,120 Bernoulli trials: the standard deviation of the share is 0.0056.
  const double share = static_cast<double>(noReturns(rays)) / static_cast<double>(rays.size());
  EXPECT_NEAR(share, 0.2, 0.025);
  for (const Ray& ray : rays) {
    if ((ray.flags & kRayNoReturn) != 0) {
      ASSERT_NEAR((ray.sample - ray.origin).norm(), config.lidar.max_range_m, 1e-9);
      ASSERT_EQ(ray.intensity, 0.0f);
    }
  }
}

TEST(SimulateScans, NothingWithinMaxRangeIsANoReturnRayAtMaxRange) {
  SimulationConfig config = smallConfig(1);
  config.lidar.max_range_m = 3.0;
  const Scene open;  // the ground only: upward beams see nothing

  const std::vector<Ray> rays = simulateScans(open, config);

  ASSERT_GT(noReturns(rays), 0u);
  for (const Ray& ray : rays) {
    const double length = (ray.sample - ray.origin).norm();
    if ((ray.flags & kRayNoReturn) != 0) {
      ASSERT_NEAR(length, 3.0, 1e-9);
    } else {
      ASSERT_LE(length, 3.0 + 0.1);
    }
  }
}

TEST(SimulateScans, ReturnsInsideTheBlindZoneAreLeftOut) {
  SimulationConfig config = smallConfig(1);
  // The ground is 1 m below: the steepest beam (-30 degrees) sees it 2 m away, the next 2.7 m.
  config.lidar.min_range_m = 2.5;
  const Scene open;

  const std::vector<Ray> rays = simulateScans(open, config);

  EXPECT_LT(rays.size(), 64u * 8u);
  for (const Ray& ray : rays) {
    if ((ray.flags & kRayNoReturn) == 0) {
      ASSERT_GE((ray.sample - ray.origin).norm(), 2.5 - 0.1);
    }
  }
}

TEST(YardScan, TheBuiltInYardStillScans) {
  YardScanConfig config;
  config.lidar.beams = 8;
  config.lidar.columns = 256;
  config.scans = 2;

  const std::vector<Ray> rays = simulateYardScans(config);

  ASSERT_EQ(rays.size(), 2u * 8u * 256u);
  EXPECT_EQ(rays.front().origin, config.start);
  EXPECT_EQ(rays.back().origin, config.end);
  EXPECT_EQ(rays.back().scan, 1u);
}

}  // namespace
}  // namespace raymap::sim
