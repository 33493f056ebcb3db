// SPDX-License-Identifier: BSD-3-Clause
// Height-map normals from NDT covariances (issue 8): an NDT-OM map of a flat floor meeting a 20
// degree slope, built from simulated rays on the CPU backend, gives every generator (CPU; OpenCL
// on PoCL; CUDA where present) normals within a few degrees of the true planes, the device
// generators agree with the CPU, and maps without an NDT layer have no normal layers.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "src/heightmap/heightmap_plan.hpp"
#include "src/io/heightmap_export.hpp"
#include "src/map/cpu_backend.hpp"
#include "src/map/ray_preparer.hpp"
#include "tests/heightmap/heightmap_generators.hpp"

namespace raymap {
namespace {

using heightmap::CellKind;
using heightmap::HeightMap;
using heightmap::HeightmapMode;
using heightmap::HeightmapOptions;

constexpr double kPi = 3.14159265358979323846;
constexpr double kSlope = 20.0 * kPi / 180.0;    // the slope's inclination
constexpr double kAzimuth = 30.0 * kPi / 180.0;  // direction (from +x toward +y) it rises in
constexpr double kHalfExtent = 2.6;              // rays hit |x|, |y| <= this, metres
constexpr double kJunctionMargin = 0.3;  // cells this close to the floor/slope edge are skipped
// Against its plane: 95 % of the valid normals, and their mean. A few slope cells are worse (up to
// ~25 degrees): their surface voxel is the top of a run, holding a thin sliver of the plane.
constexpr double kMaxP95AngleDeg = 5.0;
constexpr double kMaxMeanAngleDeg = 2.0;
constexpr double kMinValidFraction = 0.8;  // of the surface cells of each plane
constexpr float kDeviceTolerance = 1e-5f;  // a normal component, device against CPU

/// Distance along the slope's rising direction; the floor is u <= 0, the slope u > 0.
double along(double x, double y) { return x * std::cos(kAzimuth) + y * std::sin(kAzimuth); }
double surfaceZ(double x, double y) { return std::max(0.0, along(x, y) * std::tan(kSlope)); }

/// The true upward normals.
constexpr double kFloorNormal[3] = {0.0, 0.0, 1.0};
const double kSlopeNormal[3] = {-std::sin(kSlope) * std::cos(kAzimuth),
                                -std::sin(kSlope) * std::sin(kAzimuth), std::cos(kSlope)};

/// Rays from four sensors 4 to 5 m up onto the surface, ~30 per 0.1 m column, with +-5 mm of
/// uniform range noise. The region above the surface is convex (z >= max of two planes), so no
/// ray crosses the surface before its return.
std::vector<Ray> surfaceRays() {
  const Vec3d origins[4] = {{-1.5, -1.5, 4.0}, {1.5, -1.5, 4.5}, {-1.5, 1.5, 4.2}, {1.5, 1.5, 5.0}};
  std::mt19937 random(8);
  std::uniform_real_distribution<double> position(-kHalfExtent, kHalfExtent);
  std::uniform_real_distribution<double> noise(-0.005, 0.005);
  const int count = static_cast<int>(30.0 * (2 * kHalfExtent / 0.1) * (2 * kHalfExtent / 0.1));
  std::vector<Ray> rays;
  rays.reserve(static_cast<std::size_t>(count));
  for (int k = 0; k < count; ++k) {
    Ray ray;
    ray.origin = origins[k % 4];
    const double x = position(random);
    const double y = position(random);
    const Vec3d hit{x, y, surfaceZ(x, y)};
    const Vec3d d{hit.x - ray.origin.x, hit.y - ray.origin.y, hit.z - ray.origin.z};
    const double length = std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
    const double scale = 1.0 + noise(random) / length;
    ray.sample = {ray.origin.x + d.x * scale, ray.origin.y + d.y * scale,
                  ray.origin.z + d.z * scale};
    rays.push_back(ray);
  }
  return rays;
}

/// The rays integrated by the CPU backend into a map of `mode`, once per mode and process.
const VoxelMap& mappedSurface(MapMode mode) {
  static std::unique_ptr<VoxelMap> maps[3];
  std::unique_ptr<VoxelMap>& map = maps[static_cast<int>(mode)];
  if (map) {
    return *map;
  }
  MapConfig config;
  config.mode = mode;
  config.memory_budget_bytes = std::uint64_t{256} << 20;
  auto created = VoxelMap::create(config);
  EXPECT_TRUE(created) << created.error().message;
  map = std::make_unique<VoxelMap>(std::move(*created));
  const std::vector<Ray> rays = surfaceRays();
  RayPreparer preparer(*map, RayFilter{});
  std::vector<PreparedRay> prepared(rays.size());
  prepared.resize(preparer.prepare(rays, prepared).written);
  auto backend = createCpuBackend(*map, CpuBackendOptions{});
  EXPECT_TRUE(backend);
  EXPECT_TRUE((*backend)->integrate(prepared));
  EXPECT_TRUE((*backend)->synchronise());
  return *map;
}

HeightmapOptions surfaceOptions(HeightmapMode mode) {
  HeightmapOptions o;
  o.centre = {0.05, 0.05, 0.0};
  o.size = 5.0;
  o.mode = mode;
  return o;
}

/// Generates with generator `name`; fails the test on error.
HeightMap generate(heightmap::HeightmapGenerator& generator, const VoxelMap& map,
                   const HeightmapOptions& o) {
  heightmap::HeightmapPlan plan;
  auto planned = heightmap::planHeightmap(map, o, plan);
  EXPECT_TRUE(planned) << planned.error().message;
  HeightMap out;
  auto ok = generator.generate(map, plan, out);
  EXPECT_TRUE(ok) << ok.error().message;
  return out;
}

double angleDegrees(const HeightMap& h, std::size_t k, const double* truth) {
  const double c = static_cast<double>(h.normal_x[k]) * truth[0] +
                   static_cast<double>(h.normal_y[k]) * truth[1] +
                   static_cast<double>(h.normal_z[k]) * truth[2];
  return std::acos(std::clamp(c, -1.0, 1.0)) * 180.0 / kPi;
}

/// Angle errors of the surface cells of one plane.
struct PlaneStats {
  int surface_cells = 0;
  int valid = 0;
  double max_deg = 0.0;
  double sum_deg = 0.0;
  std::vector<double> degs;
  double percentileDeg(double q) {
    std::sort(degs.begin(), degs.end());
    return degs.empty() ? 0.0
                        : degs[static_cast<std::size_t>(q * static_cast<double>(degs.size() - 1))];
  }
  double meanDeg() const { return valid > 0 ? sum_deg / valid : 0.0; }
};

class HeightmapNormals : public ::testing::TestWithParam<std::tuple<std::string, HeightmapMode>> {};

TEST_P(HeightmapNormals, SurfaceNormalsMatchTheFloorAndTheSlope) {
  REQUIRE_HEIGHTMAP_GENERATOR(std::get<0>(GetParam()), generator);
  const VoxelMap& map = mappedSurface(MapMode::kNdtOm);
  ASSERT_GE(map.ndtLayer(), 0);
  const HeightMap h = generate(*generator, map, surfaceOptions(std::get<1>(GetParam())));
  ASSERT_TRUE(h.has_normals);
  ASSERT_EQ(h.normal_x.size(), h.cellCount());
  ASSERT_EQ(h.normal_y.size(), h.cellCount());
  ASSERT_EQ(h.normal_z.size(), h.cellCount());
  PlaneStats floor;
  PlaneStats slope;
  for (int j = 0; j < h.cells_y; ++j) {
    for (int i = 0; i < h.cells_x; ++i) {
      const std::size_t k = h.index(i, j);
      const bool has = !std::isnan(h.normal_z[k]);
      if (h.kindAt(i, j) != CellKind::kSurface) {
        EXPECT_FALSE(has) << "a normal on a cell of kind " << h.kind[k];
        continue;
      }
      const Vec3d c = h.cellCentre(i, j);
      const double u = along(c.x, c.y);
      if (std::fabs(u) < kJunctionMargin) {
        continue;
      }
      PlaneStats& s = u < 0.0 ? floor : slope;
      ++s.surface_cells;
      if (!has) {
        continue;
      }
      ++s.valid;
      const double deg = angleDegrees(h, k, u < 0.0 ? kFloorNormal : kSlopeNormal);
      s.max_deg = std::max(s.max_deg, deg);
      s.sum_deg += deg;
      s.degs.push_back(deg);
    }
  }
  for (PlaneStats* s : {&floor, &slope}) {
    const char* name = s == &floor ? "floor" : "slope";
    std::printf(
        "%s: %d surface cells, %d with a normal; angle error mean %.3f deg, 95%% %.3f deg, max "
        "%.3f deg\n",
        name, s->surface_cells, s->valid, s->meanDeg(), s->percentileDeg(0.95), s->max_deg);
    ASSERT_GT(s->surface_cells, 500) << name;
    EXPECT_GE(s->valid, kMinValidFraction * s->surface_cells) << name;
    EXPECT_LE(s->meanDeg(), kMaxMeanAngleDeg) << name;
    EXPECT_LE(s->percentileDeg(0.95), kMaxP95AngleDeg) << name;
  }
}

TEST_P(HeightmapNormals, AnOccupancyMapHasNoNormalLayers) {
  REQUIRE_HEIGHTMAP_GENERATOR(std::get<0>(GetParam()), generator);
  const VoxelMap& map = mappedSurface(MapMode::kOccupancy);
  ASSERT_LT(map.ndtLayer(), 0);
  const HeightMap h = generate(*generator, map, surfaceOptions(std::get<1>(GetParam())));
  EXPECT_FALSE(h.has_normals);
  EXPECT_TRUE(h.normal_x.empty());
  EXPECT_TRUE(h.normal_y.empty());
  EXPECT_TRUE(h.normal_z.empty());
  EXPECT_GT(std::count(h.kind.begin(), h.kind.end(), RM_HM_SURFACE), 2000);
}

INSTANTIATE_TEST_SUITE_P(
    Generators, HeightmapNormals,
    ::testing::Combine(::testing::ValuesIn(test::heightmapGeneratorNames()),
                       ::testing::Values(HeightmapMode::kPlanar, HeightmapMode::kFill)),
    [](const ::testing::TestParamInfo<std::tuple<std::string, HeightmapMode>>& param_info) {
      return std::get<0>(param_info.param) +
             (std::get<1>(param_info.param) == HeightmapMode::kFill ? "_fill" : "_planar");
    });

TEST(HeightmapNormalsAcrossGenerators, DeviceNormalsAgreeWithTheCpu) {
  const VoxelMap& map = mappedSurface(MapMode::kNdtOm);
  const HeightmapOptions o = surfaceOptions(HeightmapMode::kFill);
  std::string why;
  heightmap::HeightmapGenerator* cpu = test::heightmapGenerator("cpu", &why);
  ASSERT_NE(cpu, nullptr) << why;
  const HeightMap reference = generate(*cpu, map, o);
  int compared = 0;
  for (const std::string& name : test::heightmapGeneratorNames()) {
    heightmap::HeightmapGenerator* device = test::heightmapGenerator(name, &why);
    if (name == "cpu" || device == nullptr) {
      continue;
    }
    const HeightMap h = generate(*device, map, o);
    ASSERT_TRUE(h.has_normals) << name;
    ASSERT_EQ(h.kind, reference.kind) << name;
    int valid = 0;
    for (std::size_t k = 0; k < h.cellCount(); ++k) {
      const float a[3] = {h.normal_x[k], h.normal_y[k], h.normal_z[k]};
      const float b[3] = {reference.normal_x[k], reference.normal_y[k], reference.normal_z[k]};
      for (int c = 0; c < 3; ++c) {
        ASSERT_EQ(std::isnan(a[c]), std::isnan(b[c])) << name << " cell " << k;
        if (!std::isnan(b[c])) {
          EXPECT_NEAR(a[c], b[c], kDeviceTolerance) << name << " cell " << k << " axis " << c;
        }
      }
      valid += std::isnan(b[2]) ? 0 : 1;
    }
    EXPECT_GT(valid, 1000) << name;
    ++compared;
  }
  if (compared == 0) {
    GTEST_SKIP() << "no device height-map generator on this machine";
  }
}

TEST(HeightmapNormalsExport, CsvHasNormalColumnsOnlyWithNormals) {
  std::string why;
  heightmap::HeightmapGenerator* cpu = test::heightmapGenerator("cpu", &why);
  ASSERT_NE(cpu, nullptr) << why;
  const std::string path = ::testing::TempDir() + "raymap_normals.csv";
  for (const MapMode mode : {MapMode::kOccupancy, MapMode::kNdtOm}) {
    const HeightMap h = generate(*cpu, mappedSurface(mode), surfaceOptions(HeightmapMode::kPlanar));
    ASSERT_TRUE(io::writeHeightmapCsv(path, h));
    std::ifstream file(path);
    std::string header;
    std::getline(file, header);
    EXPECT_EQ(header, mode == MapMode::kOccupancy
                          ? "x,y,elevation,clearance,kind"
                          : "x,y,elevation,clearance,kind,normal_x,normal_y,normal_z");
    std::string line;
    std::size_t lines = 0;
    std::size_t commas = 0;
    while (std::getline(file, line)) {
      ++lines;
      commas =
          std::max(commas, static_cast<std::size_t>(std::count(line.begin(), line.end(), ',')));
    }
    EXPECT_EQ(lines, h.cellCount());
    EXPECT_EQ(commas, mode == MapMode::kOccupancy ? 4u : 7u);
  }
  std::remove(path.c_str());
}

}  // namespace
}  // namespace raymap
