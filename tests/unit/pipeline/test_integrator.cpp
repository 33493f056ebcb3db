// SPDX-License-Identifier: BSD-3-Clause
// Integrator on a real rolling VoxelMap and the CPU backend: deskewing with interpolated poses,
// extrinsics, waiting for and dropping scans without poses, no-return points, batching and the
// arrivals of completed scans. The test plays the ingest thread (mailbox and pose queue).
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>

#include "platform/pi_mutex.hpp"
#include "src/core/eigen_conversions.hpp"
#include "src/map/cpu_backend.hpp"
#include "src/map/voxel_map.hpp"
#include "src/pipeline/integrator.hpp"
#include "src/pipeline/pipeline_stats.hpp"
#include "src/pipeline/pose_update.hpp"
#include "src/pipeline/scan_mailbox.hpp"
#include "tests/support/integrator_feed.hpp"
#include "tests/support/nanoseconds.hpp"
#include "tests/support/test_rays.hpp"

namespace raymap::pipeline {
namespace {

using test::kMs;
constexpr std::int64_t kNever = std::numeric_limits<std::int64_t>::max();
constexpr std::int64_t kStamp = 1000 * kMs;  // header.stamp of the scans (pose clock)
constexpr std::int64_t kNow = 5000 * kMs;    // monotonic "now" of the integrator thread
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

/// The integrator's clock in these tests: it stands still except while the backend integrates,
/// which takes exactly kNsPerRay a ray. Deadlines and the measured cost per ray are then exact,
/// whatever the machine running the test is doing.
constexpr std::int64_t kNsPerRay = 1000;
std::atomic<std::int64_t> g_now_ns{kNow};
std::int64_t testClock() noexcept { return g_now_ns.load(); }

/// The CPU backend, on the test clock.
class ClockedBackend final : public Backend {
 public:
  explicit ClockedBackend(std::unique_ptr<Backend> inner) : inner_(std::move(inner)) {}
  const char* name() const noexcept override { return inner_->name(); }
  unsigned threads() const noexcept override { return inner_->threads(); }
  Expected<void, IntegrateError> integrate(std::span<const PreparedRay> rays) noexcept override {
    g_now_ns += static_cast<std::int64_t>(rays.size()) * kNsPerRay;
    return inner_->integrate(rays);
  }
  Expected<void, IntegrateError> synchronise() noexcept override { return inner_->synchronise(); }
  BackendStats stats() const noexcept override { return inner_->stats(); }

 private:
  std::unique_ptr<Backend> inner_;
};

/// A yaw of `radians` about +z.
Eigen::Quaterniond yaw(double radians) {
  return {std::cos(0.5 * radians), 0.0, 0.0, std::sin(0.5 * radians)};  // w x y z
}

io::Pose makePose(Vec3d position, Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity()) {
  io::Pose p;
  p.position = toEigen(position);
  p.orientation = orientation;
  return p;
}

/// The point in the frame of `pose` that `pose` maps to `p_world`.
Vec3d toLocal(const io::Pose& pose, Vec3d p_world) {
  return toVec3(pose.orientation.conjugate() * (toEigen(p_world) - pose.position));
}

/// The point of the world frame that `pose` maps `p_local` to.
Vec3d toWorld(const io::Pose& pose, Vec3d p_local) {
  return toVec3(pose.transform(toEigen(p_local)));
}

msgs::ScanPoint scanPoint(Vec3d p_sensor, float time_s = 0.0f, std::uint32_t flags = 0) {
  return msgs::ScanPoint{static_cast<float>(p_sensor.x),
                         static_cast<float>(p_sensor.y),
                         static_cast<float>(p_sensor.z),
                         time_s,
                         1.0f,
                         flags};
}

SensorSettings sensorAt(const io::Pose& extrinsic = {}) {
  SensorSettings s;
  s.extrinsic = extrinsic;
  s.filter.min_range_m = 0.2;
  s.filter.max_range_m = 10.0;
  return s;
}

IntegratorSettings defaultSettings() {
  IntegratorSettings s;
  s.batch_rays = 1024;
  s.batch_deadline_ns = 5 * kMs;
  s.pose_wait_ns = 50 * kMs;
  s.pose_hold_ns = 20 * kMs;
  s.pose_history = 64;
  s.clock_ns = &testClock;
  return s;
}

/// The pipeline around one integrator, as raymapd wires it: 0.1 m voxels, 1.6 m regions, a
/// rolling window of 6 x 6 x 2 regions (9.6 x 9.6 x 3.2 m) centred on the origin.
struct Rig {
  explicit Rig(const IntegratorSettings& settings = defaultSettings(),
               std::vector<SensorSettings> sensors = {sensorAt()},
               Semantics semantics = Semantics::kPerRay)
      : map(test::makeMap(mapConfig(semantics))),
        backend(std::make_unique<ClockedBackend>(test::cpuBackend(map, 1))),
        mailbox(4, 4096),
        poses(256),
        arrivals(64),
        integrator(prepared(map), *backend, mutex, mailbox, poses, arrivals, latest, settings,
                   std::move(sensors), stats) {}

  static MapConfig mapConfig(Semantics semantics) {
    g_now_ns = kNow;  // every rig starts the test clock over
    MapConfig c;
    c.geometry.resolution = 0.1;
    c.geometry.region_voxels = 16;
    c.policy = StorePolicy::kRolling;
    c.window_regions = {6, 6, 2};
    c.semantics = semantics;
    return c;
  }
  static VoxelMap& prepared(VoxelMap& m) {
    m.setWindowCentre({0.0, 0.0, 0.0});  // the publisher's job in raymapd
    return m;
  }

  void pushPose(std::int64_t stamp_ns, const io::Pose& base_in_world) {
    test::pushBasePose(poses, stamp_ns, base_in_world);
  }
  void pushExtrinsic(std::uint32_t sensor, const io::Pose& sensor_in_base) {
    test::pushSensorExtrinsic(poses, sensor, sensor_in_base);
  }
  /// Publishes a scan as the ingest thread does.
  void publishScan(std::int64_t stamp_ns, const std::vector<msgs::ScanPoint>& points,
                   std::uint32_t sensor = 0, std::int64_t arrival_ns = kNow) {
    test::publishScan(mailbox, stamp_ns, points, sensor, arrival_ns);
  }
  VoxelState stateAt(Vec3d p_world) const { return map.state(map.voxelOf(p_world)); }
  std::vector<std::int64_t> drainArrivals() {
    std::vector<std::int64_t> out;
    std::int64_t a = 0;
    while (arrivals.pop(a)) {
      out.push_back(a);
    }
    return out;
  }

  VoxelMap map;
  std::unique_ptr<Backend> backend;
  platform::PiMutex mutex;
  ScanMailbox mailbox;
  PoseQueue poses;
  ArrivalQueue arrivals;
  LatestPosition latest;
  PipelineStats stats;
  Integrator integrator;
};

/// A point straight ahead of an identity-posed sensor at the centre of a wall voxel.
const Vec3d kWall{3.05, 0.05, 0.05};

TEST(Integrator, DeskewsEveryPointWithThePoseAtItsTime) {
  auto rig = std::make_unique<Rig>();
  // The base moves 1 m along x and turns 90 degrees left during the 125 ms scan. Times are exact
  // in float (0, 1/16 s, 1/8 s) so that the interpolated poses are known exactly.
  const io::Pose start = makePose({0.0, 0.0, 0.0});
  const io::Pose middle =
      io::interpolate(start, makePose({1.0, 0.0, 0.0}, yaw(std::numbers::pi / 2)), 0.5);
  const io::Pose end = makePose({1.0, 0.0, 0.0}, yaw(std::numbers::pi / 2));
  rig->pushPose(kStamp, start);
  rig->pushPose(kStamp + 125 * kMs, end);
  // Three wall voxels at x = 3.0..3.1, one seen at each instant.
  const Vec3d w0{3.05, 0.05, 0.05};
  const Vec3d w1{3.05, 1.05, 0.05};
  const Vec3d w2{3.05, -1.05, 0.05};
  const Vec3d p0 = toLocal(start, w0);
  const Vec3d p1 = toLocal(middle, w1);
  const Vec3d p2 = toLocal(end, w2);
  rig->publishScan(kStamp, {scanPoint(p0, 0.0f), scanPoint(p1, 0.0625f), scanPoint(p2, 0.125f)});

  rig->integrator.step(kNow);
  rig->integrator.flush(kNow);

  EXPECT_EQ(rig->stats.scans_integrated.get(), 1u);
  EXPECT_EQ(rig->stats.rays_integrated.get(), 3u);
  EXPECT_EQ(rig->stats.scans_no_pose.get(), 0u);
  EXPECT_EQ(rig->stateAt(w0), VoxelState::kOccupied);
  EXPECT_EQ(rig->stateAt(w1), VoxelState::kOccupied);
  EXPECT_EQ(rig->stateAt(w2), VoxelState::kOccupied);
  EXPECT_EQ(rig->map.summarise().voxels_occupied, 3u) << "hits only at the three wall voxels";
  // Without deskewing (every point with the pose at the header stamp, or at the scan's end) the
  // hits would land here instead.
  EXPECT_NE(rig->stateAt(toWorld(start, p1)), VoxelState::kOccupied);
  EXPECT_NE(rig->stateAt(toWorld(start, p2)), VoxelState::kOccupied);
  EXPECT_NE(rig->stateAt(toWorld(end, p0)), VoxelState::kOccupied);
  // The ray of each point starts where the sensor was at that point's time: the voxels between
  // the interpolated origin and the wall are free.
  EXPECT_EQ(rig->stateAt({2.05, 0.05, 0.05}), VoxelState::kFree);
  const Vec3d middle_origin = toVec3(middle.position);
  EXPECT_EQ(rig->stateAt(middle_origin + (w1 - middle_origin) * 0.5), VoxelState::kFree);
}

TEST(Integrator, StaticExtrinsicPlacesTheSensorOnTheBase) {
  // Sensor 0.5 m forward, 1 m left, 0.2 m up, turned 180 degrees about z.
  const io::Pose extrinsic = makePose({0.5, 1.0, 0.2}, yaw(std::numbers::pi));
  auto rig =
      std::make_unique<Rig>(defaultSettings(), std::vector<SensorSettings>{sensorAt(extrinsic)});
  const io::Pose base = makePose({0.0, 0.0, 0.0});
  rig->pushPose(kStamp, base);
  const Vec3d p = toLocal(io::compose(base, extrinsic), kWall);

  rig->publishScan(kStamp, {scanPoint(p)});
  rig->integrator.step(kNow);
  rig->integrator.flush(kNow);

  EXPECT_EQ(rig->stateAt(kWall), VoxelState::kOccupied);
  EXPECT_EQ(rig->map.summarise().voxels_occupied, 1u);
  // The ray starts at the sensor: half way to the wall is free.
  EXPECT_EQ(rig->stateAt(Vec3d{0.5, 1.0, 0.2} + (kWall - Vec3d{0.5, 1.0, 0.2}) * 0.5),
            VoxelState::kFree);
}

TEST(Integrator, ExtrinsicUpdateTakesEffectForLaterScans) {
  auto rig = std::make_unique<Rig>();
  const io::Pose base = makePose({0.0, 0.0, 0.0});
  rig->pushPose(kStamp, base);
  rig->pushPose(kStamp + 200 * kMs, base);
  // Scan 1 with the configured (identity) extrinsic.
  rig->publishScan(kStamp, {scanPoint(kWall)});
  rig->integrator.step(kNow);
  rig->integrator.flush(kNow);
  ASSERT_EQ(rig->stateAt(kWall), VoxelState::kOccupied);

  // tf_static arrives: the sensor is 1 m left of the base, turned 180 degrees.
  const io::Pose extrinsic = makePose({0.0, 1.0, 0.0}, yaw(std::numbers::pi));
  rig->pushExtrinsic(0, extrinsic);
  const Vec3d target{-2.05, 2.05, 0.05};
  const Vec3d p = toLocal(io::compose(base, extrinsic), target);
  // Scan 2 at the same point time as scan 1: a pose cached for that time must not be reused.
  rig->publishScan(kStamp, {scanPoint(p)});
  rig->integrator.step(kNow + 10 * kMs);
  rig->integrator.flush(kNow + 10 * kMs);

  EXPECT_EQ(rig->stats.scans_integrated.get(), 2u);
  EXPECT_EQ(rig->stateAt(target), VoxelState::kOccupied);
  EXPECT_NE(rig->stateAt(toWorld(base, p)), VoxelState::kOccupied)
      << "scan 2 used the old extrinsic";
  EXPECT_EQ(rig->map.summarise().voxels_occupied, 2u);
}

TEST(Integrator, ExtrinsicOfAnUnknownSensorIsIgnored) {
  auto rig = std::make_unique<Rig>();
  rig->pushPose(kStamp, makePose({0.0, 0.0, 0.0}));
  rig->pushExtrinsic(7, makePose({0.0, 3.0, 0.0}));

  rig->publishScan(kStamp, {scanPoint(kWall)});
  rig->integrator.step(kNow);
  rig->integrator.flush(kNow);

  EXPECT_EQ(rig->stateAt(kWall), VoxelState::kOccupied);
}

// Regression: the cached sensor pose was keyed by point time alone, so two lidars whose clouds
// carry the same header stamp placed the second sensor's points with the first's extrinsic.
TEST(Integrator, TwoSensorsWithTheSameStampUseTheirOwnExtrinsics) {
  const io::Pose front = makePose({0.3, 0.0, 0.0});
  const io::Pose rear = makePose({-0.3, 0.0, 0.0}, yaw(std::numbers::pi));
  auto rig = std::make_unique<Rig>(defaultSettings(),
                                   std::vector<SensorSettings>{sensorAt(front), sensorAt(rear)});
  const io::Pose base = makePose({0.0, 0.0, 0.0});
  rig->pushPose(kStamp, base);
  const Vec3d front_target{3.05, 0.05, 0.05};
  const Vec3d rear_target{-3.05, -1.05, 0.05};
  const Vec3d p_front = toLocal(io::compose(base, front), front_target);
  const Vec3d p_rear = toLocal(io::compose(base, rear), rear_target);

  rig->publishScan(kStamp, {scanPoint(p_front)}, 0);
  rig->publishScan(kStamp, {scanPoint(p_rear)}, 1);
  rig->integrator.step(kNow);
  rig->integrator.flush(kNow);

  EXPECT_EQ(rig->stats.scans_integrated.get(), 2u);
  EXPECT_EQ(rig->stateAt(front_target), VoxelState::kOccupied);
  EXPECT_EQ(rig->stateAt(rear_target), VoxelState::kOccupied)
      << "the rear sensor's point was placed with another pose";
  EXPECT_NE(rig->stateAt(toWorld(io::compose(base, front), p_rear)), VoxelState::kOccupied)
      << "the rear sensor's point was placed with the front sensor's extrinsic";
}

TEST(Integrator, ScanWithoutPosesWaitsThenIsDropped) {
  auto rig = std::make_unique<Rig>();  // pose_wait 50 ms
  rig->publishScan(kStamp, {scanPoint(kWall)});

  const std::int64_t wake = rig->integrator.step(kNow);
  EXPECT_EQ(wake, kNow + 50 * kMs);
  EXPECT_EQ(rig->stats.scans_no_pose.get(), 0u);
  EXPECT_EQ(rig->mailbox.waiting(), 0u) << "the integrator holds the scan while it waits";
  EXPECT_EQ(rig->integrator.step(kNow + 49 * kMs), kNow + 50 * kMs) << "the wait is not renewed";
  EXPECT_EQ(rig->stats.scans_no_pose.get(), 0u);

  EXPECT_EQ(rig->integrator.step(kNow + 50 * kMs), kNever);

  EXPECT_EQ(rig->stats.scans_no_pose.get(), 1u);
  EXPECT_EQ(rig->stats.scans_integrated.get(), 0u);
  EXPECT_TRUE(rig->drainArrivals().empty());
  EXPECT_EQ(rig->map.summarise().voxels_occupied, 0u);
  // The slot went back: every slot takes a scan again without dropping one.
  for (std::uint32_t i = 0; i < rig->mailbox.capacity(); ++i) {
    rig->publishScan(kStamp, {scanPoint(kWall)});
  }
  EXPECT_EQ(rig->mailbox.droppedOldest(), 0u);
}

TEST(Integrator, ScanWaitsForPosesThatArriveLater) {
  auto rig = std::make_unique<Rig>();  // hold 20 ms
  rig->pushPose(kStamp, makePose({0.0, 0.0, 0.0}));
  // The last point is 100 ms after the only pose: not covered yet.
  rig->publishScan(kStamp, {scanPoint(kWall, 0.0f), scanPoint({3.05, 1.05, 0.05}, 0.1f)});
  const std::int64_t wake = rig->integrator.step(kNow);
  ASSERT_EQ(wake, kNow + 50 * kMs);
  EXPECT_EQ(rig->stats.rays_integrated.get(), 0u);

  rig->pushPose(kStamp + 100 * kMs, makePose({0.0, 0.0, 0.0}));
  rig->integrator.step(kNow + 10 * kMs);
  rig->integrator.flush(kNow + 10 * kMs);

  EXPECT_EQ(rig->stats.scans_no_pose.get(), 0u);
  EXPECT_EQ(rig->stats.scans_integrated.get(), 1u);
  EXPECT_EQ(rig->stateAt(kWall), VoxelState::kOccupied);
  EXPECT_EQ(rig->stateAt({3.05, 1.05, 0.05}), VoxelState::kOccupied);
}

TEST(Integrator, NewestPoseIsHeldForPointsJustBeyondIt) {
  auto rig = std::make_unique<Rig>();  // hold 20 ms
  rig->pushPose(kStamp, makePose({0.0, 0.0, 0.0}));

  rig->publishScan(kStamp, {scanPoint(kWall, 0.015f)});
  EXPECT_EQ(rig->integrator.step(kNow), kNow + 5 * kMs) << "batched: due at its deadline";
  rig->integrator.step(kNow + 5 * kMs);

  EXPECT_EQ(rig->stats.scans_integrated.get(), 1u);
  EXPECT_EQ(rig->stateAt(kWall), VoxelState::kOccupied);
}

TEST(Integrator, ScanOlderThanThePoseHistoryIsDroppedAtOnce) {
  IntegratorSettings settings = defaultSettings();
  settings.pose_history = 4;
  auto rig = std::make_unique<Rig>(settings);
  for (int i = 0; i < 10; ++i) {  // the history keeps 60..90 ms
    rig->pushPose(kStamp + i * 10 * kMs, makePose({0.0, 0.0, 0.0}));
  }
  rig->publishScan(kStamp + 20 * kMs, {scanPoint(kWall)});

  EXPECT_EQ(rig->integrator.step(kNow), kNever) << "no wait: older poses never come";

  EXPECT_EQ(rig->stats.scans_no_pose.get(), 1u);
  EXPECT_EQ(rig->stats.scans_integrated.get(), 0u);
  EXPECT_EQ(rig->integrator.poses().oldestStamp(), kStamp + 60 * kMs);
  EXPECT_EQ(rig->map.summarise().voxels_occupied, 0u);
}

TEST(Integrator, NoReturnPointsAreCountedAndNotIntegrated) {
  auto rig = std::make_unique<Rig>();
  rig->pushPose(kStamp, makePose({0.0, 0.0, 0.0}));
  msgs::ScanPoint no_return{kNaN, kNaN, kNaN, 0.0f, 0.0f, msgs::kPointNoReturn};
  rig->publishScan(kStamp, {scanPoint(kWall), no_return, scanPoint({3.05, 1.05, 0.05}), no_return,
                            scanPoint({3.05, -1.05, 0.05})});

  rig->integrator.step(kNow);
  rig->integrator.flush(kNow);

  EXPECT_EQ(rig->stats.points_no_return.get(), 2u);
  EXPECT_EQ(rig->stats.rays_integrated.get(), 3u);
  EXPECT_EQ(rig->stats.rays_rejected.get(), 0u);
  EXPECT_EQ(rig->stats.scans_integrated.get(), 1u);
  EXPECT_EQ(rig->map.summarise().voxels_occupied, 3u);
}

TEST(Integrator, APointWithACorruptTimeCostsThatPointNotTheScan) {
  auto rig = std::make_unique<Rig>();
  rig->pushPose(kStamp, makePose({0.0, 0.0, 0.0}));
  rig->pushPose(kStamp + 100 * kMs, makePose({0.0, 0.0, 0.0}));
  // An Ouster-like t of 0xFFFFFFFF ns (4.29 s after the stamp): no pose will ever cover it.
  rig->publishScan(kStamp,
                   {scanPoint(kWall, 0.0f), scanPoint({3.05, 1.05, 0.05}, 4.294967295f),
                    scanPoint({3.05, -1.05, 0.05}, 0.05f), scanPoint({3.05, 2.05, 0.05}, kNaN)});

  rig->integrator.step(kNow);
  rig->integrator.flush(kNow);

  EXPECT_EQ(rig->stats.scans_integrated.get(), 1u);
  EXPECT_EQ(rig->stats.scans_no_pose.get(), 0u);
  EXPECT_EQ(rig->stats.points_bad_time.get(), 2u);
  EXPECT_EQ(rig->stats.rays_integrated.get(), 2u);
  EXPECT_EQ(rig->stateAt(kWall), VoxelState::kOccupied);
  EXPECT_NE(rig->stateAt({3.05, 1.05, 0.05}), VoxelState::kOccupied);
}

/// A scan of `n` points at the wall, all at the header stamp.
std::vector<msgs::ScanPoint> wallScan(std::size_t n) {
  return std::vector<msgs::ScanPoint>(n, scanPoint(kWall));
}

TEST(Integrator, LatencyBoundSubsamplesAScanThatWouldMissTheLastMapWithinIt) {
  IntegratorSettings settings = defaultSettings();
  settings.shed_always = true;  // the bound applies without a second of saturation first
  auto rig = std::make_unique<Rig>(settings);
  rig->pushPose(kStamp, makePose({0.0, 0.0, 0.0}));
  // The scan arrived 100 ms ago; the bound (250 ms) allows the map published 5.75 ms from now,
  // generated 0.75 ms from now (no lead, and the margin of one 5 ms lock hold), and the
  // integrator starts out assuming 1 us a ray: 1,000 rays need 1 ms, so every second point fits.
  rig->stats.next_publish_ns.store(kNow + kMs * 3 / 4 + settings.max_lock_hold_ns);
  rig->stats.publish_lead_us.store(0);
  rig->publishScan(kStamp, wallScan(1000), 0, kNow - 100 * kMs);

  rig->integrator.step(kNow);
  rig->integrator.flush(kNow);

  EXPECT_EQ(rig->stats.scans_integrated.get(), 1u);
  EXPECT_EQ(rig->stats.scans_shed.get(), 0u);
  EXPECT_EQ(rig->stats.scans_cut_short.get(), 0u);
  EXPECT_EQ(rig->stats.points_shed.get(), 500u);
  EXPECT_EQ(rig->stats.rays_integrated.get(), 500u);
  EXPECT_LE(g_now_ns.load(), kNow + kMs * 3 / 4);  // in before the map's generation
}

TEST(Integrator, LatencyBoundDropsAScanNoMapWithinItCanHold) {
  IntegratorSettings settings = defaultSettings();
  settings.shed_always = true;  // the bound applies without a second of saturation first
  auto rig = std::make_unique<Rig>(settings);
  rig->pushPose(kStamp, makePose({0.0, 0.0, 0.0}));
  // Arrived 300 ms ago: even the next map, 0.5 ms away, is beyond 250 ms.
  rig->stats.next_publish_ns.store(kNow + kMs / 2);
  rig->publishScan(kStamp, wallScan(10), 0, kNow - 300 * kMs);
  // A later scan that makes it is still integrated.
  rig->publishScan(kStamp, wallScan(10), 0, kNow);

  rig->integrator.step(kNow);
  rig->integrator.flush(kNow);

  EXPECT_EQ(rig->stats.scans_shed.get(), 1u);
  EXPECT_EQ(rig->stats.scans_integrated.get(), 1u);
  EXPECT_EQ(rig->stats.rays_integrated.get(), 10u);
}

TEST(Integrator, DeadlineCutsAScanShortEvenBelowSaturation) {
  // Not saturated (no prediction): the scan is taken whole, and its deadline still holds. It
  // arrived 100 ms ago, so the last map within the bound is generated 2 ms from now; 4,000
  // rays at 1 us need 4. What went in by then is every second point, spread over the scan.
  auto rig = std::make_unique<Rig>();
  rig->pushPose(kStamp, makePose({0.0, 0.0, 0.0}));
  rig->stats.next_publish_ns.store(kNow + 2 * kMs + defaultSettings().max_lock_hold_ns);
  rig->stats.publish_lead_us.store(0);
  rig->publishScan(kStamp, wallScan(4000), 0, kNow - 100 * kMs);

  rig->integrator.step(kNow);

  EXPECT_EQ(rig->stats.scans_integrated.get(), 1u);
  EXPECT_EQ(rig->stats.scans_cut_short.get(), 1u);
  EXPECT_EQ(rig->stats.scans_shed.get(), 0u);
  EXPECT_EQ(rig->stats.rays_integrated.get(), 2000u);
  EXPECT_EQ(rig->stats.points_shed.get(), 2000u);
  EXPECT_LE(g_now_ns.load(), kNow + 2 * kMs);  // in the map before its generation
  // Its arrival is queued (the map that is generated next contains it).
  EXPECT_EQ(rig->drainArrivals(), (std::vector<std::int64_t>{kNow - 100 * kMs}));
}

TEST(Integrator, AScanWhoseDeadlineHasPassedIsShedWhole) {
  auto rig = std::make_unique<Rig>();
  rig->pushPose(kStamp, makePose({0.0, 0.0, 0.0}));
  // The last map within the bound was generated 2 ms ago.
  rig->stats.next_publish_ns.store(kNow + 3 * kMs);
  rig->stats.publish_lead_us.store(0);
  rig->publishScan(kStamp, wallScan(100), 0, kNow - 100 * kMs);

  rig->integrator.step(kNow);
  rig->integrator.flush(kNow);

  EXPECT_EQ(rig->stats.scans_shed.get(), 1u);
  EXPECT_EQ(rig->stats.scans_integrated.get(), 0u);
  EXPECT_EQ(rig->stats.points_shed.get(), 0u);  // shed whole: counted as a scan
  EXPECT_TRUE(rig->drainArrivals().empty());
}

TEST(Integrator, AnEmptyScanWithTimeLeftIsCountedEmptyNotShedAndKeepsNothingFresh) {
  auto rig = std::make_unique<Rig>();
  rig->pushPose(kStamp, makePose({0.0, 0.0, 0.0}));
  rig->stats.next_publish_ns.store(kNow + 100 * kMs);
  rig->publishScan(kStamp, {}, 0, kNow);

  rig->integrator.step(kNow);

  EXPECT_EQ(rig->stats.scans_empty.get(), 1u);
  EXPECT_EQ(rig->stats.scans_integrated.get(), 0u);
  EXPECT_EQ(rig->stats.last_scan_integrated_ns.load(), 0) << "nothing went into the map";
  EXPECT_EQ(rig->stats.scans_shed.get(), 0u);
  EXPECT_EQ(rig->stats.scans_cut_short.get(), 0u);
}

TEST(Integrator, AScanWhoseEveryRayIsShorterThanMinRangeIsEmptyAndCountedPerReason) {
  std::vector<SensorSettings> sensors = {sensorAt()};
  sensors[0].filter.min_range_m = 5.0;  // beyond the wall at 3 m
  auto rig = std::make_unique<Rig>(defaultSettings(), sensors);
  rig->pushPose(kStamp, makePose({0.0, 0.0, 0.0}));
  rig->publishScan(kStamp, std::vector<msgs::ScanPoint>(100, scanPoint(kWall)));

  rig->integrator.step(kNow);
  rig->integrator.flush(kNow);

  EXPECT_EQ(rig->stats.rays_integrated.get(), 0u);
  EXPECT_EQ(rig->stats.rays_rejected.get(), 100u);
  EXPECT_EQ(rig->stats.rays_too_short.get(), 100u);
  EXPECT_EQ(rig->stats.scans_empty.get(), 1u);
  EXPECT_EQ(rig->stats.scans_integrated.get(), 0u);
  EXPECT_EQ(rig->stats.last_scan_integrated_ns.load(), 0) << "the map is not fresher for it";
}

TEST(Integrator, APoseClockThatGoesBackStartsTheHistoryOverInsteadOfStarvingEveryScan) {
  // A bag played in a loop: its stamps go back 10 s at every lap. The poses after the jump used
  // to be ignored as out of order, and every scan of the new lap dropped for want of a pose.
  auto rig = std::make_unique<Rig>();
  rig->pushPose(kStamp, makePose({0.0, 0.0, 0.0}));
  rig->publishScan(kStamp, {scanPoint(kWall)});
  rig->integrator.step(kNow);
  rig->integrator.flush(kNow);
  ASSERT_EQ(rig->stats.scans_integrated.get(), 1u);

  const std::int64_t lap = kStamp - 10 * 1000 * kMs;
  rig->pushPose(lap, makePose({0.0, 0.0, 0.0}));
  rig->publishScan(lap, {scanPoint(kWall)});
  rig->integrator.step(kNow + 10 * kMs);
  rig->integrator.flush(kNow + 10 * kMs);

  EXPECT_EQ(rig->stats.pose_time_resets.get(), 1u);
  EXPECT_EQ(rig->stats.last_time_reset_ms.load(), 10000);
  EXPECT_EQ(rig->stats.poses_out_of_order.get(), 0u);
  EXPECT_EQ(rig->stats.scans_no_pose.get(), 0u);
  EXPECT_EQ(rig->stats.scans_integrated.get(), 2u);
}

TEST(Integrator, ALatePoseIsIgnoredNotAReset) {
  auto rig = std::make_unique<Rig>();
  rig->pushPose(kStamp, makePose({0.0, 0.0, 0.0}));
  rig->pushPose(kStamp - 50 * kMs, makePose({0.0, 0.0, 0.0}));  // best effort, delivered late
  rig->integrator.step(kNow);
  EXPECT_EQ(rig->stats.poses_out_of_order.get(), 1u);
  EXPECT_EQ(rig->stats.pose_time_resets.get(), 0u);
}

/// A rig that integrates one wall point, then receives a pose `jump_m` along x 100 ms later.
std::unique_ptr<Rig> rigAfterAJump(double jump_m, bool clear) {
  IntegratorSettings settings = defaultSettings();
  settings.max_pose_jump_m = 1.0;
  settings.clear_on_jump = clear;
  auto rig = std::make_unique<Rig>(settings);
  rig->pushPose(kStamp, makePose({0.0, 0.0, 0.0}));
  rig->publishScan(kStamp, {scanPoint(kWall)});
  rig->integrator.step(kNow);
  rig->integrator.flush(kNow);
  rig->pushPose(kStamp + 100 * kMs, makePose({jump_m, 0.0, 0.0}));
  rig->integrator.step(kNow + 10 * kMs);
  return rig;
}

TEST(Integrator, APoseJumpIsCountedAndKeepsOrClearsTheWindowAsConfigured) {
  const auto kept = rigAfterAJump(2.5, false);
  EXPECT_EQ(kept->stats.pose_jumps.get(), 1u);
  EXPECT_EQ(kept->stats.last_pose_jump_mm.load(), 2500);
  EXPECT_EQ(kept->stats.window_clears.get(), 0u);
  EXPECT_EQ(kept->stateAt(kWall), VoxelState::kOccupied);

  const auto cleared = rigAfterAJump(2.5, true);
  EXPECT_EQ(cleared->stats.pose_jumps.get(), 1u);
  EXPECT_EQ(cleared->stats.window_clears.get(), 1u);
  EXPECT_EQ(cleared->stateAt(kWall), VoxelState::kUnobserved);

  const auto walked = rigAfterAJump(0.5, true);  // 5 m/s: within max_pose_jump_m
  EXPECT_EQ(walked->stats.pose_jumps.get(), 0u);
  EXPECT_EQ(walked->stateAt(kWall), VoxelState::kOccupied);
}

TEST(Integrator, EarlierScansInTheBatchGoInBeforeTheirDeadline) {
  // Scan A (100 rays) must be in the map 2 ms from now; scan B (3,000 rays) has until the map
  // after. B's rays must not hold A's back: A goes in by its deadline, B whole after.
  IntegratorSettings settings = defaultSettings();
  settings.batch_rays = 16384;
  auto rig = std::make_unique<Rig>(settings);
  rig->pushPose(kStamp, makePose({0.0, 0.0, 0.0}));
  rig->stats.next_publish_ns.store(kNow + 2 * kMs + settings.max_lock_hold_ns);
  rig->stats.publish_lead_us.store(0);
  rig->publishScan(kStamp, wallScan(100), 0, kNow - 100 * kMs);
  rig->publishScan(kStamp, wallScan(3000), 0, kNow);

  rig->integrator.step(kNow);

  EXPECT_EQ(rig->stats.scans_integrated.get(), 2u);
  EXPECT_EQ(rig->stats.scans_cut_short.get(), 0u);
  EXPECT_EQ(rig->stats.rays_integrated.get(), 3100u);
  EXPECT_GE(rig->stats.batches.get(), 2u);  // A's batch went in on its own
}

TEST(Integrator, RayBudgetThinsEveryScanWhileTheInputExceedsTheBackendAndNotAfter) {
  // Scans come faster than the backend integrates them (the test clock runs only while it
  // integrates: it is busy all the time, and the mailbox drops the oldest): after a second every
  // scan is subsampled alike (subsample_stride > 1). Once scans come with idle time between
  // them, the stride comes back to 1.
  auto rig = std::make_unique<Rig>();
  rig->pushPose(0, makePose({0.0, 0.0, 0.0}));
  rig->pushPose(kNow * 4, makePose({0.0, 0.0, 0.0}));
  std::int64_t stamp = kStamp;
  for (int i = 0; i < 600; ++i) {  // 3 scans of 4 ms each step: 1.2 s of work per 400 ms offered
    for (int k = 0; k < 3; ++k) {
      rig->publishScan(stamp += kMs, wallScan(4000), 0, g_now_ns.load());
    }
    rig->integrator.step(g_now_ns.load());
  }
  EXPECT_GT(rig->stats.subsample_stride.load(), 1);
  EXPECT_GT(rig->stats.points_shed.get(), 0u);
  EXPECT_EQ(rig->stats.scans_shed.get(), 0u);  // no schedule: nothing is shed whole
  for (int i = 0; i < 200; ++i) {              // one scan every 20 ms, at most 4 ms of work
    rig->publishScan(stamp += kMs, wallScan(4000), 0, g_now_ns.load());
    rig->integrator.step(g_now_ns.load());
    g_now_ns += 20 * kMs;
  }
  EXPECT_EQ(rig->stats.subsample_stride.load(), 1);
}

TEST(Integrator, RaysShorterThanTheMinimumRangeAreRejected) {
  auto rig = std::make_unique<Rig>();  // min range 0.2 m
  rig->pushPose(kStamp, makePose({0.0, 0.0, 0.0}));
  rig->publishScan(kStamp, {scanPoint(kWall), scanPoint({0.1, 0.0, 0.0})});

  rig->integrator.step(kNow);
  rig->integrator.flush(kNow);

  EXPECT_EQ(rig->stats.rays_rejected.get(), 1u);
  EXPECT_EQ(rig->stats.rays_integrated.get(), 1u);
  EXPECT_EQ(rig->stats.scans_integrated.get(), 1u);
}

TEST(Integrator, ArrivalsOfCompletedScansAreQueuedAfterTheirRaysAreInTheMap) {
  auto rig = std::make_unique<Rig>();  // deadline 5 ms
  rig->pushPose(kStamp, makePose({0.0, 0.0, 0.0}));
  rig->pushPose(kStamp + 100 * kMs, makePose({0.0, 0.0, 0.0}));
  rig->publishScan(kStamp, {scanPoint(kWall)}, 0, kNow - 2 * kMs);
  rig->publishScan(kStamp + 50 * kMs, {scanPoint({3.05, 1.05, 0.05})}, 0, kNow - kMs);

  const std::int64_t due = rig->integrator.step(kNow);
  EXPECT_EQ(due, kNow - 2 * kMs + 5 * kMs) << "the first scan's arrival plus the deadline";
  EXPECT_TRUE(rig->drainArrivals().empty()) << "nothing is in the map yet";
  EXPECT_EQ(rig->stats.batches.get(), 0u);

  EXPECT_EQ(rig->integrator.step(due), kNever);

  EXPECT_EQ(rig->stats.batches.get(), 1u) << "both scans in one batch";
  EXPECT_EQ(rig->stats.scans_integrated.get(), 2u);
  EXPECT_EQ(rig->drainArrivals(), (std::vector<std::int64_t>{kNow - 2 * kMs, kNow - kMs}));
  EXPECT_EQ(rig->stats.newest_scan_stamp_ns.load(), kStamp + 50 * kMs);
}

TEST(Integrator, BatchesAreSplitAtBatchRays) {
  IntegratorSettings settings = defaultSettings();
  settings.batch_rays = 4;
  auto rig = std::make_unique<Rig>(settings);
  rig->pushPose(kStamp, makePose({0.0, 0.0, 0.0}));
  std::vector<msgs::ScanPoint> points;
  for (int i = 0; i < 10; ++i) {
    points.push_back(scanPoint({3.05, -1.95 + 0.4 * i, 0.05}));
  }
  rig->publishScan(kStamp, points);

  const std::int64_t due = rig->integrator.step(kNow);

  EXPECT_EQ(rig->stats.batches.get(), 2u) << "two full batches of 4 at once";
  EXPECT_EQ(rig->stats.rays_integrated.get(), 8u);
  EXPECT_EQ(rig->stats.scans_integrated.get(), 0u) << "the scan's last rays are not in yet";
  EXPECT_TRUE(rig->drainArrivals().empty());
  EXPECT_EQ(due, kNow + 5 * kMs);

  rig->integrator.step(due);

  EXPECT_EQ(rig->stats.batches.get(), 3u);
  EXPECT_EQ(rig->stats.rays_integrated.get(), 10u);
  EXPECT_EQ(rig->stats.scans_integrated.get(), 1u);
  EXPECT_EQ(rig->drainArrivals().size(), 1u);
  EXPECT_EQ(rig->map.summarise().voxels_occupied, 10u);
}

// Regression: a scan of exactly batch_rays (or a multiple) left a full batch waiting for the
// deadline.
TEST(Integrator, FullBatchIsIntegratedWithoutWaitingForTheDeadline) {
  IntegratorSettings settings = defaultSettings();
  settings.batch_rays = 4;
  auto rig = std::make_unique<Rig>(settings);
  rig->pushPose(kStamp, makePose({0.0, 0.0, 0.0}));
  std::vector<msgs::ScanPoint> points;
  for (int i = 0; i < 4; ++i) {
    points.push_back(scanPoint({3.05, -1.95 + 0.4 * i, 0.05}));
  }
  rig->publishScan(kStamp, points);

  rig->integrator.step(kNow);

  EXPECT_EQ(rig->stats.batches.get(), 1u);
  EXPECT_EQ(rig->stats.scans_integrated.get(), 1u);
}

TEST(Integrator, SensorChangeClosesTheBatch) {
  auto rig =
      std::make_unique<Rig>(defaultSettings(), std::vector<SensorSettings>{sensorAt(), sensorAt()});
  rig->pushPose(kStamp, makePose({0.0, 0.0, 0.0}));
  rig->pushPose(kStamp + 100 * kMs, makePose({0.0, 0.0, 0.0}));
  rig->publishScan(kStamp, {scanPoint(kWall)}, 0);
  rig->publishScan(kStamp + 10 * kMs, {scanPoint({3.05, 1.05, 0.05})}, 1);

  rig->integrator.step(kNow);

  EXPECT_EQ(rig->stats.batches.get(), 1u) << "sensor 0's batch went in when sensor 1's came";
  EXPECT_EQ(rig->stats.scans_integrated.get(), 1u);
  rig->integrator.step(kNow + 5 * kMs);
  EXPECT_EQ(rig->stats.batches.get(), 2u);
  EXPECT_EQ(rig->stats.scans_integrated.get(), 2u);
}

TEST(Integrator, PerScanSemanticsIntegrateEachScanInOneCallAtOnce) {
  IntegratorSettings settings = defaultSettings();
  settings.batch_rays = 4;  // smaller than a scan: per-scan batches hold a whole scan anyway
  auto rig =
      std::make_unique<Rig>(settings, std::vector<SensorSettings>{sensorAt()}, Semantics::kPerScan);
  rig->pushPose(kStamp, makePose({0.0, 0.0, 0.0}));
  rig->pushPose(kStamp + 100 * kMs, makePose({0.0, 0.0, 0.0}));
  std::vector<msgs::ScanPoint> points;
  for (int i = 0; i < 10; ++i) {
    points.push_back(scanPoint({3.05, -1.95 + 0.4 * i, 0.05}));
  }
  rig->publishScan(kStamp, points);
  rig->publishScan(kStamp + 50 * kMs, points);

  EXPECT_EQ(rig->integrator.step(kNow), kNever) << "nothing left for a deadline";

  EXPECT_EQ(rig->stats.batches.get(), 2u);
  EXPECT_EQ(rig->stats.rays_integrated.get(), 20u);
  EXPECT_EQ(rig->stats.scans_integrated.get(), 2u);
  EXPECT_EQ(rig->drainArrivals().size(), 2u);
  EXPECT_EQ(rig->map.summarise().voxels_occupied, 10u);
}

// Regression: while a scan waited for poses, step() returned the pose give-up time without
// looking at the pending batch: an earlier, complete scan stayed out of the map (and its arrival
// out of the latency queue) up to pose_wait_ns instead of batch_deadline_ns.
TEST(Integrator, PendingBatchMeetsItsDeadlineWhileTheNextScanWaitsForPoses) {
  auto rig = std::make_unique<Rig>();  // deadline 5 ms, pose wait 50 ms, hold 20 ms
  rig->pushPose(kStamp, makePose({0.0, 0.0, 0.0}));
  rig->publishScan(kStamp, {scanPoint(kWall)}, 0, kNow);
  rig->publishScan(kStamp + 100 * kMs, {scanPoint({3.05, 1.05, 0.05})}, 0, kNow);

  const std::int64_t wake = rig->integrator.step(kNow);
  EXPECT_LE(wake, kNow + 5 * kMs) << "the first scan's batch is due before the pose give-up";
  rig->integrator.step(kNow + 5 * kMs);

  EXPECT_EQ(rig->stats.scans_integrated.get(), 1u);
  EXPECT_EQ(rig->drainArrivals().size(), 1u);
  EXPECT_EQ(rig->stateAt(kWall), VoxelState::kOccupied);
}

TEST(Integrator, PosesFeedTheHistoryAndTheLatestPosition) {
  auto rig = std::make_unique<Rig>();
  std::int64_t stamp = 0;
  Vec3d position;
  ASSERT_FALSE(rig->latest.load(&stamp, &position));
  rig->pushPose(kStamp, makePose({1.0, 2.0, 3.0}));
  rig->pushPose(kStamp + 10 * kMs, makePose({4.0, 5.0, 6.0}));
  rig->pushPose(kStamp + 5 * kMs, makePose({9.0, 9.0, 9.0}));  // out of order: ignored

  EXPECT_EQ(rig->integrator.step(kNow), kNever) << "no scan: nothing to wake for";

  EXPECT_EQ(rig->stats.poses_out_of_order.get(), 1u);
  EXPECT_EQ(rig->integrator.poses().size(), 2u);
  ASSERT_TRUE(rig->latest.load(&stamp, &position));
  EXPECT_EQ(stamp, kStamp + 10 * kMs);
  EXPECT_EQ(position, (Vec3d{4.0, 5.0, 6.0}));
}

}  // namespace
}  // namespace raymap::pipeline
