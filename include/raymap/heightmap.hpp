// SPDX-License-Identifier: BSD-3-Clause
// Robot-centric 2.5D height maps from a raymap::Mapper (the layers raymapd publishes as a
// grid_map_msgs/GridMap).
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include <Eigen/Core>

namespace raymap {

/// @brief What a height-map cell holds (the `kind` layer).
enum class HeightCell : std::uint8_t {
  kUnknown = 0,         ///< nothing observed in the searched range: elevation NaN
  kSurface = 1,         ///< an occupied voxel with enough free space above it
  kVirtualSurface = 2,  ///< free space seen over unseen space: the ground is at or below it
  kVacant = 3,          ///< observed free down to the floor limit: elevation NaN
};

/// @brief A height-map request. World frame, metres.
struct HeightmapRequest {
  /// x, y: the column the map is centred on (the robot); z: the height the surface is searched
  /// around (usually the robot's ground height).
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  double size = 20.0;  ///< side of the square map (and of the searched cube), metres
  /// false: one reference height (centre.z) for every column; true: follow the terrain outward
  /// from the centre (stairs, ramps).
  bool follow_terrain = false;
  double min_clearance = 0.5;         ///< free height a surface needs above it to count as ground
  std::optional<double> floor_depth;  ///< searched below the reference; nullopt: size / 2
  std::optional<double> ceiling_height;  ///< searched above the reference; nullopt: size / 2
  bool virtual_surfaces = false;         ///< report virtual surfaces (negative obstacles)
};

/// @brief A height map: cells_x × cells_y cells of `resolution` metres, column-major (grid_map's
/// and Eigen's default): cell (i, j) is at index i + j * cells_x, i counts cells along -x and j
/// along -y from the +x/+y corner. World frame, metres. Plain value type.
struct HeightMap {
  double resolution = 0.1;  ///< cell edge, metres (the map's voxel size)
  int cells_x = 0;
  int cells_y = 0;
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();  ///< world x, y of the grid's centre
  std::vector<float> elevation;  ///< world z of the supporting surface; NaN where none
  /// Free height above the surface up to the next occupied voxel; +inf when open to the top of
  /// the searched box; NaN where no surface.
  std::vector<float> clearance;
  std::vector<HeightCell> kind;
  std::vector<std::uint32_t> observed_count;  ///< samples in the surface voxel

  std::size_t index(int i, int j) const noexcept {
    return static_cast<std::size_t>(i) +
           static_cast<std::size_t>(j) * static_cast<std::size_t>(cells_x);
  }
  /// @brief World x, y of the centre of cell (i, j), metres.
  Eigen::Vector2d cellCentre(int i, int j) const noexcept {
    return {centre.x() + (0.5 * cells_x - i - 0.5) * resolution,
            centre.y() + (0.5 * cells_y - j - 0.5) * resolution};
  }
};

/// @brief What makes a costmap cell lethal, and how free cells are scaled (the `costmap:`
/// section of raymapd, docs/configuration.md). Metres and degrees.
struct CostmapOptions {
  double max_step = 0.15;       ///< a step to a 4-neighbour's elevation above this is lethal
  double max_slope_deg = 30.0;  ///< a slope above this is lethal
  double min_clearance = 0.5;   ///< free height above the surface below this is lethal
  bool virtual_lethal = true;   ///< virtual surfaces (a drop-off's edge) lethal, else unknown
  int max_free_cost = 50;       ///< free cells cost slope / max_slope × this, 0..99
};

/// @brief A Nav2 costmap in nav_msgs/OccupancyGrid's layout: row-major, cell (x, y) at index
/// x + y * width, row 0 along the grid's -y edge, column 0 along its -x edge. Costs -1 (unknown),
/// 0..99 (free, by slope) and 100 (lethal). World frame, metres. Plain value type.
struct Costmap {
  double resolution = 0.1;                           ///< cell edge, metres
  int width = 0;                                     ///< cells along x
  int height = 0;                                    ///< cells along y
  Eigen::Vector2d origin = Eigen::Vector2d::Zero();  ///< world x, y of cell (0, 0)'s -x/-y corner
  std::vector<std::int8_t> cells;
};

}  // namespace raymap
