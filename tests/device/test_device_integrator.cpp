// SPDX-License-Identifier: BSD-3-Clause
// raymapd's integrator on a device backend that deskews and prepares on the device (its batches
// are points with pose tables, RayBatcher::integratePoints) against the same integrator on the
// same device planning on the host (its batches are rays deskewed on the host): a sensor moving
// and turning under 100 Hz odometry, scans whose points carry their own times, no-return and
// too-near points, an extrinsic that changes between scans, and poses that arrive while a scan
// is converted. The maps must be the same bit for bit, and so must every count.
#include <atomic>
#include <cmath>
#include <cstdint>
#include <memory>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "platform/pi_mutex.hpp"
#include "src/map/voxel_map.hpp"
#include "src/pipeline/integrator.hpp"
#include "src/pipeline/pipeline_stats.hpp"
#include "src/pipeline/pose_update.hpp"
#include "src/pipeline/scan_mailbox.hpp"
#include "tests/device/device_map_compare.hpp"
#include "tests/device/device_under_test.hpp"
#include "tests/support/integrator_feed.hpp"
#include "tests/support/test_rays.hpp"

namespace raymap::test {
namespace {

constexpr std::int64_t kIntegratorMs = 1'000'000;
constexpr std::int64_t kIntegratorNow = 9'000 * kIntegratorMs;

/// A clock that stands still: no deadline passes, nothing is shed.
std::int64_t stillClock() noexcept { return kIntegratorNow; }

io::Pose basePoseAt(std::int64_t t_ns) {
  const double s = static_cast<double>(t_ns) * 1e-9;
  const double yaw = 0.6 * s;
  return io::Pose{Eigen::Vector3d(0.8 * s, 0.2 * s, 0.05 * std::sin(3.0 * s)),
                  Eigen::Quaterniond(std::cos(0.5 * yaw), 0.0, 0.0, std::sin(0.5 * yaw))};
}

/// One integrator on one device backend, as raymapd wires it.
struct IntegratorRig {
  IntegratorRig(gpu::Planning planning, Semantics semantics)
      : map(makeMap(config(semantics))), mailbox(4, 4096), poses(1024), arrivals(64) {
    map.setWindowCentre({0.0, 0.0, 0.0});
    DeviceBackendOptions options;
    options.planning = planning;
    backend = createDeviceBackendAsGiven(map, options);
    if (!backend) {
      return;
    }
    pipeline::IntegratorSettings settings;
    settings.batch_rays = 4096;
    settings.batch_deadline_ns = 5 * kIntegratorMs;
    settings.pose_wait_ns = 50 * kIntegratorMs;
    settings.pose_hold_ns = 20 * kIntegratorMs;
    settings.pose_history = 256;
    settings.clock_ns = &stillClock;
    pipeline::SensorSettings sensor;
    sensor.extrinsic = io::Pose{Eigen::Vector3d(0.1, 0.0, 0.5), Eigen::Quaterniond::Identity()};
    sensor.filter.min_range_m = 0.4;
    sensor.filter.max_range_m = 6.0;
    integrator.emplace(map, *backend, mutex, mailbox, poses, arrivals, latest, settings,
                       std::vector<pipeline::SensorSettings>{sensor}, stats);
  }
  static MapConfig config(Semantics semantics) {
    MapConfig c;
    c.geometry.resolution = 0.1;
    c.geometry.region_voxels = 16;
    c.policy = StorePolicy::kRolling;
    c.window_regions = {8, 8, 3};
    c.semantics = semantics;
    return c;
  }
  void pushPose(std::int64_t stamp_ns) { pushBasePose(poses, stamp_ns, basePoseAt(stamp_ns)); }
  void pushExtrinsic(const io::Pose& sensor_in_base) {
    pushSensorExtrinsic(poses, 0, sensor_in_base);
  }
  void publishScan(std::int64_t stamp_ns, const std::vector<msgs::ScanPoint>& points) {
    test::publishScan(mailbox, stamp_ns, points, 0, kIntegratorNow);
  }

  VoxelMap map;
  std::unique_ptr<Backend> backend;
  platform::PiMutex mutex;
  pipeline::ScanMailbox mailbox;
  pipeline::PoseQueue poses;
  pipeline::ArrivalQueue arrivals;
  pipeline::LatestPosition latest;
  pipeline::PipelineStats stats;
  std::optional<pipeline::Integrator> integrator;
};

/// A 0.1 s sweep of `count` points with times across it, ranges 0.2-5 m.
std::vector<msgs::ScanPoint> sweep(std::mt19937_64& rng, int count) {
  std::uniform_real_distribution<double> elevation(-0.3, 0.3);
  std::uniform_real_distribution<double> range(0.2, 5.0);
  std::vector<msgs::ScanPoint> points;
  for (int i = 0; i < count; ++i) {
    const double azimuth = 2.0 * 3.14159265358979 * i / count;
    const double e = elevation(rng);
    const double r = range(rng);
    msgs::ScanPoint p{static_cast<float>(r * std::cos(azimuth) * std::cos(e)),
                      static_cast<float>(r * std::sin(azimuth) * std::cos(e)),
                      static_cast<float>(r * std::sin(e)),
                      static_cast<float>(0.1 * i / count),
                      1.0f,
                      0u};
    if (i % 29 == 0) {
      p.flags = msgs::kPointFreeOnly;
    }
    if (i % 97 == 0) {
      p.flags = msgs::kPointNoReturn;
    }
    points.push_back(p);
  }
  return points;
}

TEST(DeviceIntegrator, PointsDeskewedOnTheDeviceGiveTheHostsMapAndCounts) {
  REQUIRE_DEVICE_PREPARATION();
  for (const Semantics semantics : {Semantics::kPerRay, Semantics::kPerScan}) {
    const char* label = semantics == Semantics::kPerRay ? "per ray" : "per scan";
    IntegratorRig host(gpu::Planning::kHost, semantics);
    IntegratorRig device(gpu::Planning::kDevice, semantics);
    ASSERT_TRUE(host.integrator && device.integrator) << label;
    ASSERT_FALSE(host.backend->preparesOnDevice(RayFilter{})) << label;
    std::mt19937_64 rng(5);
    constexpr std::int64_t kPoseStep = 10 * kIntegratorMs;
    std::int64_t next_pose = 0;
    for (int scan = 0; scan < 12; ++scan) {
      const std::int64_t stamp = 1000 * kIntegratorMs + scan * 100 * kIntegratorMs;
      // Poses up to the middle of the scan now, the rest while it waits (held or interpolated).
      for (; next_pose <= stamp + 60 * kIntegratorMs; next_pose += kPoseStep) {
        host.pushPose(next_pose);
        device.pushPose(next_pose);
      }
      if (scan == 6) {
        const io::Pose turned{Eigen::Vector3d(0.0, 0.1, 0.6),
                              Eigen::Quaterniond(std::cos(0.3), 0.0, std::sin(0.3), 0.0)};
        host.pushExtrinsic(turned);
        device.pushExtrinsic(turned);
      }
      const std::vector<msgs::ScanPoint> points = sweep(rng, 3000);
      host.publishScan(stamp, points);
      device.publishScan(stamp, points);
      (void)host.integrator->step(kIntegratorNow);
      (void)device.integrator->step(kIntegratorNow);
      for (; next_pose <= stamp + 130 * kIntegratorMs; next_pose += kPoseStep) {
        host.pushPose(next_pose);
        device.pushPose(next_pose);
      }
      (void)host.integrator->step(kIntegratorNow);
      (void)device.integrator->step(kIntegratorNow);
    }
    host.integrator->flush(kIntegratorNow);
    device.integrator->flush(kIntegratorNow);
    ASSERT_TRUE(host.backend->synchronise()) << label;
    ASSERT_TRUE(device.backend->synchronise()) << label;
    EXPECT_EQ(device.stats.scans_integrated.get(), host.stats.scans_integrated.get()) << label;
    EXPECT_GT(host.stats.scans_integrated.get(), 10u) << label;
    EXPECT_EQ(device.stats.rays_integrated.get(), host.stats.rays_integrated.get()) << label;
    EXPECT_EQ(device.stats.rays_rejected.get(), host.stats.rays_rejected.get()) << label;
    EXPECT_GT(host.stats.rays_rejected.get(), 0u) << label;
    EXPECT_EQ(device.stats.points_no_return.get(), host.stats.points_no_return.get()) << label;
    EXPECT_EQ(device.stats.scans_no_pose.get(), host.stats.scans_no_pose.get()) << label;
    EXPECT_GT(device.backend->stats().points_deskewed_on_device, 30000u) << label;
    EXPECT_EQ(host.backend->stats().points_deskewed_on_device, 0u) << label;
    if (mapsAgreeBitForBit(host.map, *host.backend)) {
      EXPECT_EQ(differingRegions(host.map, device.map), 0u) << label;
    }
  }
}

}  // namespace
}  // namespace raymap::test
