// SPDX-License-Identifier: BSD-3-Clause
// planHeightmap(): requests it refuses (each error names the option and the reason) and the plan
// it makes (grid size and geometry, the seed cell, the region table), without any generator.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <initializer_list>
#include <limits>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "kernels/common/heightmap.h"
#include "src/heightmap/heightmap_plan.hpp"
#include "src/io/map_file.hpp"
#include "tests/support/temp_dir.hpp"

namespace raymap {
namespace {

using heightmap::HeightMap;
using heightmap::HeightmapMode;
using heightmap::HeightmapOptions;
using heightmap::HeightmapPlan;
using heightmap::kMaxCellsPerSide;
using heightmap::planHeightmap;

constexpr double kPlanRes = MapGeometry::kDefaultResolution;
constexpr double kExtent = kPlanRes * MapGeometry::kDefaultRegionVoxels;  // 3.2 m
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
/// Coordinates computed from the grid and from the map agree to rounding only.
constexpr double kCoordTolerance = 1e-9;

std::unique_ptr<VoxelMap> makeMap(const MapConfig& config) {
  auto created = VoxelMap::create(config);
  EXPECT_TRUE(created) << created.error().message;
  if (!created) {
    return nullptr;
  }
  return std::make_unique<VoxelMap>(std::move(*created));
}

MapConfig smallGlobalConfig() {
  MapConfig config;
  config.memory_budget_bytes = std::uint64_t{64} << 20;
  return config;
}

/// A global map holding the eight regions around the origin: its bounds are [-3.2, 3.2) m on
/// every axis.
std::unique_ptr<VoxelMap> globalMap(const MapConfig& config = smallGlobalConfig()) {
  auto map = makeMap(config);
  if (map) {
    for (int x = -1; x <= 0; ++x) {
      for (int y = -1; y <= 0; ++y) {
        for (int z = -1; z <= 0; ++z) {
          EXPECT_TRUE(map->acquireRegion({x, y, z}));
        }
      }
    }
  }
  return map;
}

/// A rolling map, window 4 x 4 x 2 regions centred on the origin: x, y in [-6.4, 6.4) m, z in
/// [-3.2, 3.2) m.
std::unique_ptr<VoxelMap> rollingMap() {
  MapConfig config;
  config.policy = StorePolicy::kRolling;
  config.window_regions = {4, 4, 2};
  auto map = makeMap(config);
  if (map) {
    map->setWindowCentre({0.0, 0.0, 0.0});
  }
  return map;
}

HeightmapOptions request(Vec3d centre, double size) {
  HeightmapOptions o;
  o.centre = centre;
  o.size = size;
  return o;
}

/// Planning fails with `code` and a message holding every phrase, which names options by their
/// configuration keys (heightmap.size), never by the command line's flags (--size).
::testing::AssertionResult rejects(const VoxelMap& map, const HeightmapOptions& o, ErrorCode code,
                                   std::initializer_list<std::string_view> phrases) {
  HeightmapPlan plan;
  auto planned = planHeightmap(map, o, plan);
  if (planned) {
    return ::testing::AssertionFailure() << "planned without an error";
  }
  const Error& e = planned.error();
  if (e.code != code) {
    return ::testing::AssertionFailure() << "error code " << toString(e.code) << ", expected "
                                         << toString(code) << ": " << e.message;
  }
  for (std::string_view phrase : phrases) {
    if (e.message.find(phrase) == std::string::npos) {
      return ::testing::AssertionFailure() << "'" << phrase << "' not in: " << e.message;
    }
  }
  if (e.message.find("--") != std::string::npos) {
    return ::testing::AssertionFailure() << "a command-line flag in: " << e.message;
  }
  return ::testing::AssertionSuccess() << e.message;
}

::testing::AssertionResult plans(const VoxelMap& map, const HeightmapOptions& o) {
  HeightmapPlan plan;
  auto planned = planHeightmap(map, o, plan);
  if (!planned) {
    return ::testing::AssertionFailure() << planned.error().message;
  }
  return ::testing::AssertionSuccess();
}

HeightmapPlan planOrFail(const VoxelMap& map, const HeightmapOptions& o) {
  HeightmapPlan plan;
  auto planned = planHeightmap(map, o, plan);
  EXPECT_TRUE(planned) << planned.error().message;
  return plan;
}

void expectSamePlan(const HeightmapPlan& a, const HeightmapPlan& b) {
  // rm_heightmap_params is 25 four-byte fields: no padding, so bytes compare the values.
  static_assert(sizeof(rm_heightmap_params) == 25 * 4);
  EXPECT_EQ(std::memcmp(&a.params, &b.params, sizeof a.params), 0);
  EXPECT_EQ(a.region_table, b.region_table);
  EXPECT_EQ(a.region_slots, b.region_slots);
  EXPECT_EQ(a.grid.resolution, b.grid.resolution);
  EXPECT_EQ(a.grid.cells_x, b.grid.cells_x);
  EXPECT_EQ(a.grid.cells_y, b.grid.cells_y);
  EXPECT_EQ(a.grid.centre_x, b.grid.centre_x);
  EXPECT_EQ(a.grid.centre_y, b.grid.centre_y);
  EXPECT_EQ(a.grid.reference_z, b.grid.reference_z);
  EXPECT_EQ(a.grid.mode, b.grid.mode);
}

// ---------------------------------------------------------------------------------------------
// Requests refused

TEST(HeightmapPlanErrors, CentreOutsideTheStoredRegionsOfAGlobalMap) {
  auto map = globalMap();
  ASSERT_NE(map, nullptr);
  // The bounds are half open: the low faces are inside, the high faces outside.
  EXPECT_TRUE(plans(*map, request({-kExtent, -kExtent, -kExtent}, 2.0)));
  EXPECT_TRUE(plans(*map, request({kExtent - 0.01, kExtent - 0.01, kExtent - 0.01}, 2.0)));
  for (const Vec3d centre : {Vec3d{kExtent, 0.0, 0.0}, Vec3d{0.0, -kExtent - 0.01, 0.0},
                             Vec3d{0.0, 0.0, kExtent}, Vec3d{500.0, 0.0, 0.0}}) {
    SCOPED_TRACE(::testing::Message() << centre.x << ", " << centre.y << ", " << centre.z);
    EXPECT_TRUE(rejects(*map, request(centre, 2.0), ErrorCode::kInvalidArgument,
                        {"heightmap.centre: ", "outside the map"}));
  }
}

TEST(HeightmapPlanErrors, AnEmptyGlobalMapHasNoInside) {
  auto map = makeMap(smallGlobalConfig());
  ASSERT_NE(map, nullptr);
  EXPECT_TRUE(rejects(*map, request({0.0, 0.0, 0.0}, 2.0), ErrorCode::kInvalidArgument,
                      {"heightmap.centre: ", "outside the map"}));
}

TEST(HeightmapPlanErrors, CentreOutsideTheRollingWindow) {
  auto map = rollingMap();
  ASSERT_NE(map, nullptr);
  const auto [lo, hi] = map->windowBounds();
  ASSERT_EQ(lo.x, -2 * kExtent);
  ASSERT_EQ(hi.x, 2 * kExtent);
  // Inside the window: no region needs to be stored.
  EXPECT_TRUE(plans(*map, request({0.0, 0.0, 0.0}, 4.0)));
  EXPECT_TRUE(plans(*map, request({lo.x, lo.y, lo.z}, 4.0)));
  EXPECT_TRUE(rejects(*map, request({hi.x, 0.0, 0.0}, 4.0), ErrorCode::kInvalidArgument,
                      {"heightmap.centre: ", "outside the map"}));
  EXPECT_TRUE(rejects(*map, request({0.0, 0.0, hi.z + 1.0}, 4.0), ErrorCode::kInvalidArgument,
                      {"heightmap.centre: ", "outside the map"}));
  // The window follows the robot: the origin is left behind.
  map->setWindowCentre({40.0, 0.0, 0.0});
  EXPECT_TRUE(rejects(*map, request({0.0, 0.0, 0.0}, 4.0), ErrorCode::kInvalidArgument,
                      {"heightmap.centre: ", "outside the map"}));
  EXPECT_TRUE(plans(*map, request({40.0, 0.0, 0.0}, 4.0)));
}

TEST(HeightmapPlanErrors, SizeLargerThanTheRollingWindow) {
  auto map = rollingMap();
  ASSERT_NE(map, nullptr);
  const double window = 4 * kExtent;  // 12.8 m on x and y
  EXPECT_TRUE(plans(*map, request({0.0, 0.0, 0.0}, window)));
  EXPECT_TRUE(rejects(*map, request({0.0, 0.0, 0.0}, window + 0.1), ErrorCode::kInvalidArgument,
                      {"heightmap.size: ", "larger than the rolling window"}));
}

TEST(HeightmapPlanErrors, SizeBelowTheResolution) {
  auto map = globalMap();
  ASSERT_NE(map, nullptr);
  EXPECT_TRUE(plans(*map, request({0.0, 0.0, 0.0}, kPlanRes)));
  for (const double size : {0.5 * kPlanRes, 0.0, -1.0, kNaN, kInf, -kInf}) {
    SCOPED_TRACE(size);
    EXPECT_TRUE(rejects(*map, request({0.0, 0.0, 0.0}, size), ErrorCode::kInvalidArgument,
                        {"heightmap.size: ", "finite size of at least the map resolution"}));
  }
}

TEST(HeightmapPlanErrors, SizeAboveTheCellLimit) {
  auto map = globalMap();
  ASSERT_NE(map, nullptr);
  const double size = (kMaxCellsPerSide + 1) * kPlanRes;
  EXPECT_TRUE(rejects(*map, request({0.0, 0.0, 0.0}, size), ErrorCode::kInvalidArgument,
                      {"heightmap.size: ", std::to_string(kMaxCellsPerSide + 1) + " cells per side",
                       "at most " + std::to_string(kMaxCellsPerSide)}));
}

TEST(HeightmapPlanErrors, TheCellLimitItselfIsAccepted) {
  // Regions of 128^3 voxels keep the table of a 819.2 m cube small (65^3 entries); one region
  // of occupancy only (8 MiB) is the whole pool.
  MapConfig config;
  config.geometry.region_voxels = MapGeometry::kMaxRegionVoxels;
  config.voxel_mean = false;
  config.memory_budget_bytes = config.schema().bytesPerRegion(config.geometry.voxelsPerRegion());
  auto map = makeMap(config);
  ASSERT_NE(map, nullptr);
  ASSERT_TRUE(map->acquireRegion({0, 0, 0}));
  const HeightmapPlan plan =
      planOrFail(*map, request({1.0, 1.0, 1.0}, kMaxCellsPerSide * kPlanRes));
  EXPECT_EQ(plan.params.cells_x, kMaxCellsPerSide);
  EXPECT_EQ(plan.grid.cells_y, kMaxCellsPerSide);
  EXPECT_EQ(plan.region_slots.size(), 1u);
}

TEST(HeightmapPlanErrors, CentreMustBeFinite) {
  auto map = globalMap();
  ASSERT_NE(map, nullptr);
  for (const Vec3d centre :
       {Vec3d{kNaN, 0.0, 0.0}, Vec3d{0.0, kInf, 0.0}, Vec3d{0.0, 0.0, -kInf}}) {
    SCOPED_TRACE(::testing::Message() << centre.x << ", " << centre.y << ", " << centre.z);
    EXPECT_TRUE(rejects(*map, request(centre, 2.0), ErrorCode::kInvalidArgument,
                        {"heightmap.centre: ", "finite"}));
  }
}

TEST(HeightmapPlanErrors, NegativeClearanceFloorOrCeiling) {
  auto map = globalMap();
  ASSERT_NE(map, nullptr);
  HeightmapOptions zero = request({0.0, 0.0, 0.0}, 2.0);
  zero.min_clearance = 0.0;
  zero.floor_depth = 0.0;
  zero.ceiling_height = 0.0;
  EXPECT_TRUE(plans(*map, zero));
  for (const double bad : {-0.1, kNaN, kInf}) {
    SCOPED_TRACE(bad);
    HeightmapOptions o = request({0.0, 0.0, 0.0}, 2.0);
    o.min_clearance = bad;
    EXPECT_TRUE(rejects(*map, o, ErrorCode::kInvalidArgument,
                        {"heightmap.min_clearance: ", "must be >= 0"}));
    o = request({0.0, 0.0, 0.0}, 2.0);
    o.floor_depth = bad;
    EXPECT_TRUE(
        rejects(*map, o, ErrorCode::kInvalidArgument, {"heightmap.floor_depth: ", "must be >= 0"}));
    o = request({0.0, 0.0, 0.0}, 2.0);
    o.ceiling_height = bad;
    EXPECT_TRUE(rejects(*map, o, ErrorCode::kInvalidArgument,
                        {"heightmap.ceiling_height: ", "must be >= 0"}));
  }
}

TEST(HeightmapPlanErrors, MapWithoutAnOccupancyLayer) {
  const MapConfig config = smallGlobalConfig().forDecay();  // decay rates only
  auto map = globalMap(config);
  ASSERT_NE(map, nullptr);
  ASSERT_LT(map->occupancyLayer(), 0);
  EXPECT_TRUE(rejects(*map, request({0.0, 0.0, 0.0}, 2.0), ErrorCode::kUnsupported,
                      {"no occupancy layer"}));
}

TEST(HeightmapPlanErrors, MapWithoutAnOccupancyLayerAfterSaveAndLoad) {
  const MapConfig config = smallGlobalConfig().forDecay();  // decay rates only
  auto map = globalMap(config);
  ASSERT_NE(map, nullptr);
  test::TempDir dir;
  const std::string path = dir.file("no_occupancy.rmap");
  auto saved = io::saveMap(*map, path);
  ASSERT_TRUE(saved) << saved.error().message;

  auto loaded = io::loadMap(path);

  ASSERT_TRUE(loaded) << loaded.error().message;
  EXPECT_LT(loaded->occupancyLayer(), 0);
  EXPECT_FALSE(loaded->config().occupancy_layer);
  EXPECT_EQ(loaded->store().size(), 8u);
  EXPECT_TRUE(rejects(*loaded, request({0.0, 0.0, 0.0}, 2.0), ErrorCode::kUnsupported,
                      {"no occupancy layer"}));
}

// ---------------------------------------------------------------------------------------------
// The plan

TEST(HeightmapPlanGeometry, CellsAreTheSizeOverTheResolutionRounded) {
  auto map = globalMap();
  ASSERT_NE(map, nullptr);
  const std::pair<double, int> cases[] = {{0.1, 1},   {0.14, 1},  {0.16, 2},
                                          {2.04, 20}, {2.06, 21}, {5.0, 50}};
  for (const auto& [size, cells] : cases) {
    SCOPED_TRACE(size);
    const HeightmapPlan plan = planOrFail(*map, request({0.05, 0.05, 0.05}, size));
    EXPECT_EQ(plan.params.cells_x, cells);
    EXPECT_EQ(plan.params.cells_y, cells);
    EXPECT_EQ(plan.grid.cells_x, cells);
    EXPECT_EQ(plan.grid.cells_y, cells);
    EXPECT_EQ(plan.grid.resolution, kPlanRes);
    EXPECT_TRUE(plan.grid.elevation.empty());  // geometry only
  }
}

TEST(HeightmapPlanGeometry, TheCentresColumnIsTheSeedCell) {
  auto map = globalMap();
  ASSERT_NE(map, nullptr);
  // Centres inside voxels; a centre on a voxel face is the disabled test below.
  for (const double size : {1.0, 1.1}) {  // even and odd cell counts
    for (const Vec3d centre :
         {Vec3d{0.05, 0.05, 0.0}, Vec3d{-1.234, 2.71, -0.4}, Vec3d{2.96, -3.13, 1.5}}) {
      SCOPED_TRACE(::testing::Message() << "size " << size << " centre " << centre.x << ", "
                                        << centre.y << ", " << centre.z);
      const HeightmapPlan plan = planOrFail(*map, request(centre, size));
      const rm_heightmap_params& p = plan.params;
      const HeightMap& g = plan.grid;
      const Vec3i voxel = map->voxelOf(centre);
      // Cell i covers voxel x0 - i: the seed cell covers the centre's voxel.
      EXPECT_EQ(p.voxel_x0 - p.seed_i, voxel.x);
      EXPECT_EQ(p.voxel_y0 - p.seed_j, voxel.y);
      int i = -1;
      int j = -1;
      ASSERT_TRUE(g.cellOf(centre.x, centre.y, &i, &j));
      EXPECT_EQ(i, p.seed_i);
      EXPECT_EQ(j, p.seed_j);
      const Vec3d seed_centre = g.cellCentre(p.seed_i, p.seed_j);
      EXPECT_NEAR(seed_centre.x, map->voxelCentre(voxel).x, kCoordTolerance);
      EXPECT_NEAR(seed_centre.y, map->voxelCentre(voxel).y, kCoordTolerance);
      // The centre's column is in the middle: on the grid's centre for an odd count, just +x/+y
      // of it (its min corner on the grid's centre) for an even one.
      const Vec3d anchor =
          g.cells_x % 2 == 1 ? map->voxelCentre(voxel) : map->voxelMinCorner(voxel);
      EXPECT_NEAR(g.centre_x, anchor.x, kCoordTolerance);
      EXPECT_NEAR(g.centre_y, anchor.y, kCoordTolerance);
      EXPECT_EQ(g.reference_z, centre.z);
      EXPECT_FLOAT_EQ(p.reference_z, static_cast<float>(centre.z));
    }
  }
}

// A centre on a voxel face (any typed multiple of the resolution, e.g. --center 3,0,0) is in
// voxel floor(x * (1 / res)) for VoxelMap::voxelOf(), which the plan seeds from; cellOf() must
// agree.
TEST(HeightmapPlanGeometry, ACentreOnAVoxelFaceIsInTheSeedCell) {
  auto map = globalMap();
  ASSERT_NE(map, nullptr);
  for (const double size : {1.0, 1.1, 8.0}) {
    for (const Vec3d centre :
         {Vec3d{3.0, -3.1, 0.0}, Vec3d{0.3, 0.7, 0.0}, Vec3d{-1.2, 2.0, 0.0}}) {
      SCOPED_TRACE(::testing::Message()
                   << "size " << size << " centre " << centre.x << ", " << centre.y);
      const HeightmapPlan plan = planOrFail(*map, request(centre, size));
      int i = -1;
      int j = -1;
      ASSERT_TRUE(plan.grid.cellOf(centre.x, centre.y, &i, &j));
      EXPECT_EQ(i, plan.params.seed_i);
      EXPECT_EQ(j, plan.params.seed_j);
    }
  }
}

TEST(HeightmapPlanGeometry, EveryCellCentreLiesInItsOwnCellAndVoxelColumn) {
  auto map = globalMap();
  ASSERT_NE(map, nullptr);
  for (const double size : {1.1, 1.2}) {
    SCOPED_TRACE(size);
    const HeightmapPlan plan = planOrFail(*map, request({-0.37, 0.82, 0.0}, size));
    const HeightMap& g = plan.grid;
    for (int j = 0; j < g.cells_y; ++j) {
      for (int i = 0; i < g.cells_x; ++i) {
        const Vec3d c = g.cellCentre(i, j);
        int ci = -1;
        int cj = -1;
        ASSERT_TRUE(g.cellOf(c.x, c.y, &ci, &cj)) << i << ", " << j;
        EXPECT_EQ(ci, i);
        EXPECT_EQ(cj, j);
        // The cell is the voxel column the kernel searches for it.
        const Vec3d voxel_centre =
            map->voxelCentre({plan.params.voxel_x0 - i, plan.params.voxel_y0 - j, 0});
        EXPECT_NEAR(c.x, voxel_centre.x, kCoordTolerance) << i << ", " << j;
        EXPECT_NEAR(c.y, voxel_centre.y, kCoordTolerance) << i << ", " << j;
      }
    }
    // (0, 0) is the +x/+y corner; points beyond the grid's edges have no cell.
    const Vec3d corner = g.cellCentre(0, 0);
    const Vec3d far = g.cellCentre(g.cells_x - 1, g.cells_y - 1);
    EXPECT_GT(corner.x, far.x);
    EXPECT_GT(corner.y, far.y);
    int i = 0;
    int j = 0;
    EXPECT_FALSE(g.cellOf(corner.x + kPlanRes, corner.y, &i, &j));
    EXPECT_FALSE(g.cellOf(corner.x, corner.y + kPlanRes, &i, &j));
    EXPECT_FALSE(g.cellOf(far.x - kPlanRes, far.y, &i, &j));
    EXPECT_FALSE(g.cellOf(far.x, far.y - kPlanRes, &i, &j));
  }
}

TEST(HeightmapPlanGeometry, RegionTableHoldsSlotIndicesForPresentRegionsOnly) {
  MapConfig config = smallGlobalConfig();
  auto map = makeMap(config);
  ASSERT_NE(map, nullptr);
  // A region far outside the box first, so store slots and table indices differ; then some of
  // the box's regions, not in table order.
  for (const Vec3i region :
       {Vec3i{5, 5, 5}, Vec3i{0, 0, 0}, Vec3i{-1, 0, -1}, Vec3i{0, -1, 0}, Vec3i{-1, -1, -1}}) {
    ASSERT_TRUE(map->acquireRegion(region));
  }
  const Vec3d centre{0.05, 0.05, 0.05};
  const double size = 6.0;

  const HeightmapPlan plan = planOrFail(*map, request(centre, size));

  const rm_heightmap_params& p = plan.params;
  // The table spans the box: the grid's columns, and z from one voxel below its bottom (the
  // search looks at the voxel under a candidate) to its top.
  const Vec3i voxel = map->voxelOf(centre);
  const auto half = static_cast<std::int32_t>(std::lround(0.5 * size / kPlanRes));
  EXPECT_EQ(p.box_z_min, voxel.z - half);
  EXPECT_EQ(p.box_z_max, voxel.z + half);
  const Vec3i lo =
      map->regionOfVoxel({p.voxel_x0 - p.cells_x + 1, p.voxel_y0 - p.cells_y + 1, p.box_z_min - 1});
  const Vec3i hi = map->regionOfVoxel({p.voxel_x0, p.voxel_y0, p.box_z_max});
  EXPECT_EQ((Vec3i{p.region_x0, p.region_y0, p.region_z0}), lo);
  EXPECT_EQ((Vec3i{p.regions_x, p.regions_y, p.regions_z}), (hi - lo + Vec3i{1, 1, 1}));
  EXPECT_EQ(p.region_voxels, MapGeometry::kDefaultRegionVoxels);
  ASSERT_EQ(plan.region_table.size(), static_cast<std::size_t>(p.regions_x) *
                                          static_cast<std::size_t>(p.regions_y) *
                                          static_cast<std::size_t>(p.regions_z));

  std::vector<int> uses(plan.region_slots.size(), 0);
  std::size_t present = 0;
  std::size_t t = 0;
  for (std::int32_t z = 0; z < p.regions_z; ++z) {
    for (std::int32_t y = 0; y < p.regions_y; ++y) {
      for (std::int32_t x = 0; x < p.regions_x; ++x, ++t) {  // x fastest
        const Vec3i region{p.region_x0 + x, p.region_y0 + y, p.region_z0 + z};
        const std::uint32_t slot = map->store().find(region);
        const std::uint32_t entry = plan.region_table[t];
        SCOPED_TRACE(::testing::Message()
                     << "region " << region.x << ", " << region.y << ", " << region.z);
        if (slot == RegionStore::kNoSlot) {
          EXPECT_EQ(entry, RM_HM_NO_REGION);
          continue;
        }
        ++present;
        ASSERT_LT(entry, plan.region_slots.size());
        EXPECT_EQ(plan.region_slots[entry], slot);
        ++uses[entry];
      }
    }
  }
  // The four regions under the box, each once; the far region is not in the plan.
  EXPECT_EQ(present, 4u);
  EXPECT_EQ(plan.region_slots.size(), 4u);
  for (const int n : uses) {
    EXPECT_EQ(n, 1);
  }
}

TEST(HeightmapPlanGeometry, LimitsAndFlagsFollowTheRequest) {
  auto map = globalMap();
  ASSERT_NE(map, nullptr);
  HeightmapOptions o = request({0.0, 0.0, 0.3}, 4.0);
  HeightmapPlan plan = planOrFail(*map, o);
  EXPECT_FLOAT_EQ(plan.params.floor_depth, 2.0f);  // default: size / 2
  EXPECT_FLOAT_EQ(plan.params.ceiling_height, 2.0f);
  EXPECT_FLOAT_EQ(plan.params.min_clearance,
                  static_cast<float>(HeightmapOptions::kDefaultMinClearance));
  EXPECT_EQ(plan.params.occupied_threshold, map->occupancy().threshold);
  // Planar, no virtual surfaces; the map has means: heights and sample counts from them.
  EXPECT_EQ(plan.params.flags, RM_HM_FLAG_MEAN | RM_HM_FLAG_SAMPLES);
  EXPECT_EQ(plan.grid.mode, HeightmapMode::kPlanar);

  o.floor_depth = 0.7;
  o.ceiling_height = 1.9;
  o.min_clearance = 0.25;
  o.mode = HeightmapMode::kFill;
  o.virtual_surfaces = true;
  o.use_voxel_mean = false;
  plan = planOrFail(*map, o);
  EXPECT_FLOAT_EQ(plan.params.floor_depth, 0.7f);
  EXPECT_FLOAT_EQ(plan.params.ceiling_height, 1.9f);
  EXPECT_FLOAT_EQ(plan.params.min_clearance, 0.25f);
  EXPECT_EQ(plan.params.flags, RM_HM_FLAG_FILL | RM_HM_FLAG_VIRTUAL | RM_HM_FLAG_SAMPLES);
  EXPECT_EQ(plan.grid.mode, HeightmapMode::kFill);

  // Asking for means from a map without them is no error; the flag stays off.
  MapConfig no_mean = smallGlobalConfig();
  no_mean.voxel_mean = false;
  auto plain = globalMap(no_mean);
  ASSERT_NE(plain, nullptr);
  EXPECT_EQ(planOrFail(*plain, request({0.0, 0.0, 0.0}, 2.0)).params.flags & RM_HM_FLAG_MEAN, 0);
}

TEST(HeightmapPlanGeometry, PlanningAgainIntoTheSamePlanGivesTheSameResult) {
  auto map = globalMap();
  ASSERT_NE(map, nullptr);
  const HeightmapOptions small = request({0.05, -0.35, 0.0}, 2.0);
  const HeightmapOptions large = request({-1.0, 1.0, 0.5}, 6.0);
  const HeightmapPlan fresh_small = planOrFail(*map, small);
  const HeightmapPlan fresh_large = planOrFail(*map, large);
  ASSERT_GT(fresh_large.region_table.size(), fresh_small.region_table.size());

  HeightmapPlan reused;
  for (int round = 0; round < 2; ++round) {
    SCOPED_TRACE(round);
    ASSERT_TRUE(planHeightmap(*map, small, reused));
    expectSamePlan(reused, fresh_small);
    ASSERT_TRUE(planHeightmap(*map, small, reused));
    expectSamePlan(reused, fresh_small);
    // A larger plan and then a smaller one again: nothing of the larger one is left over.
    ASSERT_TRUE(planHeightmap(*map, large, reused));
    expectSamePlan(reused, fresh_large);
  }
  ASSERT_TRUE(planHeightmap(*map, small, reused));
  expectSamePlan(reused, fresh_small);
  EXPECT_TRUE(reused.grid.elevation.empty());
}

}  // namespace
}  // namespace raymap
