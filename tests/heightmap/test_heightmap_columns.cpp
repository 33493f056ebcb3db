// SPDX-License-Identifier: BSD-3-Clause
// The column search on hand-built voxel columns, with exact expectations, for every generator.
#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "kernels/common/key_math.h"
#include "src/heightmap/heightmap_plan.hpp"
#include "tests/heightmap/column_map.hpp"
#include "tests/heightmap/heightmap_generators.hpp"

namespace raymap {
namespace {

using heightmap::CellKind;
using heightmap::HeightMap;
using heightmap::HeightmapMode;
using heightmap::HeightmapOptions;

using test::ColumnMap;
constexpr float kColumnOccupied = ColumnMap::kOccupied;
constexpr double kRes = 0.1;

class HeightmapColumns : public ::testing::TestWithParam<std::string> {
 protected:
  HeightmapOptions options() const {
    HeightmapOptions o;
    o.centre = {0.05, 0.05, 0.0};
    o.size = 2.0;
    o.min_clearance = 0.5;
    return o;
  }
  /// Generates with the parametrised generator; fails the test on error.
  HeightMap generate(ColumnMap& m, const HeightmapOptions& o) {
    std::string why;
    heightmap::HeightmapGenerator* g = test::heightmapGenerator(GetParam(), &why);
    EXPECT_NE(g, nullptr) << why;
    heightmap::HeightmapPlan plan;
    auto planned = heightmap::planHeightmap(m.map(), o, plan);
    EXPECT_TRUE(planned) << planned.error().message;
    HeightMap out;
    auto ok = g->generate(m.map(), plan, out);
    EXPECT_TRUE(ok) << ok.error().message;
    return out;
  }
  struct Cell {
    float elevation;
    float clearance;
    CellKind kind;
    std::uint32_t samples;
  };
  static Cell at(const HeightMap& h, int vx, int vy) {
    int i = 0;
    int j = 0;
    EXPECT_TRUE(h.cellOf((vx + 0.5) * kRes, (vy + 0.5) * kRes, &i, &j));
    const std::size_t n = h.index(i, j);
    return {h.elevation[n], h.clearance[n], static_cast<CellKind>(h.kind[n]), h.observed_count[n]};
  }
};

#define SKIP_UNAVAILABLE()                      \
  REQUIRE_HEIGHTMAP_GENERATOR(GetParam(), gen); \
  (void)gen

TEST_P(HeightmapColumns, FlatGroundUsesTheVoxelMeanAndIsOpenAbove) {
  SKIP_UNAVAILABLE();
  ColumnMap m;
  m.occupied(0, 0, -1, 0.9f);
  m.freeRange(0, 0, 0, 9);
  const Cell c = at(generate(m, options()), 0, 0);
  EXPECT_EQ(c.kind, CellKind::kSurface);
  EXPECT_NEAR(c.elevation, -0.1 + 0.09, 1e-3);
  EXPECT_TRUE(std::isinf(c.clearance));
  EXPECT_EQ(c.samples, 3u);
}

TEST_P(HeightmapColumns, WithoutMeansTheVoxelCentreIsTheHeight) {
  SKIP_UNAVAILABLE();
  ColumnMap m;
  m.occupied(0, 0, 2);
  HeightmapOptions o = options();
  const Cell c = at(generate(m, o), 0, 0);
  EXPECT_EQ(c.kind, CellKind::kSurface);
  EXPECT_NEAR(c.elevation, 0.25, 1e-6);
  EXPECT_EQ(c.samples, 0u);
}

TEST_P(HeightmapColumns, UnderATableTheGroundWithTheTablesClearance) {
  SKIP_UNAVAILABLE();
  ColumnMap m;
  m.occupied(1, 1, -1, 1.0f);  // ground surface at z = 0
  m.freeRange(1, 1, 0, 6);
  m.occupied(1, 1, 7, 0.5f);  // table top at 0.75
  m.freeRange(1, 1, 8, 9);
  HeightmapOptions o = options();
  Cell c = at(generate(m, o), 1, 1);
  EXPECT_EQ(c.kind, CellKind::kSurface);
  EXPECT_NEAR(c.elevation, 0.0, 1e-3);
  EXPECT_NEAR(c.clearance, 0.7, 1e-3);  // up to the table's bottom face
  // A robot taller than the gap stands on nothing here: the table top is the surface.
  o.min_clearance = 1.0;
  c = at(generate(m, o), 1, 1);
  EXPECT_EQ(c.kind, CellKind::kSurface);
  EXPECT_NEAR(c.elevation, 0.75, 1e-3);
  EXPECT_TRUE(std::isinf(c.clearance));
}

TEST_P(HeightmapColumns, BoxTopOverUnobservedInterior) {
  SKIP_UNAVAILABLE();
  ColumnMap m;
  m.occupied(-2, 3, 9, 0.95f);  // top face of a 1 m box; inside never seen
  m.freeRange(-2, 3, 10, 12);
  const Cell c = at(generate(m, options()), -2, 3);
  EXPECT_EQ(c.kind, CellKind::kSurface);
  EXPECT_NEAR(c.elevation, 0.995, 1e-3);
}

TEST_P(HeightmapColumns, NearestQualifyingSurfaceToTheReferenceWins) {
  SKIP_UNAVAILABLE();
  ColumnMap m;
  m.occupied(0, 2, -1, 1.0f);  // ground at 0
  m.freeRange(0, 2, 0, 5);
  m.occupied(0, 2, 6, 0.5f);  // a platform at 0.65, seen from above
  m.freeRange(0, 2, 7, 9);
  HeightmapOptions o = options();
  o.min_clearance = 0.3;
  EXPECT_NEAR(at(generate(m, o), 0, 2).elevation, 0.0, 1e-3);
  o.centre.z = 0.4;  // closer to the platform
  EXPECT_NEAR(at(generate(m, o), 0, 2).elevation, 0.65, 1e-3);
  o.ceiling_height = 0.2;  // the platform's voxel centre is above 0.6: out of range
  EXPECT_NEAR(at(generate(m, o), 0, 2).elevation, 0.0, 1e-3);
}

TEST_P(HeightmapColumns, DitchGivesAVirtualSurfaceOnlyWhenAsked) {
  SKIP_UNAVAILABLE();
  ColumnMap m;
  m.freeRange(2, 0, -5, 9);  // free down to -0.5; below never seen
  HeightmapOptions o = options();
  Cell c = at(generate(m, o), 2, 0);
  EXPECT_EQ(c.kind, CellKind::kUnknown);
  EXPECT_TRUE(std::isnan(c.elevation));
  EXPECT_TRUE(std::isnan(c.clearance));
  o.virtual_surfaces = true;
  c = at(generate(m, o), 2, 0);
  EXPECT_EQ(c.kind, CellKind::kVirtualSurface);
  EXPECT_NEAR(c.elevation, -0.5, 1e-6);  // the bottom face of the lowest free voxel
  EXPECT_TRUE(std::isinf(c.clearance));
  EXPECT_EQ(c.samples, 0u);
}

TEST_P(HeightmapColumns, FreeDownToTheFloorLimitIsVacant) {
  SKIP_UNAVAILABLE();
  ColumnMap m;
  m.freeRange(2, 0, -5, 9);
  HeightmapOptions o = options();
  o.floor_depth = 0.3;  // the search ends at -0.3: all free there
  o.virtual_surfaces = true;
  const Cell c = at(generate(m, o), 2, 0);
  EXPECT_EQ(c.kind, CellKind::kVacant);
  EXPECT_TRUE(std::isnan(c.elevation));
}

TEST_P(HeightmapColumns, AShadowAboveTheReferenceStaysUnknown) {
  SKIP_UNAVAILABLE();
  ColumnMap m;
  m.freeRange(-1, -1, 5, 9);  // seen from 0.5 up; nothing below
  HeightmapOptions o = options();
  o.virtual_surfaces = true;
  const Cell c = at(generate(m, o), -1, -1);
  EXPECT_EQ(c.kind, CellKind::kUnknown);
  EXPECT_TRUE(std::isnan(c.elevation));
}

TEST_P(HeightmapColumns, ASurfaceBeatsAVirtualSurfaceAtTheSameDistance) {
  SKIP_UNAVAILABLE();
  ColumnMap m;
  // Virtual candidate at -0.2 (free over unseen) and a surface at +0.2 (voxel centre 0.15+0.05).
  m.freeRange(3, 3, -2, 0);
  m.set(3, 3, 1, kColumnOccupied, 1.0f);  // height 0.2 exactly
  m.freeRange(3, 3, 2, 9);
  HeightmapOptions o = options();
  o.virtual_surfaces = true;
  o.min_clearance = 0.0;
  const Cell c = at(generate(m, o), 3, 3);
  EXPECT_EQ(c.kind, CellKind::kSurface);
  EXPECT_NEAR(c.elevation, 0.2, 1e-3);
}

TEST_P(HeightmapColumns, ACeilingSeenOnlyFromBelowIsNoSurface) {
  SKIP_UNAVAILABLE();
  ColumnMap m;
  // Free from 0.2 m up to a ceiling at 2.5 m whose top was never seen; the floor never hit.
  m.freeRange(1, -1, 2, 23);
  m.occupied(1, -1, 24, 0.9f);  // hits on both sides of a voxel face: a run of two
  m.occupied(1, -1, 25, 0.1f);
  HeightmapOptions o = options();
  o.size = 6.0;  // the box reaches 3 m up
  Cell c = at(generate(m, o), 1, -1);
  EXPECT_EQ(c.kind, CellKind::kUnknown);
  // With the floor seen: the floor, with the ceiling as its clearance.
  m.occupied(1, -1, 1, 0.5f);
  c = at(generate(m, o), 1, -1);
  EXPECT_EQ(c.kind, CellKind::kSurface);
  EXPECT_NEAR(c.elevation, 0.15, 1e-3);
  EXPECT_NEAR(c.clearance, 2.25, 1e-3);
  // The same slab seen from above (free over it) is a surface again: a platform.
  ColumnMap platform;
  platform.freeRange(1, -1, 2, 24);
  platform.occupied(1, -1, 25, 0.9f);
  platform.freeRange(1, -1, 26, 30);
  HeightmapOptions high = o;
  high.centre.z = 2.5;
  c = at(generate(platform, high), 1, -1);
  EXPECT_EQ(c.kind, CellKind::kSurface);
  EXPECT_NEAR(c.elevation, 2.59, 1e-3);
}

TEST_P(HeightmapColumns, UnobservedColumnsAreUnknownNaN) {
  SKIP_UNAVAILABLE();
  ColumnMap m;
  m.occupied(0, 0, -1, 1.0f);
  const HeightMap h = generate(m, options());
  std::size_t unknown = 0;
  for (std::size_t n = 0; n < h.cellCount(); ++n) {
    if (h.kind[n] == RM_HM_UNKNOWN) {
      ++unknown;
      EXPECT_TRUE(std::isnan(h.elevation[n]));
      EXPECT_TRUE(std::isnan(h.clearance[n]));
    }
  }
  EXPECT_EQ(unknown, h.cellCount() - 1);
}

TEST_P(HeightmapColumns, GridMapLayoutCornerAndOrder) {
  SKIP_UNAVAILABLE();
  ColumnMap m;
  // 2 m at 0.1 m: 20 x 20 cells over voxels -10..9; (0,0) is the +x/+y corner voxel (9, 9).
  m.occupied(9, 9, 0);
  m.occupied(8, 9, 1);  // next along -x: i = 1
  m.occupied(9, 8, 2);  // next along -y: j = 1
  const HeightMap h = generate(m, options());
  ASSERT_EQ(h.cells_x, 20);
  EXPECT_NEAR(h.elevation[0], 0.05, 1e-6);
  EXPECT_NEAR(h.elevation[1], 0.15, 1e-6);
  EXPECT_NEAR(h.elevation[20], 0.25, 1e-6);
  const Vec3d corner = h.cellCentre(0, 0);
  EXPECT_NEAR(corner.x, 0.95, 1e-9);
  EXPECT_NEAR(corner.y, 0.95, 1e-9);
}

TEST_P(HeightmapColumns, FloodFillFollowsARampPlanarDoesNot) {
  SKIP_UNAVAILABLE();
  ColumnMap m;
  // A ramp rising 0.1 m per column along +x, 3 columns wide, from x = 0 to 9 (top 0.95 m).
  for (int x = -10; x <= 9; ++x) {
    for (int y = -1; y <= 1; ++y) {
      const int z = std::max(x, 0) - 1;
      m.occupied(x, y, z, 0.95f);
      m.freeRange(x, y, z + 1, z + 12);
    }
  }
  HeightmapOptions o = options();
  o.floor_depth = 0.25;
  o.ceiling_height = 0.25;
  o.mode = HeightmapMode::kPlanar;
  EXPECT_EQ(at(generate(m, o), 8, 0).kind, CellKind::kUnknown);  // 0.75 m: out of the band
  o.mode = HeightmapMode::kFill;
  const HeightMap h = generate(m, o);
  for (int x = 0; x <= 9; ++x) {
    const Cell c = at(h, x, 0);
    EXPECT_EQ(c.kind, CellKind::kSurface) << "x voxel " << x;
    EXPECT_NEAR(c.elevation, (x - 1) * kRes + 0.095, 1e-3) << "x voxel " << x;
  }
}

TEST_P(HeightmapColumns, DeviceGeneratorsCountWhatTheyCopyTheCpuNothing) {
  SKIP_UNAVAILABLE();
  ColumnMap m;
  m.occupied(0, 0, -1, 0.9f);
  const std::uint64_t before = gen->bytesCopied();
  const HeightMap h = generate(m, options());
  const std::uint64_t copied = gen->bytesCopied() - before;
  if (GetParam() == "cpu") {
    EXPECT_EQ(copied, 0u);
  } else {
    // The five output layers read back, and the regions under the map uploaded.
    EXPECT_GT(copied, std::uint64_t{h.cellCount()} * 4 * 5) << GetParam();
  }
}

INSTANTIATE_TEST_SUITE_P(Generators, HeightmapColumns,
                         ::testing::ValuesIn(test::heightmapGeneratorNames()),
                         [](const ::testing::TestParamInfo<std::string>& param_info) {
                           return param_info.param;
                         });

}  // namespace
}  // namespace raymap
