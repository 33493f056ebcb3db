// SPDX-License-Identifier: BSD-3-Clause
// computeCostmap: what is lethal (holes, steps, slopes, low clearance), unknown, and how free
// cells are scaled, in nav_msgs/OccupancyGrid's layout.
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>

#include "src/heightmap/costmap.hpp"

namespace raymap::heightmap {
namespace {

constexpr double kRes = 0.1;
constexpr int kCells = 20;  // 2 m square, centred on (1, 2)

/// Flat open ground everywhere: surfaces at z = 0 with unlimited clearance.
HeightMap flatGround() {
  HeightMap m;
  m.resolution = kRes;
  m.cells_x = kCells;
  m.cells_y = kCells;
  m.centre_x = 1.0;
  m.centre_y = 2.0;
  m.resizeLayers();
  for (std::size_t c = 0; c < m.cellCount(); ++c) {
    m.elevation[c] = 0.0f;
    m.clearance[c] = std::numeric_limits<float>::infinity();
    m.kind[c] = static_cast<std::uint32_t>(CellKind::kSurface);
  }
  return m;
}

/// The cost of the cell holding world (x, y), read through OccupancyGrid's layout.
std::int8_t costAt(const HeightMap& m, const std::vector<std::int8_t>& cells, double x, double y) {
  const Vec3d origin = costmapOrigin(m);
  const auto column = static_cast<std::size_t>(std::floor((x - origin.x) / m.resolution));
  const auto row = static_cast<std::size_t>(std::floor((y - origin.y) / m.resolution));
  return cells.at(row * static_cast<std::size_t>(m.cells_x) + column);
}

std::vector<std::int8_t> costmapOf(const HeightMap& m, const CostmapParams& p = {}) {
  std::vector<std::int8_t> cells(m.cellCount(), 42);
  computeCostmap(m, p, cells);
  return cells;
}

void setAt(HeightMap& m, double x, double y, CellKind kind, float z, float clearance) {
  int i = 0;
  int j = 0;
  ASSERT_TRUE(m.cellOf(x, y, &i, &j));
  m.kind[m.index(i, j)] = static_cast<std::uint32_t>(kind);
  m.elevation[m.index(i, j)] = z;
  m.clearance[m.index(i, j)] = clearance;
}

TEST(Costmap, FlatOpenGroundIsFreeAndTheOriginIsTheMinusXMinusYCorner) {
  const HeightMap m = flatGround();
  const std::vector<std::int8_t> cells = costmapOf(m);
  for (const std::int8_t c : cells) {
    EXPECT_EQ(c, 0);
  }
  const Vec3d origin = costmapOrigin(m);
  EXPECT_DOUBLE_EQ(origin.x, 0.0);
  EXPECT_DOUBLE_EQ(origin.y, 1.0);
}

TEST(Costmap, CellsLandWhereOccupancyGridPutsThem) {
  // One hole near the +x/-y corner: found at its world position through the grid's layout,
  // and nowhere else.
  HeightMap m = flatGround();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  setAt(m, 1.85, 1.25, CellKind::kVacant, nan, nan);
  const std::vector<std::int8_t> cells = costmapOf(m);
  EXPECT_EQ(costAt(m, cells, 1.85, 1.25), kCostLethal);
  EXPECT_EQ(cells[2 * kCells + 18], kCostLethal);  // row 2 (y 1.2-1.3), column 18 (x 1.8-1.9)
  int lethal = 0;
  for (const std::int8_t c : cells) {
    lethal += c == kCostLethal ? 1 : 0;
  }
  EXPECT_EQ(lethal, 1);
}

TEST(Costmap, UnknownIsUnknownAndVirtualSurfacesAreLethalOrUnknownBySetting) {
  HeightMap m = flatGround();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  setAt(m, 0.55, 1.55, CellKind::kUnknown, nan, nan);
  setAt(m, 1.55, 2.55, CellKind::kVirtualSurface, 0.0f, std::numeric_limits<float>::infinity());
  EXPECT_EQ(costAt(m, costmapOf(m), 0.55, 1.55), kCostUnknown);
  EXPECT_EQ(costAt(m, costmapOf(m), 1.55, 2.55), kCostLethal);
  CostmapParams p;
  p.virtual_lethal = false;
  EXPECT_EQ(costAt(m, costmapOf(m, p), 1.55, 2.55), kCostUnknown);
}

TEST(Costmap, AStepAboveMaxStepIsLethalOnBothSidesAndASmallOneIsNot) {
  HeightMap m = flatGround();
  const float open = std::numeric_limits<float>::infinity();
  setAt(m, 1.05, 2.05, CellKind::kSurface, 0.3f, open);  // a 0.3 m box, one cell
  setAt(m, 0.45, 1.45, CellKind::kSurface, 0.1f, open);  // a 0.1 m bump
  const std::vector<std::int8_t> cells = costmapOf(m);
  EXPECT_EQ(costAt(m, cells, 1.05, 2.05), kCostLethal);
  EXPECT_EQ(costAt(m, cells, 1.15, 2.05), kCostLethal);  // its neighbour steps up to it
  EXPECT_EQ(costAt(m, cells, 1.05, 1.95), kCostLethal);
  EXPECT_EQ(costAt(m, cells, 1.15, 2.15), 0);  // diagonal: no step across an edge
  EXPECT_NE(costAt(m, cells, 0.45, 1.45), kCostLethal);
  EXPECT_NE(costAt(m, cells, 0.55, 1.45), kCostLethal);
}

TEST(Costmap, FreeCellsScaleWithSlopeUpToTheLethalSlope) {
  // A ramp along x: 20 degrees costs round(50 * 20 / 30) = 33 inside it; 40 degrees is lethal.
  for (const double degrees : {20.0, 40.0}) {
    HeightMap m = flatGround();
    const double rise = std::tan(degrees * std::numbers::pi / 180.0) * kRes;
    for (int j = 0; j < kCells; ++j) {
      for (int i = 0; i < kCells; ++i) {
        m.elevation[m.index(i, j)] = static_cast<float>(m.cellCentre(i, j).x * rise / kRes);
      }
    }
    CostmapParams p;
    p.max_step_m = 1.0;  // the slope rule, not the step rule
    const std::vector<std::int8_t> cells = costmapOf(m, p);
    EXPECT_EQ(costAt(m, cells, 1.05, 2.05), degrees < 30.0 ? 33 : kCostLethal) << degrees;
  }
}

TEST(Costmap, ClearanceBelowTheRobotIsLethal) {
  HeightMap m = flatGround();
  setAt(m, 1.05, 2.05, CellKind::kSurface, 0.0f, 0.3f);  // under a table
  setAt(m, 1.25, 2.05, CellKind::kSurface, 0.0f, 0.8f);  // under an arch
  const std::vector<std::int8_t> cells = costmapOf(m);
  EXPECT_EQ(costAt(m, cells, 1.05, 2.05), kCostLethal);
  EXPECT_EQ(costAt(m, cells, 1.25, 2.05), 0);
}

}  // namespace
}  // namespace raymap::heightmap
