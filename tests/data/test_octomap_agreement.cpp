// SPDX-License-Identifier: BSD-3-Clause
// Agreement of raymap with OctoMap on the shared real data: the same rays, resolution, range
// limit and probabilities give the same free and occupied voxels, per ray and per scan.
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
#include <span>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "src/map/backend.hpp"
#include "src/map/map_params.hpp"
#include "src/map/ray_preparer.hpp"
#include "src/map/voxel_map.hpp"
#include "tests/support/shared_data.hpp"
#include "tests/support/temp_dir.hpp"
#include "tests/support/test_rays.hpp"
#include "tools/bench/octomap_reference.hpp"

namespace raymap::test {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

// The settings of docs/benchmarks.md: 0.1 m voxels, rays clipped at 20 m, OctoMap's probabilities.
constexpr double kAgreementResolution = 0.1;  // metres
constexpr double kAgreementMaxRange = 20.0;   // metres
constexpr double kCountTolerance = 0.005;     // relative difference of free or occupied counts
constexpr double kMinAgreement = 0.999;  // voxels with the same state, of those either observed

/// A raymap map of the rays and what building it took.
struct RaymapRun {
  VoxelMap map;
  RayCounters counters;
  double seconds = 0.0;  ///< preparation and integration
};

MapConfig mapConfig(Semantics semantics) {
  MapConfig config;
  config.geometry.resolution = kAgreementResolution;
  config.occupancy = OccupancyParams::octomap();
  config.semantics = semantics;
  config.voxel_mean = false;  // not compared; saves memory and time
  return config;
}

/// Builds the map with one integrate() call per scan (which per-scan semantics needs).
RaymapRun buildRaymap(std::span<const Ray> rays, Semantics semantics, unsigned threads) {
  RaymapRun run{makeMap(mapConfig(semantics)), {}, 0.0};
  std::unique_ptr<Backend> backend = cpuBackend(run.map, threads);
  RayFilter filter;
  filter.max_range_m = kAgreementMaxRange;
  RayPreparer preparer(run.map, filter);
  std::vector<PreparedRay> prepared;
  const Clock::time_point start = Clock::now();
  forEachScan(rays, [&](std::span<const Ray> scan) {
    prepared.resize(scan.size());  // without segmentation every ray gives at most one piece
    const RayPreparer::Progress progress = preparer.prepare(scan, prepared);
    EXPECT_EQ(progress.consumed, scan.size()) << "a scan did not fit one batch";
    auto ok = backend->integrate(std::span<const PreparedRay>(prepared.data(), progress.written));
    EXPECT_TRUE(ok.has_value()) << "integration failed: " << toString(ok.error());
  });
  EXPECT_TRUE(backend->synchronise().has_value());
  run.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  run.counters = preparer.counters();
  return run;
}

/// Relative difference of a count from the reference count.
double relativeDifference(std::uint64_t ours, std::uint64_t reference) {
  const double r = static_cast<double>(reference);
  return r > 0.0 ? std::fabs(static_cast<double>(ours) - r) / r : (ours == 0 ? 0.0 : 1.0);
}

class OctomapAgreement : public testing::TestWithParam<DataCase> {};

TEST_P(OctomapAgreement, CountsAndVoxelStatesMatchOctomap) {
  // Arrange
  const DataCase& param = GetParam();
  const DataFiles files = dataFiles(param.data);
  if (!files.missing.empty()) {
    GTEST_SKIP() << files.missing;
  }
  const std::vector<Ray> rays = loadRays(files.file, files.trajectory);
  ASSERT_FALSE(rays.empty());
  bench::OctomapOptions octomap_options;
  octomap_options.resolution = kAgreementResolution;
  octomap_options.max_range_m = kAgreementMaxRange;
  octomap_options.occupancy = OccupancyParams::octomap();
  octomap_options.semantics = param.semantics;
  bench::OctomapReference octomap(octomap_options);

  // Act
  const RaymapRun one_thread = buildRaymap(rays, param.semantics, 1);
  const RaymapRun two_threads = buildRaymap(rays, param.semantics, 2);
  forEachScan(rays, [&](std::span<const Ray> scan) { octomap.integrate(scan); });
  const bench::OctomapCounts theirs = octomap.counts();
  const MapSummary ours = one_thread.map.summarise();
  const MapSummary ours_two = two_threads.map.summarise();
  const bench::Agreement agreement = octomap.compare(one_thread.map);
  const MapComparison threads_comparison = compareMaps(one_thread.map, two_threads.map);

  // Report (for docs/benchmarks.md).
  const double free_diff = relativeDifference(ours.voxels_free, theirs.voxels_free);
  const double occupied_diff = relativeDifference(ours.voxels_occupied, theirs.voxels_occupied);
  char line[512];
  std::snprintf(
      line, sizeof(line),
      "%s %s: rays %zu (raymap integrated %llu, octomap %llu); free raymap %llu octomap "
      "%llu (%+.3f %%); occupied raymap %llu octomap %llu (%+.3f %%); agreement %.4f %% "
      "of %llu voxels (only raymap %llu, only octomap %llu); seconds raymap 1t %.2f 2t "
      "%.2f octomap %.2f",
      param.data.name, toString(param.semantics), rays.size(),
      static_cast<unsigned long long>(one_thread.counters.rays_accepted),
      static_cast<unsigned long long>(theirs.rays_integrated),
      static_cast<unsigned long long>(ours.voxels_free),
      static_cast<unsigned long long>(theirs.voxels_free),
      100.0 * (static_cast<double>(ours.voxels_free) - static_cast<double>(theirs.voxels_free)) /
          static_cast<double>(std::max<std::uint64_t>(theirs.voxels_free, 1)),
      static_cast<unsigned long long>(ours.voxels_occupied),
      static_cast<unsigned long long>(theirs.voxels_occupied),
      100.0 *
          (static_cast<double>(ours.voxels_occupied) -
           static_cast<double>(theirs.voxels_occupied)) /
          static_cast<double>(std::max<std::uint64_t>(theirs.voxels_occupied, 1)),
      100.0 * agreement.fraction(), static_cast<unsigned long long>(agreement.compared),
      static_cast<unsigned long long>(agreement.only_raymap),
      static_cast<unsigned long long>(agreement.only_octomap), one_thread.seconds,
      two_threads.seconds, theirs.integrate_seconds);
  std::cout << "[agreement] " << line << std::endl;
  RecordProperty("raymap_free", std::to_string(ours.voxels_free));
  RecordProperty("octomap_free", std::to_string(theirs.voxels_free));
  RecordProperty("raymap_occupied", std::to_string(ours.voxels_occupied));
  RecordProperty("octomap_occupied", std::to_string(theirs.voxels_occupied));
  RecordProperty("agreement_percent", std::to_string(100.0 * agreement.fraction()));
  RecordProperty("compared_voxels", std::to_string(agreement.compared));

  // Assert
  EXPECT_EQ(one_thread.counters.rays_in, rays.size());
  EXPECT_GT(ours.voxels_occupied, 0u);
  EXPECT_LE(free_diff, kCountTolerance) << "free voxels differ by " << 100.0 * free_diff << " %";
  EXPECT_LE(occupied_diff, kCountTolerance)
      << "occupied voxels differ by " << 100.0 * occupied_diff << " %";
  EXPECT_GE(agreement.fraction(), kMinAgreement);
  // Two threads build the single-threaded map, bit for bit.
  EXPECT_EQ(ours_two.voxels_free, ours.voxels_free);
  EXPECT_EQ(ours_two.voxels_occupied, ours.voxels_occupied);
  EXPECT_EQ(threads_comparison.exact_value, threads_comparison.compared);
}

INSTANTIATE_TEST_SUITE_P(SharedData, OctomapAgreement, testing::ValuesIn(dataCases()),
                         [](const testing::TestParamInfo<DataCase>& param_info) {
                           return dataCaseName(param_info.param);
                         });

}  // namespace
}  // namespace raymap::test
