// SPDX-License-Identifier: BSD-3-Clause
// NDT-OM against plain occupancy on the shared real data, at the same probabilities: NDT-OM keeps
// more occupied voxels on thin (pole-like) and flat (wall-like) structures, which plain occupancy
// erodes with rays passing beside them or grazing them. Skips without the shared data.
#include <cstdio>
#include <iostream>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include "src/map/backend.hpp"
#include "src/map/ray_preparer.hpp"
#include "src/map/voxel_map.hpp"
#include "tests/support/shared_data.hpp"
#include "tests/support/test_rays.hpp"

namespace raymap::test {
namespace {

constexpr double kResolution = 0.1;  // metres
constexpr double kMaxRange = 20.0;   // metres, as in docs/benchmarks.md
// Shape classes of a Gaussian by its eigenvalues l0 <= l1 <= l2 (voxel units squared).
constexpr double kShapeRatio = 0.1;

VoxelMap buildMap(std::span<const Ray> rays, MapMode mode, const OccupancyParams& occupancy) {
  MapConfig config;
  config.occupancy = occupancy;
  config.geometry.resolution = kResolution;
  config.mode = mode;
  VoxelMap map = makeMap(config);
  std::unique_ptr<Backend> backend = cpuBackend(map, 0);
  RayFilter filter;
  filter.max_range_m = kMaxRange;
  RayPreparer preparer(map, filter);
  std::vector<PreparedRay> prepared;
  forEachScan(rays, [&](std::span<const Ray> scan) {
    prepared.resize(scan.size());
    const RayPreparer::Progress progress = preparer.prepare(scan, prepared);
    EXPECT_EQ(progress.consumed, scan.size());
    EXPECT_TRUE(
        backend->integrate(std::span<const PreparedRay>(prepared.data(), progress.written)));
  });
  EXPECT_TRUE(backend->synchronise().has_value());
  return map;
}

enum class Shape { kLinear, kPlanar, kOther };

Shape shapeOf(const rm_ndt_voxel& g) {
  float p[6];
  rm_ndt_covariance(g.s, p);
  Eigen::Matrix3d covariance;      // from the packed lower triangle (kernels/common/ndt.h)
  covariance << p[0], p[1], p[3],  //
      p[1], p[2], p[4],            //
      p[3], p[4], p[5];
  // Eigenvalues in ascending order.
  const Eigen::Vector3d l =
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(covariance, Eigen::EigenvaluesOnly)
          .eigenvalues();
  if (l[1] < kShapeRatio * l[2]) {
    return Shape::kLinear;  // one dominant axis: a pole, a wire, an edge
  }
  if (l[0] < kShapeRatio * l[1]) {
    return Shape::kPlanar;  // two: a wall, the ground
  }
  return Shape::kOther;
}

struct ShapeCounts {
  std::uint64_t voxels = 0;          ///< with a Gaussian of >= 4 samples in the NDT-OM map
  std::uint64_t occupied_ndt = 0;    ///< of those, occupied in NDT-OM
  std::uint64_t occupied_plain = 0;  ///< of those, occupied in plain occupancy
};

/// raymap's default probabilities (hit 0.9, miss 0.45) and OctoMap's (0.7, 0.4).
class NdtRealData : public testing::TestWithParam<bool> {};

TEST_P(NdtRealData, OusterPolesAndWallsKeepMoreOccupiedVoxelsThanPlainOccupancy) {
  const OccupancyParams occupancy = GetParam() ? OccupancyParams::octomap() : OccupancyParams();
  const DataSet& ouster = sharedDataSets()[0];
  const DataFiles files = dataFiles(ouster);
  if (!files.missing.empty()) {
    GTEST_SKIP() << files.missing;
  }
  const std::vector<Ray> rays = loadRays(files.file, files.trajectory);
  ASSERT_FALSE(rays.empty());
  const VoxelMap plain = buildMap(rays, MapMode::kOccupancy, occupancy);
  const VoxelMap ndt = buildMap(rays, MapMode::kNdtOm, occupancy);

  ShapeCounts linear;
  ShapeCounts planar;
  const RegionStore& store = ndt.store();
  store.forEachRegion([&](std::uint32_t slot, Vec3i region) {
    const rm_ndt_voxel* gaussians = store.layerData<rm_ndt_voxel>(slot, ndt.ndtLayer());
    for (std::uint32_t i = 0; i < ndt.geometry().voxelsPerRegion(); ++i) {
      if (gaussians[i].count < 4) {
        continue;
      }
      const Shape shape = shapeOf(gaussians[i]);
      if (shape == Shape::kOther) {
        continue;
      }
      ShapeCounts& c = shape == Shape::kLinear ? linear : planar;
      const Vec3i voxel = ndt.voxelAt(region, i);
      ++c.voxels;
      c.occupied_ndt += ndt.state(voxel) == VoxelState::kOccupied ? 1u : 0u;
      c.occupied_plain += plain.state(voxel) == VoxelState::kOccupied ? 1u : 0u;
    }
  });
  const MapSummary s_plain = plain.summarise();
  const MapSummary s_ndt = ndt.summarise();
  char line[512];
  std::snprintf(line, sizeof(line),
                "%s probabilities: occupied voxels: occupancy %llu, NDT-OM %llu; pole-like voxels "
                "%llu: occupied "
                "%llu (occupancy) vs %llu (NDT-OM); wall-like voxels %llu: occupied %llu vs %llu",
                GetParam() ? "OctoMap's" : "raymap's",
                static_cast<unsigned long long>(s_plain.voxels_occupied),
                static_cast<unsigned long long>(s_ndt.voxels_occupied),
                static_cast<unsigned long long>(linear.voxels),
                static_cast<unsigned long long>(linear.occupied_plain),
                static_cast<unsigned long long>(linear.occupied_ndt),
                static_cast<unsigned long long>(planar.voxels),
                static_cast<unsigned long long>(planar.occupied_plain),
                static_cast<unsigned long long>(planar.occupied_ndt));
  std::cout << "[ndt] " << line << std::endl;
  EXPECT_GT(linear.voxels, 100u);
  EXPECT_GT(planar.voxels, 1000u);
  EXPECT_GT(linear.occupied_ndt, linear.occupied_plain);
  EXPECT_GT(planar.occupied_ndt, planar.occupied_plain);
  EXPECT_GT(s_ndt.voxels_occupied, s_plain.voxels_occupied);
}

INSTANTIATE_TEST_SUITE_P(Probabilities, NdtRealData, testing::Values(false, true),
                         [](const testing::TestParamInfo<bool>& p) {
                           return p.param ? std::string("octomap") : std::string("raymap");
                         });

}  // namespace
}  // namespace raymap::test
