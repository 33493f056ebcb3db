// SPDX-License-Identifier: BSD-3-Clause
// What comes out of a map through the library (issue 55): raymap::Mapper::exportPly writes the
// file `raymap export` writes, byte for byte, for every kind; Mapper::costmap lays its cells out
// as nav_msgs/OccupancyGrid over the height map it comes from; and options that do not fit are
// refused naming their key.
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "raymap/mapper.hpp"
#include <gtest/gtest.h>

#include "tests/support/cli_runner.hpp"
#include "tests/support/file_bytes.hpp"
#include "tests/support/temp_dir.hpp"

namespace raymap::test {
namespace {

/// The room scene's lidar, five scans, as a ray cloud.
std::string roomRays(const TempDir& dir) {
  const std::string rays = dir.file("room.ply");
  const RunResult r = runRaymap({"simulate", std::string(RAYMAP_SCENES_DIR) + "/room.yaml",
                                 "--sensors", "lidar", "--scans", "5", "--rays", rays, "-q"});
  EXPECT_EQ(r.exit_code, 0) << describe(r);
  return rays;
}

ExportRequest requestOf(ExportKind kind) {
  ExportRequest request;
  request.kind = kind;
  return request;
}

struct ExportCase {
  std::vector<std::string> populate;  ///< the map's `raymap populate` flags
  std::vector<std::string> export_flags;
  ExportRequest request;
};

std::vector<ExportCase> exportCases() {
  ExportRequest decay = requestOf(ExportKind::kDecay);
  decay.decay_threshold = 0.5;
  ExportRequest ndt = requestOf(ExportKind::kNdt);
  ndt.ndt_sigmas = 3.0;
  ndt.ndt_min_axis = 0.01;
  ExportRequest ndt_points = requestOf(ExportKind::kNdtPoints);
  ndt_points.ndt_colour = ExportColour::kPermeability;
  ExportRequest tsdf = requestOf(ExportKind::kTsdf);
  tsdf.tsdf_min_weight = 2.0;
  return {
      {{}, {"--mode", "occupied"}, requestOf(ExportKind::kOccupied)},
      {{}, {"--mode", "free"}, requestOf(ExportKind::kFree)},
      {{}, {"--mode", "mean"}, requestOf(ExportKind::kMean)},
      {{"--decay-rate"}, {"--mode", "decay", "--threshold", "0.5"}, decay},
      {{"--mode", "ndt-om"}, {"--mode", "ndt", "--sigmas", "3", "--min-axis", "0.01"}, ndt},
      {{"--mode", "ndt-tm"}, {"--mode", "ndt-points", "--colour", "permeability"}, ndt_points},
      {{"--mode", "tsdf"}, {"--mode", "tsdf", "--min-weight", "2"}, tsdf},
      {{"--mode", "tsdf"}, {"--mode", "tsdf-mesh"}, requestOf(ExportKind::kTsdfMesh)},
  };
}

TEST(LibraryExports, EveryKindWritesTheFileRaymapExportWrites) {
  TempDir dir;
  const std::string rays = roomRays(dir);
  int n = 0;
  for (const ExportCase& c : exportCases()) {
    const std::string name(toString(c.request.kind));
    SCOPED_TRACE(name);
    const std::string map = dir.file("map" + std::to_string(n) + ".rmap");
    const std::string cli_ply = dir.file("cli" + std::to_string(n) + ".ply");
    const std::string library_ply = dir.file("library" + std::to_string(n) + ".ply");
    ++n;
    std::vector<std::string> populate{"populate", rays, "-o", map, "-q", "--max-range", "20"};
    populate.insert(populate.end(), c.populate.begin(), c.populate.end());
    ASSERT_EQ(runRaymap(populate).exit_code, 0);
    std::vector<std::string> export_args{"export", map, "--ply", cli_ply, "-q"};
    export_args.insert(export_args.end(), c.export_flags.begin(), c.export_flags.end());
    const RunResult exported = runRaymap(export_args);
    ASSERT_EQ(exported.exit_code, 0) << describe(exported);

    auto mapper = Mapper::load(map);
    ASSERT_TRUE(mapper) << mapper.error().message;
    auto counts = mapper->exportPly(library_ply, c.request);
    ASSERT_TRUE(counts) << counts.error().message;

    EXPECT_GT(counts->items, 0u);
    EXPECT_EQ(c.request.kind == ExportKind::kTsdfMesh, counts->vertices > 0);
    EXPECT_EQ(readFileBytes(library_ply), readFileBytes(cli_ply));
    EXPECT_EQ(exportKindFromName(name), c.request.kind);
  }
}

TEST(LibraryExports, OptionsOfAnotherKindAndBadValuesAreRefusedByKeyAndWriteNothing) {
  TempDir dir;
  const std::string map = dir.file("map.rmap");
  ASSERT_EQ(runRaymap({"populate", roomRays(dir), "-o", map, "-q"}).exit_code, 0);
  auto mapper = Mapper::load(map);
  ASSERT_TRUE(mapper) << mapper.error().message;
  const std::string ply = dir.file("x.ply");

  ExportRequest weight = requestOf(ExportKind::kOccupied);
  weight.tsdf_min_weight = 1.0;
  ExportRequest sigmas = requestOf(ExportKind::kNdt);
  sigmas.ndt_sigmas = 0.0;
  ExportRequest threshold = requestOf(ExportKind::kDecay);
  threshold.decay_threshold = -1.0;
  ExportRequest colour = requestOf(ExportKind::kTsdf);
  colour.ndt_colour = ExportColour::kHeight;

  const auto refused = [&](const ExportRequest& request) {
    auto counts = mapper->exportPly(ply, request);
    EXPECT_FALSE(std::filesystem::exists(ply));
    return counts ? std::string() : counts.error().message;
  };
  EXPECT_EQ(refused(weight), "export.min_weight applies only to export.mode tsdf or tsdf-mesh");
  EXPECT_EQ(refused(sigmas), "export.sigmas must be in (0, 100]");
  EXPECT_NE(refused(threshold).find("export.threshold"), std::string::npos);
  EXPECT_EQ(refused(colour),
            "export.colour does not apply to export.mode tsdf (its option is export.min_weight)");
  // A kind the map has no layer for says which.
  EXPECT_NE(refused(requestOf(ExportKind::kTsdfMesh)).find("TSDF"), std::string::npos);
}

TEST(LibraryCostmap, CellsFollowTheHeightMapInOccupancyGridsLayout) {
  TempDir dir;
  const std::string map = dir.file("map.rmap");
  ASSERT_EQ(runRaymap({"populate", roomRays(dir), "-o", map, "-q"}).exit_code, 0);
  auto mapper = Mapper::load(map);
  ASSERT_TRUE(mapper) << mapper.error().message;
  HeightmapRequest request;
  request.centre = {0.0, 0.0, 0.0};
  request.size = 9.0;
  CostmapOptions options;
  options.max_slope_deg = 40.0;

  auto height = mapper->heightmap(request);
  auto costmap = mapper->costmap(request, options);

  ASSERT_TRUE(height) << height.error().message;
  ASSERT_TRUE(costmap) << costmap.error().message;
  ASSERT_EQ(costmap->width, height->cells_x);
  ASSERT_EQ(costmap->height, height->cells_y);
  ASSERT_EQ(costmap->cells.size(), height->kind.size());
  EXPECT_DOUBLE_EQ(costmap->resolution, height->resolution);
  EXPECT_NEAR(costmap->origin.x(), height->centre.x() - 0.5 * height->cells_x * height->resolution,
              1e-9);
  int unknown = 0;
  int lethal = 0;
  int free = 0;
  for (int y = 0; y < costmap->height; ++y) {
    for (int x = 0; x < costmap->width; ++x) {
      // OccupancyGrid's cell (x, y) is row-major from the -x/-y corner; the height map's cell
      // (i, j) counts from the +x/+y corner, column-major: the same cell's centre.
      const int i = height->cells_x - 1 - x;
      const int j = height->cells_y - 1 - y;
      const Eigen::Vector2d centre = height->cellCentre(i, j);
      EXPECT_NEAR(centre.x(), costmap->origin.x() + (x + 0.5) * costmap->resolution, 1e-9);
      EXPECT_NEAR(centre.y(), costmap->origin.y() + (y + 0.5) * costmap->resolution, 1e-9);
      const std::int8_t cost = costmap->cells[static_cast<std::size_t>(x + y * costmap->width)];
      const HeightCell kind = height->kind[height->index(i, j)];
      EXPECT_EQ(cost == -1, kind == HeightCell::kUnknown);
      if (kind == HeightCell::kSurface && height->clearance[height->index(i, j)] < 0.5F) {
        EXPECT_EQ(cost, 100);  // the robot does not fit: under the table
      }
      unknown += cost == -1 ? 1 : 0;
      lethal += cost == 100 ? 1 : 0;
      free += cost >= 0 && cost < 100 ? 1 : 0;
    }
  }
  // The room's floor is free, its walls and furniture lethal, the world beyond unknown.
  EXPECT_GT(free, 1000);
  EXPECT_GT(lethal, 50);
  EXPECT_GT(unknown, 0);
}

TEST(LibraryCostmap, OptionsOutOfRangeAreRefusedByKey) {
  TempDir dir;
  const std::string map = dir.file("map.rmap");
  ASSERT_EQ(runRaymap({"populate", roomRays(dir), "-o", map, "-q"}).exit_code, 0);
  auto mapper = Mapper::load(map);
  ASSERT_TRUE(mapper) << mapper.error().message;
  CostmapOptions slope;
  slope.max_slope_deg = 90.0;
  CostmapOptions cost;
  cost.max_free_cost = 100;

  auto a = mapper->costmap(HeightmapRequest{}, slope);
  auto b = mapper->costmap(HeightmapRequest{}, cost);

  ASSERT_FALSE(a);
  ASSERT_FALSE(b);
  EXPECT_NE(a.error().message.find("costmap.max_slope"), std::string::npos) << a.error().message;
  EXPECT_NE(b.error().message.find("costmap.max_free_cost"), std::string::npos)
      << b.error().message;
}

}  // namespace
}  // namespace raymap::test
