// SPDX-License-Identifier: BSD-3-Clause
// Agreement of a device backend with the CPU reference on the shared real data: the same rays,
// resolution, range limit and probabilities give the same voxel states, log-odds within half a
// hit and the same voxel means, per ray and per scan. Written once; linked into one executable
// per GPU API (test_opencl_data, test_cuda_data). Skips without the data or the device.
#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <ostream>
#include <set>
#include <span>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "kernels/common/voxel_mean.h"
#include "src/map/backend.hpp"
#include "src/map/map_params.hpp"
#include "src/map/ray_preparer.hpp"
#include "src/map/voxel_map.hpp"
#include "tests/device/device_under_test.hpp"
#include "tests/support/shared_data.hpp"
#include "tests/support/temp_dir.hpp"
#include "tests/support/test_rays.hpp"

namespace raymap::test {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

// The settings of docs/benchmarks.md: 0.1 m voxels, rays clipped at 20 m, OctoMap's probabilities.
constexpr double kResolution = 0.1;      // metres
constexpr double kMaxRange = 20.0;       // metres
constexpr double kMinAgreement = 0.999;  // voxels with the same state, of those either observed
// Of the voxels observed in both maps with the same state: those whose log-odds differ by more
// than half a hit (per-ray updates land on the device in another order, and clamping makes the
// sum order-dependent).
constexpr double kMaxValueOutliers = 0.001;
constexpr float kMeanTolerance = 1e-4f;  // voxel units, per component of a decoded mean

MapConfig mapConfig(Semantics semantics) {
  MapConfig config;
  config.geometry.resolution = kResolution;
  config.occupancy = OccupancyParams::octomap();
  config.semantics = semantics;
  config.voxel_mean = true;
  return config;
}

/// What integrating the rays took.
struct IntegrationRun {
  RayCounters counters;
  double seconds = 0.0;  ///< preparation, integration and the final synchronise()
};

/// Integrates the rays with one integrate() call per scan (which per-scan semantics needs), then
/// synchronises.
IntegrationRun integrateByScan(VoxelMap& map, Backend& backend, std::span<const Ray> rays,
                               const RayFilter& filter) {
  RayPreparer preparer(map, filter);
  std::vector<PreparedRay> prepared;
  const Clock::time_point start = Clock::now();
  forEachScan(rays, [&](std::span<const Ray> scan) {
    prepared.resize(scan.size());  // without segmentation every ray gives at most one piece
    const RayPreparer::Progress progress = preparer.prepare(scan, prepared);
    EXPECT_EQ(progress.consumed, scan.size()) << "a scan did not fit one batch";
    auto ok = backend.integrate(std::span<const PreparedRay>(prepared.data(), progress.written));
    EXPECT_TRUE(ok.has_value()) << "integration failed: " << toString(ok.error());
  });
  auto synced = backend.synchronise();
  EXPECT_TRUE(synced.has_value()) << "synchronise failed: " << toString(synced.error());
  return {preparer.counters(), std::chrono::duration<double>(Clock::now() - start).count()};
}

/// Values and voxel means of two maps, voxel by voxel over the union of their regions.
struct ValueComparison {
  std::uint64_t same_observed = 0;   ///< observed in both, with the same state
  std::uint64_t value_outliers = 0;  ///< of those: log-odds differ by more than half a hit
  std::uint64_t with_samples = 0;    ///< voxels with a nonzero mean count in either map
  std::uint64_t count_mismatches = 0;
  std::uint64_t mean_mismatches = 0;  ///< equal nonzero counts, decoded means beyond tolerance
  float max_mean_difference = 0.0f;   ///< voxel units, over voxels with equal nonzero counts

  double outlierFraction() const {
    return same_observed ? double(value_outliers) / double(same_observed) : 0.0;
  }
};

ValueComparison compareValues(const VoxelMap& reference, const VoxelMap& map) {
  ValueComparison result;
  const float half_hit = 0.5f * map.occupancy().toKernel().hit;
  std::set<std::tuple<int, int, int>> regions;
  reference.store().forEachRegion([&](std::uint32_t, Vec3i r) { regions.insert({r.x, r.y, r.z}); });
  map.store().forEachRegion([&](std::uint32_t, Vec3i r) { regions.insert({r.x, r.y, r.z}); });
  const std::uint32_t n = map.store().voxelsPerRegion();
  for (const auto& [x, y, z] : regions) {
    for (std::uint32_t i = 0; i < n; ++i) {
      const Vec3i voxel = map.voxelAt({x, y, z}, i);
      const VoxelState state = map.state(voxel);
      if (state != VoxelState::kUnobserved && state == reference.state(voxel)) {
        ++result.same_observed;
        const float difference =
            std::fabs(map.occupancyValue(voxel) - reference.occupancyValue(voxel));
        result.value_outliers += difference > half_hit ? 1u : 0u;
      }
      const rm_voxel_mean a = reference.mean(voxel);
      const rm_voxel_mean b = map.mean(voxel);
      if (a.count == 0 && b.count == 0) {
        continue;
      }
      ++result.with_samples;
      if (a.count != b.count) {
        ++result.count_mismatches;
        continue;
      }
      const rm_vec3f ma = rm_mean_decode(a.packed, a.count);
      const rm_vec3f mb = rm_mean_decode(b.packed, b.count);
      const float difference =
          std::max({std::fabs(ma.x - mb.x), std::fabs(ma.y - mb.y), std::fabs(ma.z - mb.z)});
      result.max_mean_difference = std::max(result.max_mean_difference, difference);
      result.mean_mismatches += difference > kMeanTolerance ? 1u : 0u;
    }
  }
  return result;
}

class DeviceDataAgreement : public testing::TestWithParam<DataCase> {};

TEST_P(DeviceDataAgreement, StatesValuesAndMeansMatchTheCpuReference) {
  // Arrange
  const DataCase& param = GetParam();
  const DataFiles files = dataFiles(param.data);
  if (!files.missing.empty()) {
    GTEST_SKIP() << files.missing;
  }
  REQUIRE_DEVICE();
  const std::vector<Ray> rays = loadRays(files.file, files.trajectory);
  ASSERT_FALSE(rays.empty());
  VoxelMap reference = makeMap(mapConfig(param.semantics));
  std::unique_ptr<Backend> cpu = cpuBackend(reference, 1);
  RayFilter forward;
  forward.max_range_m = kMaxRange;
  VoxelMap map = makeMap(mapConfig(param.semantics));
  std::unique_ptr<Backend> device = createDeviceBackend(map);
  ASSERT_TRUE(device);
  RayFilter reverse = forward;
  reverse.reverse = true;  // the shipped default for device backends

  // Act
  const IntegrationRun cpu_run = integrateByScan(reference, *cpu, rays, forward);
  const IntegrationRun device_run = integrateByScan(map, *device, rays, reverse);
  const MapComparison states = compareMaps(reference, map);
  const ValueComparison values = compareValues(reference, map);
  const BackendStats stats = device->stats();
  // The CPU walking in reverse too: what remains against the forward reference are ties at voxel
  // edges and corners, where the two walk directions pick different voxels.
  VoxelMap same_walk = makeMap(mapConfig(param.semantics));
  std::unique_ptr<Backend> cpu_reverse = cpuBackend(same_walk, 2);
  (void)integrateByScan(same_walk, *cpu_reverse, rays, reverse);
  const MapComparison same_walk_states = compareMaps(same_walk, map);

  // Report (for docs/benchmarks.md).
  char line[768];
  std::snprintf(
      line, sizeof(line),
      "%s %s: rays %zu (integrated %llu); states agree %.4f %% of %llu voxels (exact values "
      "%.4f %%); values beyond half a hit %.4f %% of %llu; means %llu, count mismatches %llu, "
      "mean mismatches %llu (max %.6f voxel); same walk: %llu of %llu values exact; seconds cpu "
      "1t %.2f %s %.2f; dropped %llu, skipped %llu; device %s",
      param.data.name, toString(param.semantics), rays.size(),
      static_cast<unsigned long long>(device_run.counters.rays_accepted),
      100.0 * states.sameStateFraction(), static_cast<unsigned long long>(states.compared),
      100.0 * static_cast<double>(states.exact_value) /
          static_cast<double>(std::max<std::uint64_t>(states.compared, 1)),
      100.0 * values.outlierFraction(), static_cast<unsigned long long>(values.same_observed),
      static_cast<unsigned long long>(values.with_samples),
      static_cast<unsigned long long>(values.count_mismatches),
      static_cast<unsigned long long>(values.mean_mismatches),
      static_cast<double>(values.max_mean_difference),
      static_cast<unsigned long long>(same_walk_states.exact_value),
      static_cast<unsigned long long>(same_walk_states.compared), cpu_run.seconds,
      deviceUnderTest().api, device_run.seconds,
      static_cast<unsigned long long>(stats.updates_dropped),
      static_cast<unsigned long long>(stats.rays_skipped), device->deviceName().c_str());
  std::cout << "[device-agreement] " << line << std::endl;
  RecordProperty("agreement_percent", std::to_string(100.0 * states.sameStateFraction()));
  RecordProperty("compared_voxels", std::to_string(states.compared));
  RecordProperty("value_outliers", std::to_string(values.value_outliers));
  RecordProperty("mean_mismatches",
                 std::to_string(values.count_mismatches + values.mean_mismatches));

  // Assert
  EXPECT_EQ(cpu_run.counters.rays_in, rays.size());
  EXPECT_EQ(device_run.counters.rays_accepted, cpu_run.counters.rays_accepted);
  EXPECT_GT(states.compared, 0u);
  EXPECT_GE(states.sameStateFraction(), kMinAgreement);
  EXPECT_LE(values.outlierFraction(), kMaxValueOutliers)
      << values.value_outliers << " of " << values.same_observed
      << " voxels differ by more than half a hit";
  EXPECT_EQ(values.count_mismatches, 0u);
  EXPECT_EQ(values.mean_mismatches, 0u) << "max difference " << values.max_mean_difference;
  EXPECT_EQ(stats.updates_dropped, 0u);
  EXPECT_EQ(stats.rays_skipped, 0u);
  // Same walk direction: every value equal, in both semantics (docs/architecture.md).
  EXPECT_EQ(same_walk_states.exact_value, same_walk_states.compared);
}

INSTANTIATE_TEST_SUITE_P(SharedData, DeviceDataAgreement, testing::ValuesIn(dataCases()),
                         [](const testing::TestParamInfo<DataCase>& param_info) {
                           return dataCaseName(param_info.param);
                         });

}  // namespace
}  // namespace raymap::test
