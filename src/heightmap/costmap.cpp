// SPDX-License-Identifier: BSD-3-Clause
// computeCostmap: lethal steps, slopes, clearances and holes; free cells scaled by slope.
#include "src/heightmap/costmap.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace raymap::heightmap {
namespace {

/// The elevation of cell (i, j) when it has one (a surface or a virtual surface), else NaN.
float heightAt(const HeightMap& map, int i, int j) noexcept {
  if (i < 0 || j < 0 || i >= map.cells_x || j >= map.cells_y) {
    return std::numeric_limits<float>::quiet_NaN();
  }
  return map.elevation[map.index(i, j)];
}

/// The elevation's derivative along one axis at a cell of height z, from its neighbours before
/// (`a`) and after (`b`) on that axis, per metre; 0 when neither has an elevation.
double derivative(float a, float z, float b, double resolution) noexcept {
  if (!std::isnan(a) && !std::isnan(b)) {
    return (static_cast<double>(b) - static_cast<double>(a)) / (2.0 * resolution);
  }
  if (!std::isnan(b)) {
    return (static_cast<double>(b) - static_cast<double>(z)) / resolution;
  }
  if (!std::isnan(a)) {
    return (static_cast<double>(z) - static_cast<double>(a)) / resolution;
  }
  return 0.0;
}

std::int8_t surfaceCost(const HeightMap& map, const CostmapParams& params, int i, int j) noexcept {
  const std::size_t c = map.index(i, j);
  const float z = map.elevation[c];
  if (std::isnan(z)) {
    return kCostUnknown;  // a surface without an elevation: nothing to stand on that is known
  }
  if (static_cast<double>(map.clearance[c]) < params.min_clearance_m) {
    return kCostLethal;  // NaN clearance compares false: only a measured lack of room is lethal
  }
  const float west = heightAt(map, i + 1, j);  // i counts along -x
  const float east = heightAt(map, i - 1, j);
  const float south = heightAt(map, i, j + 1);  // j counts along -y
  const float north = heightAt(map, i, j - 1);
  for (const float n : {west, east, south, north}) {
    if (!std::isnan(n) &&
        std::fabs(static_cast<double>(n) - static_cast<double>(z)) > params.max_step_m) {
      return kCostLethal;
    }
  }
  const double gx = derivative(west, z, east, map.resolution);
  const double gy = derivative(south, z, north, map.resolution);
  const double slope_deg = std::atan(std::hypot(gx, gy)) * 180.0 / std::numbers::pi;
  if (slope_deg > params.max_slope_deg) {
    return kCostLethal;
  }
  const double scaled =
      params.max_slope_deg > 0.0 ? slope_deg / params.max_slope_deg * params.max_free_cost : 0.0;
  return static_cast<std::int8_t>(std::clamp(std::lround(scaled), 0L, 99L));
}

}  // namespace

void computeCostmap(const HeightMap& map, const CostmapParams& params,
                    std::span<std::int8_t> cells) noexcept {
  for (int j = 0; j < map.cells_y; ++j) {
    for (int i = 0; i < map.cells_x; ++i) {
      std::int8_t cost = kCostUnknown;
      switch (map.kindAt(i, j)) {
        case CellKind::kUnknown:
          cost = kCostUnknown;
          break;
        case CellKind::kVacant:
          cost = kCostLethal;  // observed free down to the floor limit: no ground
          break;
        case CellKind::kVirtualSurface:
          cost = params.virtual_lethal ? kCostLethal : kCostUnknown;
          break;
        case CellKind::kSurface:
          cost = surfaceCost(map, params, i, j);
          break;
      }
      // OccupancyGrid: column along +x from the -x edge, row along +y from the -y edge.
      const int column = map.cells_x - 1 - i;
      const int row = map.cells_y - 1 - j;
      cells[static_cast<std::size_t>(row) * static_cast<std::size_t>(map.cells_x) +
            static_cast<std::size_t>(column)] = cost;
    }
  }
}

Vec3d costmapOrigin(const HeightMap& map) noexcept {
  return {map.centre_x - 0.5 * map.cells_x * map.resolution,
          map.centre_y - 0.5 * map.cells_y * map.resolution, 0.0};
}

}  // namespace raymap::heightmap
