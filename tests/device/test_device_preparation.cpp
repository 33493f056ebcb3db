// SPDX-License-Identifier: BSD-3-Clause
// Ray preparation on the device against the host's, its oracle: two device backends on two equal
// maps, one planning on the host (the host prepares every ray) and one planning and preparing on
// the device, each fed through its own RayBatcher the same rays in the same add() calls. Every
// counter of the preparation (rejections by reason, clipped, no-return, accepted), the rays the
// batcher integrated and the maps must be the same; the device side must really have prepared
// (RayBatcher's device batches, BackendStats::rays_prepared_on_device). Written once; linked into
// one executable per GPU API.
#include <algorithm>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "src/device/staging/staged_backend.hpp"
#include "src/map/ray_batcher.hpp"
#include "src/map/ray_preparer.hpp"
#include "tests/device/device_map_compare.hpp"
#include "tests/device/device_under_test.hpp"
#include "tests/support/test_rays.hpp"

namespace raymap::test {
namespace {

using test::makeRay;

/// One map, its backend, batcher and preparer.
struct PreparationSide {
  PreparationSide(const MapConfig& config, DeviceBackendOptions options, const RayFilter& filter,
                  std::size_t batch_rays)
      : map(makeMap(config)), preparer(map, filter) {
    backend = createDeviceBackendAsGiven(map, options);
    if (backend) {
      batcher.emplace(map, *backend, batch_rays);
    }
  }
  VoxelMap map;
  RayPreparer preparer;
  std::unique_ptr<Backend> backend;
  std::optional<RayBatcher> batcher;
};

/// The host-prepared reference and the device-prepared side.
struct PreparationPair {
  PreparationPair(const MapConfig& config, const RayFilter& filter = {},
                  std::size_t batch_rays = 4096, DeviceMemory memory = DeviceMemory::kCache)
      : host(config, options(gpu::Planning::kHost, memory), filter, batch_rays),
        device(config, options(gpu::Planning::kDevice, memory), filter, batch_rays) {}

  static DeviceBackendOptions options(gpu::Planning planning, DeviceMemory memory) {
    DeviceBackendOptions o;
    o.memory = memory;
    o.planning = planning;
    return o;
  }
  bool ready() const { return host.backend && device.backend; }

  /// The same rays into both, in add() calls of `calls` rays.
  void add(const std::vector<Ray>& rays, std::size_t calls = 1500) {
    for (std::size_t begin = 0; begin < rays.size(); begin += calls) {
      const std::span<const Ray> part =
          std::span<const Ray>(rays).subspan(begin, std::min(calls, rays.size() - begin));
      EXPECT_TRUE(host.batcher->add(host.preparer, part));
      EXPECT_TRUE(device.batcher->add(device.preparer, part));
    }
  }

  /// Flushes both and compares; returns the device side's batches prepared on the device.
  std::uint64_t expectSame(const std::string& label) {
    EXPECT_TRUE(host.batcher->flush()) << label;
    EXPECT_TRUE(device.batcher->flush()) << label;
    EXPECT_TRUE(host.backend->synchronise()) << label;
    EXPECT_TRUE(device.backend->synchronise()) << label;
    const RayCounters& h = host.preparer.counters();
    const RayCounters& d = device.preparer.counters();
    EXPECT_EQ(d.rays_in, h.rays_in) << label;
    EXPECT_EQ(d.rays_invalid, h.rays_invalid) << label;
    EXPECT_EQ(d.rays_too_short, h.rays_too_short) << label;
    EXPECT_EQ(d.rays_out_of_bounds, h.rays_out_of_bounds) << label;
    EXPECT_EQ(d.rays_outside_window, h.rays_outside_window) << label;
    EXPECT_EQ(d.rays_clipped, h.rays_clipped) << label;
    EXPECT_EQ(d.rays_no_return, h.rays_no_return) << label;
    EXPECT_EQ(d.rays_accepted, h.rays_accepted) << label;
    EXPECT_EQ(d.pieces_out, h.pieces_out) << label;
    EXPECT_EQ(device.batcher->counters().rays_integrated, host.batcher->counters().rays_integrated)
        << label;
    EXPECT_EQ(device.batcher->counters().scans_split, host.batcher->counters().scans_split)
        << label;
    EXPECT_EQ(device.backend->stats().rays, host.backend->stats().rays) << label;
    EXPECT_EQ(host.batcher->counters().device_batches, 0u) << label;
    EXPECT_GT(host.map.store().size(), 0u) << label;
    if (mapsAgreeBitForBit(host.map, *host.backend)) {
      EXPECT_EQ(differingRegions(host.map, device.map), 0u) << label;
    }
    return device.batcher->counters().device_batches;
  }

  PreparationSide host;
  PreparationSide device;
};

/// Random scans with every kind of ray the preparation rejects or changes mixed in.
std::vector<Ray> hostilePreparationRays(std::uint64_t seed, int scans) {
  std::vector<Ray> rays = randomScans(seed, scans, 3000);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<std::size_t> at(0, rays.size() - 1);
  for (int k = 0; k < 40; ++k) {
    Ray& r = rays[at(rng)];
    switch (k % 5) {
      case 0:
        r.origin.x = nan;  // invalid
        break;
      case 1:
        r.sample.z = inf;  // invalid
        break;
      case 2:
        r.sample = r.origin + Vec3d{0.05, 0.0, 0.01};  // shorter than min range
        break;
      case 3:
        r.origin = Vec3d{3.0e11, 1.0, 1.0};  // beyond the map's key range
        r.sample = r.origin + Vec3d{2.0, 0.5, 0.0};
        break;
      default:
        r.sample = r.origin + Vec3d{0.0, 0.0, 0.0};  // zero length: too short
        break;
    }
  }
  return rays;
}

RayFilter preparationRangeFilter() {
  RayFilter f;
  f.min_range_m = 0.3;
  f.max_range_m = 7.0;
  return f;
}

TEST(DevicePreparation, HostileRaysAreCountedAndIntegratedAsTheHostDoes) {
  REQUIRE_DEVICE_PREPARATION();
  for (const bool reverse : {false, true}) {
    RayFilter filter = preparationRangeFilter();
    filter.reverse = reverse;
    PreparationPair pair(smallConfig(Semantics::kPerRay), filter);
    ASSERT_TRUE(pair.ready());
    pair.add(hostilePreparationRays(11, 6));
    const std::string label = reverse ? "reverse" : "forward";
    EXPECT_GT(pair.expectSame(label), 0u) << label;
    const RayCounters& c = pair.device.preparer.counters();
    EXPECT_GT(c.rays_invalid, 0u);
    EXPECT_GT(c.rays_too_short, 0u);
    EXPECT_GT(c.rays_out_of_bounds, 0u);
    EXPECT_GT(c.rays_clipped, 0u);
    EXPECT_GT(c.rays_no_return, 0u);
    EXPECT_GT(pair.device.backend->stats().rays_prepared_on_device, 0u);
  }
}

// raymapd's integrator gathers its batch in the batcher's staging room and integrates it in
// slices (RayBatcher::integrateStaged): the device takes the staged rays in place, and the map
// and every counter are those of add() and flush() of the same slices on the host's side.
TEST(DevicePreparation, StagedSlicesGoToTheDeviceInPlaceAsAddAndFlushWould) {
  REQUIRE_DEVICE_PREPARATION();
  PreparationPair pair(smallConfig(Semantics::kPerRay), preparationRangeFilter());
  ASSERT_TRUE(pair.ready());
  const std::vector<Ray> rays = hostilePreparationRays(23, 6);
  const std::span<Ray> room = pair.device.batcher->staging();
  ASSERT_EQ(room.size(), pair.device.batcher->capacity());
  for (std::size_t begin = 0; begin < rays.size(); begin += room.size()) {
    const std::size_t n = std::min(room.size(), rays.size() - begin);
    std::copy_n(rays.begin() + static_cast<std::ptrdiff_t>(begin), n, room.begin());
    for (std::size_t done = 0; done < n; done += 1000) {  // slices, as under the map lock
      const std::size_t slice = std::min<std::size_t>(1000, n - done);
      EXPECT_TRUE(pair.host.batcher->add(pair.host.preparer,
                                         std::span<const Ray>(rays).subspan(begin + done, slice)));
      EXPECT_TRUE(pair.host.batcher->flush());
      EXPECT_TRUE(pair.device.batcher->integrateStaged(pair.device.preparer, done, slice));
      EXPECT_EQ(pair.device.batcher->pending(), 0u);  // nothing kept: the room is the batch
    }
  }
  EXPECT_GT(pair.expectSame("staged"), 0u);
  EXPECT_GT(pair.device.backend->stats().rays_prepared_on_device, 0u);
}

TEST(DevicePreparation, EveryMapModeButNdtPreparesOnTheDeviceAlike) {
  REQUIRE_DEVICE_PREPARATION();
  struct Case {
    const char* name;
    MapConfig config;
    bool on_device;
  };
  MapConfig base = smallConfig(Semantics::kPerRay);
  base.memory_budget_bytes = std::uint64_t{2} << 30;  // NDT regions are large
  MapConfig ndt = base;
  ndt.mode = MapMode::kNdtOm;
  const Case cases[] = {
      {"occupancy per ray", smallConfig(Semantics::kPerRay), true},
      {"occupancy per scan", smallConfig(Semantics::kPerScan), true},
      {"occupancy+decay per scan", decayConfig(Semantics::kPerScan), true},
      {"decay", base.forDecay(), true},
      {"tsdf", base.forTsdf(), true},
      // NDT batches end where the host's prepared rays fill them: the host prepares.
      {"ndt-om", ndt, false},
  };
  for (const Case& c : cases) {
    PreparationPair pair(c.config, preparationRangeFilter());
    ASSERT_TRUE(pair.ready()) << c.name;
    ASSERT_GT(pair.host.map.store().capacity(), 0u) << c.name;
    pair.add(hostilePreparationRays(21, 4));
    const std::uint64_t device_batches = pair.expectSame(c.name);
    EXPECT_EQ(device_batches > 0u, c.on_device) << c.name;
  }
}

TEST(DevicePreparation, RaysOutsideAMovingRollingWindowAreRejectedAndClippedAlike) {
  REQUIRE_DEVICE_PREPARATION();
  MapConfig config = smallConfig(Semantics::kPerRay);
  config.policy = StorePolicy::kRolling;
  config.window_regions = {6, 6, 3};
  PreparationPair pair(config);
  ASSERT_TRUE(pair.ready());
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int step = 0; step < 5; ++step) {
    const Vec3d robot{0.7 * step, 0.1 * step, 0.3};
    // As raymapd does: nothing waits in a batch while the window moves (RayBatcher's note).
    EXPECT_TRUE(pair.host.batcher->flush());
    EXPECT_TRUE(pair.device.batcher->flush());
    pair.host.map.setWindowCentre(robot);
    pair.device.map.setWindowCentre(robot);
    std::vector<Ray> rays;
    for (int i = 0; i < 2500; ++i) {
      Vec3d d{u(rng), u(rng), u(rng) * 0.3};
      d = d * (6.0 / d.norm());
      rays.push_back(makeRay(robot, robot + d));
      // A ray far outside the window, which misses it.
      rays.push_back(makeRay(robot + Vec3d{40.0, 40.0, 0.0}, robot + Vec3d{44.0, 41.0, 0.0}));
    }
    pair.add(rays, 700);
  }
  EXPECT_GT(pair.expectSame("rolling"), 0u);
  EXPECT_GT(pair.device.preparer.counters().rays_outside_window, 1000u);
  EXPECT_GT(pair.device.preparer.counters().rays_clipped, 1000u);
}

TEST(DevicePreparation, AScanLargerThanThePerScanBatchIsPreparedOnTheHost) {
  REQUIRE_DEVICE_PREPARATION();
  // Per-scan batches of 2000 rays: the host integrates a 5000-ray scan in parts cut where its
  // prepared rays fill a batch, which only preparing tells, so that scan goes the host's way;
  // the scans that fit go to the device whole.
  PreparationPair pair(smallConfig(Semantics::kPerScan), preparationRangeFilter(), 2000);
  ASSERT_TRUE(pair.ready());
  pair.add(randomScans(31, 1, 5000), 1200);
  pair.add(hostilePreparationRays(32, 3) /* 3000-ray scans: also too large */, 900);
  pair.add(randomScans(33, 4, 1500), 1000);
  EXPECT_GT(pair.expectSame("per scan"), 0u);
  EXPECT_GT(pair.host.batcher->counters().scans_split, 0u);
}

TEST(DevicePreparation, ABatchTheDeviceCannotPlanIsPreparedAndPlannedOnTheHost) {
  REQUIRE_DEVICE_PREPARATION();
  // A ray 1.5 km from the batch's first ray is out of reach of the relative region keys: the
  // host prepares and plans the rest of that call, and counts every ray once.
  std::vector<Ray> rays = randomScans(41, 1, 2500);
  rays.push_back(makeRay({1500.0, -20.0, 3.0}, {1502.5, -19.0, 2.0}));
  PreparationPair pair(smallConfig(Semantics::kPerRay), preparationRangeFilter());
  ASSERT_TRUE(pair.ready());
  pair.add(rays, rays.size());
  pair.add(hostilePreparationRays(42, 2));
  EXPECT_GT(pair.expectSame("far ray"), 0u);
  EXPECT_GT(pair.device.backend->stats().plans_on_host, 0u);
}

TEST(DevicePreparation, SegmentedRaysArePreparedOnTheHost) {
  REQUIRE_DEVICE_PREPARATION();
  RayFilter filter = preparationRangeFilter();
  filter.segment_length_m = 1.0;  // pieces per ray are known only after preparing
  PreparationPair pair(smallConfig(Semantics::kPerRay), filter);
  ASSERT_TRUE(pair.ready());
  EXPECT_FALSE(pair.device.backend->preparesOnDevice(filter));
  pair.add(hostilePreparationRays(51, 2));
  EXPECT_EQ(pair.expectSame("segmented"), 0u);
}

TEST(DevicePreparation, TheOptionTurnsItOff) {
  REQUIRE_DEVICE_PREPARATION();
  VoxelMap map = makeMap(smallConfig(Semantics::kPerRay));
  DeviceBackendOptions options;
  options.planning = gpu::Planning::kDevice;
  options.prepare_on_device = false;
  auto backend = createDeviceBackendAsGiven(map, options);
  ASSERT_TRUE(backend);
  EXPECT_FALSE(backend->preparesOnDevice(RayFilter{}));
  options.prepare_on_device = true;
  VoxelMap map2 = makeMap(smallConfig(Semantics::kPerRay));
  auto preparing = createDeviceBackendAsGiven(map2, options);
  ASSERT_TRUE(preparing);
  EXPECT_TRUE(preparing->preparesOnDevice(RayFilter{}));
  EXPECT_NE(preparing->deviceName().find("rays prepared on the device"), std::string::npos);
}

/// Scans of points from a sensor moving and turning on a base, with per-point times, and the
/// tables that deskew them: each scan a segment with its own copy of the samples covering it.
struct PointScans {
  std::vector<rm_scan_point> points;
  std::vector<rm_pose_sample> poses;
  std::vector<rm_deskew_segment> segments;
  std::vector<std::uint64_t> scans;
  DeskewTables tables() const { return DeskewTables{poses, segments, scans}; }
};

PointScans pointScans(std::uint64_t seed, int scans, int points_per_scan) {
  constexpr std::int64_t kScanNs = 100'000'000;
  constexpr std::int64_t kPoseNs = 10'000'000;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_real_distribution<double> range(0.2, 9.0);
  std::uniform_int_distribution<std::int64_t> offset(0, kScanNs);
  auto base = [](std::int64_t t) {
    const double s = static_cast<double>(t) * 1e-9;
    const double yaw = 0.4 * s;
    return rm_pose{rm_vec3d{1.5 * s, 0.3 * s, 0.2 * std::sin(s)},
                   rm_quat{std::cos(0.5 * yaw), 0.0, 0.0, std::sin(0.5 * yaw)}};
  };
  const rm_pose extrinsic{rm_vec3d{0.2, 0.0, 0.4},
                          rm_quat{std::sqrt(0.5), 0.0, 0.0, std::sqrt(0.5)}};
  PointScans out;
  for (int s = 0; s < scans; ++s) {
    const std::int64_t start = s * kScanNs;
    rm_deskew_segment segment{extrinsic, static_cast<rm_u32>(out.poses.size()), 0};
    for (std::int64_t t = start - kPoseNs; t <= start + kScanNs + kPoseNs; t += kPoseNs) {
      out.poses.push_back(rm_pose_sample{t, 0, base(t)});
      ++segment.poses;
    }
    out.segments.push_back(segment);
    out.scans.push_back(100 + static_cast<std::uint64_t>(s));
    for (int i = 0; i < points_per_scan; ++i) {
      rm_vec3d d{u(rng), u(rng), 0.3 * u(rng)};
      const double scale = range(rng) / rm_vec3d_norm(d);
      rm_scan_point p{static_cast<float>(d.x * scale),
                      static_cast<float>(d.y * scale),
                      static_cast<float>(d.z * scale),
                      1.0f,
                      0u,
                      static_cast<rm_u32>(s),
                      start + offset(rng)};
      if (i % 17 == 0) {
        p.flags = RM_RAW_RAY_NO_RETURN;
      }
      if (i % 101 == 0) {
        p.x = std::numeric_limits<float>::quiet_NaN();  // invalid
      }
      if (i % 103 == 0) {
        p.x = 0.01f;  // shorter than min range
        p.y = 0.0f;
        p.z = 0.0f;
      }
      out.points.push_back(p);
    }
  }
  return out;
}

/// The host's reference: the rays deskewedRay() makes of points [from, to), added and flushed
/// (what RayBatcher::integratePoints() is defined to equal).
void addDeskewedOnHost(PreparationSide& side, const PointScans& scans, std::size_t from = 0,
                       std::size_t to = std::numeric_limits<std::size_t>::max()) {
  std::vector<Ray> rays;
  for (std::size_t i = from; i < std::min(to, scans.points.size()); ++i) {
    rays.push_back(deskewedRay(scans.points[i], scans.tables()));
  }
  EXPECT_TRUE(side.batcher->add(side.preparer, rays));
  EXPECT_TRUE(side.batcher->flush());
}

TEST(DeviceDeskewing, PointsDeskewedOnTheDeviceMapAndCountAsTheHostsRays) {
  REQUIRE_DEVICE_PREPARATION();
  for (const Semantics semantics : {Semantics::kPerRay, Semantics::kPerScan}) {
    const std::string label = semantics == Semantics::kPerRay ? "per ray" : "per scan";
    PreparationPair pair(smallConfig(semantics), preparationRangeFilter(), 4096);
    ASSERT_TRUE(pair.ready()) << label;
    const PointScans scans = pointScans(61, 5, 3000);
    addDeskewedOnHost(pair.host, scans, 0, 7500);
    addDeskewedOnHost(pair.host, scans, 7500);
    // In calls of two and a half scans: runs of one scan each go to the device.
    const std::span<const rm_scan_point> all(scans.points);
    EXPECT_TRUE(pair.device.batcher->integratePoints(pair.device.preparer, all.first(7500),
                                                     scans.tables()));
    EXPECT_TRUE(pair.device.batcher->integratePoints(pair.device.preparer, all.subspan(7500),
                                                     scans.tables()));
    EXPECT_GT(pair.expectSame(label), 0u) << label;
    EXPECT_EQ(pair.device.batcher->counters().points_deskewed_on_device, scans.points.size())
        << label;
    EXPECT_GT(pair.device.preparer.counters().rays_invalid, 0u) << label;
    EXPECT_GT(pair.device.preparer.counters().rays_no_return, 0u) << label;
  }
}

TEST(DeviceDeskewing, TablesBeyondTheDevicesLimitsAreDeskewedOnTheHostAlike) {
  REQUIRE_DEVICE_PREPARATION();
  PreparationPair pair(smallConfig(Semantics::kPerRay), preparationRangeFilter());
  ASSERT_TRUE(pair.ready());
  PointScans scans = pointScans(71, 2, 2000);
  // More segments than a device batch takes: the same two scans' segments repeated.
  while (scans.segments.size() <= gpu::kMaxSegments) {
    scans.segments.push_back(scans.segments[0]);
    scans.scans.push_back(scans.scans[0]);
  }
  addDeskewedOnHost(pair.host, scans);
  EXPECT_TRUE(
      pair.device.batcher->integratePoints(pair.device.preparer, scans.points, scans.tables()));
  pair.expectSame("too many segments");
  EXPECT_EQ(pair.device.batcher->counters().points_deskewed_on_device, 0u);
}

}  // namespace
}  // namespace raymap::test
