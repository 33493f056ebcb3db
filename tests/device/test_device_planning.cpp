// SPDX-License-Identifier: BSD-3-Clause
// Planning on the device against the host planner, its oracle: two backends on two equal maps,
// one planning each batch on the host and one on the device, fed the same rays; every batch's
// plan (span records in order, grouped records and runs, hit groups with their rays), the
// counters and the maps must be the same. Written once; linked into one executable per GPU API.
#include <cstring>
#include <map>
#include <random>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "src/device/staging/staged_backend.hpp"
#include "tests/device/device_map_compare.hpp"
#include "tests/device/device_under_test.hpp"
#include "tests/support/test_rays.hpp"

namespace raymap::test {
namespace {

using test::makeRay;

/// One batch as the integration kernels get it, in comparable form.
struct RecordedPlan {
  gpu::Planning where = gpu::Planning::kHost;
  std::vector<PreparedRay> rays;
  std::vector<rm_span_record> spans;
  std::vector<rm_span_record> region_spans;
  std::vector<rm_span_run> runs;
  /// (slot, voxel) -> rays of its samples, in list order. The device lists groups in another
  /// order than the host (by region table entry, not by slot); each group's rays are in ray order.
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::vector<std::uint32_t>> groups;
};

class PlanRecorder final : public gpu::PlanObserver {
 public:
  void planned(const gpu::BatchArrays& b, gpu::Planning where) override {
    RecordedPlan p;
    p.where = where;
    p.rays.assign(b.rays.begin(), b.rays.end());
    p.spans.assign(b.spans.begin(), b.spans.end());
    p.region_spans.assign(b.region_spans.begin(), b.region_spans.end());
    p.runs.assign(b.span_runs.begin(), b.span_runs.end());
    for (const rm_hit_group& g : b.groups) {
      auto& rays = p.groups[{g.slot, g.index}];
      EXPECT_TRUE(rays.empty()) << "two hit groups for slot " << g.slot << " voxel " << g.index;
      rays.assign(b.hit_rays.begin() + g.first, b.hit_rays.begin() + g.first + g.count);
    }
    plans.push_back(std::move(p));
  }
  std::vector<RecordedPlan> plans;
};

bool sameBytes(const void* a, const void* b, std::size_t bytes) {
  return bytes == 0 || std::memcmp(a, b, bytes) == 0;
}

/// The first difference between two plans of the same batch, or "".
std::string difference(const RecordedPlan& host, const RecordedPlan& device) {
  if (host.rays.size() != device.rays.size() ||
      !sameBytes(host.rays.data(), device.rays.data(), host.rays.size() * sizeof(PreparedRay))) {
    return "rays differ (" + std::to_string(host.rays.size()) + " on the host, " +
           std::to_string(device.rays.size()) + " on the device)";
  }
  if (host.spans.size() != device.spans.size()) {
    return "span records: " + std::to_string(host.spans.size()) + " on the host, " +
           std::to_string(device.spans.size()) + " on the device";
  }
  for (std::size_t i = 0; i < host.spans.size(); ++i) {
    if (!sameBytes(&host.spans[i], &device.spans[i], sizeof(rm_span_record))) {
      const rm_span_record& h = host.spans[i];
      const rm_span_record& d = device.spans[i];
      return "span record " + std::to_string(i) + ": host (ray " + std::to_string(h.ray) +
             ", slot " + std::to_string(h.slot) + ", flags " + std::to_string(h.flags) +
             "), device (ray " + std::to_string(d.ray) + ", slot " + std::to_string(d.slot) +
             ", flags " + std::to_string(d.flags) + ")";
    }
  }
  if (host.region_spans.size() != device.region_spans.size() ||
      !sameBytes(host.region_spans.data(), device.region_spans.data(),
                 host.region_spans.size() * sizeof(rm_span_record))) {
    return "span records grouped by region differ";
  }
  if (host.runs.size() != device.runs.size() ||
      !sameBytes(host.runs.data(), device.runs.data(), host.runs.size() * sizeof(rm_span_run))) {
    return "runs of span records differ";
  }
  if (host.groups != device.groups) {
    return "hit groups differ (" + std::to_string(host.groups.size()) + " on the host, " +
           std::to_string(device.groups.size()) + " on the device)";
  }
  return {};
}

gpu::StagedBackend& staged(Backend& backend) {
  auto* s = dynamic_cast<gpu::StagedBackend*>(&backend);
  EXPECT_NE(s, nullptr);
  return *s;
}

/// A host-planned and a device-planned backend on equal maps, each recording its plans.
struct Pair {
  Pair(const MapConfig& config, DeviceBackendOptions options)
      : host_map(makeMap(config)), device_map(makeMap(config)) {
    options.planning = gpu::Planning::kHost;
    host = createDeviceBackendAsGiven(host_map, options);
    options.planning = gpu::Planning::kDevice;
    device = createDeviceBackendAsGiven(device_map, options);
    if (host && device) {
      staged(*host).observePlans(&host_plans);
      staged(*device).observePlans(&device_plans);
      EXPECT_EQ(staged(*device).planning(), gpu::Planning::kDevice);
    }
  }
  ~Pair() {
    if (host && device) {
      staged(*host).observePlans(nullptr);
      staged(*device).observePlans(nullptr);
    }
  }
  Pair(const Pair&) = delete;
  Pair& operator=(const Pair&) = delete;

  void integrate(const std::vector<Ray>& rays, const RayFilter& filter = {}) {
    test::integrate(host_map, *host, rays, filter);
    test::integrate(device_map, *device, rays, filter);
  }

  /// Compares every plan, the counters and (after synchronising) the maps; returns the batches
  /// the device planned.
  std::size_t expectSame(const std::string& label) {
    EXPECT_TRUE(host->synchronise()) << label;
    EXPECT_TRUE(device->synchronise()) << label;
    EXPECT_EQ(host_plans.plans.size(), device_plans.plans.size()) << label;
    std::size_t on_device = 0;
    for (std::size_t b = 0; b < std::min(host_plans.plans.size(), device_plans.plans.size()); ++b) {
      EXPECT_EQ(host_plans.plans[b].where, gpu::Planning::kHost);
      on_device += device_plans.plans[b].where == gpu::Planning::kDevice ? 1u : 0u;
      const std::string diff = difference(host_plans.plans[b], device_plans.plans[b]);
      EXPECT_EQ(diff, "") << label << ", batch " << b << " (planned on the "
                          << gpu::toString(device_plans.plans[b].where) << ")";
      if (!diff.empty()) {
        break;
      }
    }
    const BackendStats h = host->stats();
    const BackendStats d = device->stats();
    EXPECT_EQ(d.rays, h.rays) << label;
    EXPECT_EQ(d.voxels_visited, h.voxels_visited) << label;
    EXPECT_EQ(d.spans_outside_window, h.spans_outside_window) << label;
    EXPECT_EQ(d.rays_skipped, h.rays_skipped) << label;
    EXPECT_EQ(d.cache_hits, h.cache_hits) << label;
    EXPECT_EQ(d.cache_misses, h.cache_misses) << label;
    EXPECT_EQ(d.cache_evictions, h.cache_evictions) << label;
    EXPECT_EQ(d.region_bytes_to_device, h.region_bytes_to_device) << label;
    EXPECT_EQ(d.region_bytes_from_device, h.region_bytes_from_device) << label;
    EXPECT_EQ(d.plans_on_host, device_plans.plans.size() - on_device) << label;
    EXPECT_EQ(h.plans_on_host, 0u) << label;
    // Bit for bit, every layer of every region: the same plans on the same kernels.
    EXPECT_GT(host_map.store().size(), 0u) << label;
    EXPECT_EQ(host_map.store().size(), device_map.store().size()) << label;
    if (mapsAgreeBitForBit(host_map, *host)) {
      EXPECT_EQ(differingRegions(host_map, device_map), 0u) << label;
    }
    return on_device;
  }

  VoxelMap host_map;
  VoxelMap device_map;
  std::unique_ptr<Backend> host;
  std::unique_ptr<Backend> device;
  PlanRecorder host_plans;
  PlanRecorder device_plans;
};

DeviceBackendOptions cacheOptions() {
  DeviceBackendOptions options;
  options.memory = DeviceMemory::kCache;
  return options;
}

TEST(DevicePlanning, EqualsTheHostPlanSpanForSpanInEverySemanticsAndDirection) {
  REQUIRE_DEVICE();
  const std::vector<Ray> rays = randomScans(5489, 4, 4000);
  for (const Semantics semantics : {Semantics::kPerRay, Semantics::kPerScan}) {
    for (const bool reverse : {false, true}) {
      const std::string label =
          std::string(toString(semantics)) + (reverse ? ", reverse" : ", forward");
      DeviceBackendOptions options = cacheOptions();
      options.per_ray_batch_rays = 1500;  // several batches a call, with pipelined plans
      Pair pair(smallConfig(semantics), options);
      ASSERT_TRUE(pair.host && pair.device);
      RayFilter filter;
      filter.reverse = reverse;
      filter.max_range_m = 9.0;
      pair.integrate(rays, filter);
      pair.integrate(randomScans(99, 2, 3000), filter);
      EXPECT_GT(pair.expectSame(label), 3u) << label;
      EXPECT_EQ(pair.device->stats().plans_on_host, 0u) << label;
    }
  }
}

TEST(DevicePlanning, EqualsTheHostPlanForEveryMapMode) {
  REQUIRE_DEVICE();
  const std::vector<Ray> rays = randomScans(17, 3, 3000);
  std::vector<std::pair<std::string, MapConfig>> configs;
  MapConfig base = smallConfig(Semantics::kPerRay);
  base.memory_budget_bytes = std::uint64_t{2} << 30;  // NDT-TM regions are 30 KiB
  configs.emplace_back("ndt-tm", [&base] {
    MapConfig c = base;
    c.mode = MapMode::kNdtTm;
    return c;
  }());
  configs.emplace_back("tsdf", base.forTsdf());
  configs.emplace_back("decay", base.forDecay());
  configs.emplace_back("occupancy+decay", decayConfig(Semantics::kPerScan));
  for (const auto& [name, config] : configs) {
    Pair pair(config, cacheOptions());
    ASSERT_TRUE(pair.host && pair.device) << name;
    pair.integrate(rays);
    EXPECT_GT(pair.expectSame(name), 0u) << name;
  }
}

TEST(DevicePlanning, ABatchWithMoreRegionsThanTheCacheIsPlannedOnTheHostAndCutAlike) {
  REQUIRE_DEVICE();
  const std::vector<Ray> rays = randomScans(11, 2, 1500);
  for (const Semantics semantics : {Semantics::kPerRay, Semantics::kPerScan}) {
    const MapConfig config = smallConfig(semantics);
    DeviceBackendOptions options = cacheOptions();
    // 60 regions against several hundred a scan: most batches do not fit, and are cut where the
    // cache is full (on the host); later ones fit again.
    options.cache_regions = 60;
    options.batch_rays = 1000;
    options.per_ray_batch_rays = 200;
    Pair pair(config, options);
    ASSERT_TRUE(pair.host && pair.device);
    pair.integrate(rays);
    pair.expectSame(toString(semantics));
    EXPECT_GT(pair.device->stats().plans_on_host, 0u);
    EXPECT_GT(pair.device->stats().cache_evictions, 100u);
  }
}

TEST(DevicePlanning, RaysWithMoreSpansThanABatchHoldsEndTheBatchAsOnTheHost) {
  REQUIRE_DEVICE();
  // 0.8 m regions and rays of 6 to 30 m: 8 to 40 span records a ray, against a batch's 8 a ray
  // on average, so batches end at the span limit, on the device as on the host.
  std::vector<Ray> rays;
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_real_distribution<double> length(6.0, 30.0);
  for (int i = 0; i < 4000; ++i) {
    Vec3d d{u(rng), u(rng), u(rng)};
    d = d * (length(rng) / d.norm());
    rays.push_back(makeRay({0.05, 0.1, 0.15}, Vec3d{0.05, 0.1, 0.15} + d));
  }
  DeviceBackendOptions options = cacheOptions();
  options.per_ray_batch_rays = 500;
  MapConfig config = smallConfig(Semantics::kPerRay);
  config.memory_budget_bytes = std::uint64_t{2} << 30;  // tens of thousands of regions
  Pair pair(config, options);
  ASSERT_TRUE(pair.host && pair.device);
  pair.integrate(rays);
  EXPECT_GT(pair.expectSame("long rays"), 8u);  // 4000 rays in batches of fewer than 500
  EXPECT_EQ(pair.device->stats().plans_on_host, 0u);
}

TEST(DevicePlanning, RegionsOutsideAMovingRollingWindowAreSkippedAndCountedAlike) {
  REQUIRE_DEVICE();
  MapConfig config = smallConfig(Semantics::kPerRay);
  config.policy = StorePolicy::kRolling;
  config.window_regions = {6, 6, 3};
  for (const DeviceMemory memory : {DeviceMemory::kCache, DeviceMemory::kShared}) {
    if (memory == DeviceMemory::kShared && !deviceUnderTest().shares_memory()) {
      continue;
    }
    DeviceBackendOptions options;
    options.memory = memory;
    Pair pair(config, options);
    ASSERT_TRUE(pair.host && pair.device);
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (int step = 0; step < 6; ++step) {
      const Vec3d robot{0.6 * step, 0.2 * step, 0.3};
      pair.host_map.setWindowCentre(robot);
      pair.device_map.setWindowCentre(robot);
      std::vector<Ray> rays;
      for (int i = 0; i < 3000; ++i) {
        Vec3d d{u(rng), u(rng), u(rng) * 0.3};
        d = d * (4.0 / d.norm());
        rays.push_back(makeRay(robot, robot + d));
      }
      pair.integrate(rays);
    }
    const std::string label = memory == DeviceMemory::kCache ? "cache" : "shared memory";
    EXPECT_EQ(pair.expectSame(label), 6u) << label;
    EXPECT_GT(pair.device->stats().spans_outside_window, 1000u) << label;
  }
}

TEST(DevicePlanning, ABatchReachingFartherThanItsRegionKeysIsPlannedOnTheHost) {
  REQUIRE_DEVICE();
  // Relative region keys reach +-1024 regions (819 m of 0.8 m regions) from the batch's first
  // ray: a ray 1.5 km away in the same batch sends the batch to the host planner, exactly.
  std::vector<Ray> rays = randomScans(5, 1, 2000);
  rays.push_back(makeRay({1500.0, -20.0, 3.0}, {1502.5, -19.0, 2.0}));
  Pair pair(smallConfig(Semantics::kPerScan), cacheOptions());
  ASSERT_TRUE(pair.host && pair.device);
  pair.integrate(rays);
  pair.integrate(randomScans(6, 1, 2000));
  EXPECT_EQ(pair.expectSame("far ray"), 1u);  // the second scan, on the device
  EXPECT_EQ(pair.device->stats().plans_on_host, 1u);
}

TEST(DevicePlanning, AdversarialRaysPlanAlike) {
  REQUIRE_DEVICE();
  // Endpoints on faces, edges and corners of voxels and regions, axis-aligned and zero-length
  // rays: where the walks decide ties, both planners must decide them the same way.
  std::vector<Ray> rays = latticeRays(4242, 20000, 0.025, 8);
  rays.push_back(makeRay({0.3, 0.3, 0.3}, {0.3, 0.3, 0.3}));
  rays.push_back(makeRay({0.8, 0.8, 0.8}, {0.8, 0.8, -2.4}));
  for (const bool reverse : {false, true}) {
    RayFilter filter;
    filter.reverse = reverse;
    Pair pair(smallConfig(Semantics::kPerRay), cacheOptions());
    ASSERT_TRUE(pair.host && pair.device);
    pair.integrate(rays, filter);
    EXPECT_GT(pair.expectSame(reverse ? "reverse" : "forward"), 0u);
  }
}

}  // namespace
}  // namespace raymap::test
