// SPDX-License-Identifier: BSD-3-Clause
// Ray preparation on the device against the host's, its oracle: two device backends on two equal
// maps, one planning on the host (the host prepares every ray) and one planning and preparing on
// the device, each fed through its own RayBatcher the same rays in the same add() calls. Every
// counter of the preparation (rejections by reason, clipped, no-return, accepted), the rays the
// batcher integrated and the maps must be the same; the device side must really have prepared
// (RayBatcher's device batches, BackendStats::rays_prepared_on_device). Written once; linked into
// one executable per GPU API.
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

/// Whether the device under test prepares rays (double precision: every CUDA device, OpenCL
/// devices with cl_khr_fp64 such as PoCL's).
bool devicePreparesRays() {
  VoxelMap map = makeMap(smallConfig(Semantics::kPerRay));
  DeviceBackendOptions options;
  options.planning = gpu::Planning::kDevice;
  auto backend = createDeviceBackendAsGiven(map, options);
  return backend && backend->preparesOnDevice(RayFilter{});
}

#define REQUIRE_DEVICE_PREPARATION()                                         \
  REQUIRE_DEVICE();                                                          \
  if (!devicePreparesRays()) {                                               \
    GTEST_SKIP() << "the device has no double precision: the host prepares"; \
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

}  // namespace
}  // namespace raymap::test
