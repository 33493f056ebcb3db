// SPDX-License-Identifier: BSD-3-Clause
// A Nav2 costmap from a height map: the cells of a nav_msgs/OccupancyGrid, in its layout.
#pragma once

#include <cstdint>
#include <span>

#include "src/heightmap/height_map.hpp"

namespace raymap::heightmap {

/// Costs as nav_msgs/OccupancyGrid and Nav2's StaticLayer read them (trinary off).
inline constexpr std::int8_t kCostUnknown = -1;
inline constexpr std::int8_t kCostLethal = 100;

/// @brief What makes a cell lethal, and how free cells are scaled.
struct CostmapParams {
  /// A step to a 4-neighbour's elevation above this is lethal (a curb, a stair the robot cannot
  /// climb), metres.
  double max_step_m = 0.15;
  /// A slope above this is lethal, degrees (from the elevation gradient over the neighbours).
  double max_slope_deg = 30.0;
  /// Free height above the surface below this is lethal (the robot does not fit), metres.
  double min_clearance_m = 0.5;
  /// Virtual surfaces (free space seen over unseen space: a drop-off's edge) lethal, or unknown.
  bool virtual_lethal = true;
  /// Free cells cost slope / max_slope × this (0 on the flat; below lethal), 0..99.
  int max_free_cost = 50;
};

/// @brief Writes the costmap of `map` into `cells` (map.cellCount() values) in OccupancyGrid's
/// layout: row-major, row 0 along the grid's -y edge and column 0 along its -x edge (the origin
/// at the (-x, -y) corner, see costmapOrigin()), x to the right.
///
/// Per cell: unknown cells are kCostUnknown; vacant cells (observed free down to the floor
/// limit, no ground: a hole) are lethal; virtual surfaces are lethal or unknown
/// (CostmapParams::virtual_lethal); a surface is lethal when its clearance is below
/// min_clearance_m, when the step to any 4-neighbour with an elevation exceeds max_step_m, or
/// when its slope exceeds max_slope_deg; otherwise it costs round(max_free_cost × slope /
/// max_slope). The slope is the elevation gradient from central differences where both
/// neighbours along an axis have an elevation, else one-sided, else 0 on that axis.
/// @pre cells.size() == map.cellCount() and the map's layers are sized.
/// @rt allocates: no; O(cells).
void computeCostmap(const HeightMap& map, const CostmapParams& params,
                    std::span<std::int8_t> cells) noexcept;

/// @brief World x, y of the costmap's origin (the (-x, -y) corner of cell (0, 0)), metres.
Vec3d costmapOrigin(const HeightMap& map) noexcept;

}  // namespace raymap::heightmap
