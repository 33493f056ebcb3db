// SPDX-License-Identifier: BSD-3-Clause
// The 2.5D height map: what a planner consumes, in grid_map's conventions.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string_view>
#include <vector>

#include "kernels/common/heightmap.h"
#include "src/core/vec3.hpp"

namespace raymap::heightmap {

/// What a cell holds (the `kind` layer; values are stable, see kernels/common/heightmap.h).
enum class CellKind : std::uint8_t {
  kUnknown = RM_HM_UNKNOWN,         ///< nothing observed in the search range: elevation NaN
  kSurface = RM_HM_SURFACE,         ///< an occupied voxel with enough clearance above it
  kVirtualSurface = RM_HM_VIRTUAL,  ///< free space seen over unseen space: the ground is at or
                                    ///< below the elevation (ditch, drop-off, stair edge)
  kVacant = RM_HM_VACANT,           ///< observed free down to the floor limit: elevation NaN
};
/// @brief "unknown", "surface", "virtual", "vacant".
std::string_view toString(CellKind kind) noexcept;

/// How the reference height of each column is chosen.
enum class HeightmapMode : std::uint8_t {
  kPlanar = 0,  ///< one fixed reference height for every column
  kFill = 1,    ///< flood fill outward from the centre: each column searches around its
                ///< neighbour's height, so stairs and ramps are followed
};
std::string_view toString(HeightmapMode mode) noexcept;

/// @brief A robot-centric height map. Value type; layers are column-major (grid_map / Eigen
/// default): cell (i, j) is at index i + j * cells_x, i counts cells along -x and j along -y, so
/// (0, 0) is the +x/+y corner. World frame, metres.
///
/// Layers (names as published): `elevation` (world z of the supporting surface, NaN when none),
/// `clearance` (free height above it up to the next occupied voxel, +inf when open up to the top
/// of the searched box, NaN when no surface), `kind` (CellKind), `observed_count` (samples in the
/// surface voxel), and on maps with an NDT layer `normal_x`, `normal_y`, `normal_z` (the unit
/// normal of the surface voxel's Gaussian, world frame, pointing up: z >= 0; NaN where the cell is
/// no surface or the Gaussian gives no valid normal, see kernels/common/ndt_normal.h). Without an
/// NDT layer the normal vectors are empty. `reference` is the height each column was searched
/// around (diagnostics; in planar mode the request's reference everywhere).
///
/// Thread-safety: a plain value; no internal synchronisation.
struct HeightMap {
  double resolution = 0.1;   ///< cell edge, metres (the map's voxel size)
  int cells_x = 0;           ///< cells along x
  int cells_y = 0;           ///< cells along y
  double centre_x = 0.0;     ///< world x of the grid's geometric centre, metres
  double centre_y = 0.0;     ///< world y of the grid's geometric centre, metres
  double reference_z = 0.0;  ///< the requested reference height, metres
  HeightmapMode mode = HeightmapMode::kPlanar;
  bool has_normals = false;  ///< the normal layers are present (the map has an NDT layer)
  std::vector<float> elevation;
  std::vector<float> clearance;
  std::vector<std::uint32_t> kind;
  std::vector<std::uint32_t> observed_count;
  std::vector<float> reference;
  std::vector<float> normal_x;  ///< empty unless has_normals
  std::vector<float> normal_y;
  std::vector<float> normal_z;

  std::size_t cellCount() const noexcept {
    return static_cast<std::size_t>(cells_x) * static_cast<std::size_t>(cells_y);
  }
  std::size_t index(int i, int j) const noexcept {
    return static_cast<std::size_t>(i) +
           static_cast<std::size_t>(j) * static_cast<std::size_t>(cells_x);
  }
  /// @brief World x, y of the centre of cell (i, j), metres (z = 0).
  Vec3d cellCentre(int i, int j) const noexcept {
    return {centre_x + (0.5 * cells_x - i - 0.5) * resolution,
            centre_y + (0.5 * cells_y - j - 0.5) * resolution, 0.0};
  }
  /// @brief The cell holding world point (x, y), metres; false when outside the grid.
  bool cellOf(double x, double y, int* i, int* j) const noexcept;
  CellKind kindAt(int i, int j) const noexcept { return static_cast<CellKind>(kind[index(i, j)]); }
  /// @brief Sizes every layer for cells_x * cells_y cells, the normal layers to 0 cells unless
  /// has_normals (keeps capacity: no allocation when the size does not grow).
  void resizeLayers();
};

}  // namespace raymap::heightmap
