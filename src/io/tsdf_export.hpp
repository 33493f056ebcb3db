// SPDX-License-Identifier: BSD-3-Clause
// Exporting the surface of a TSDF map as a PLY: its zero crossings as points, or a triangle mesh.
#pragma once

#include <cstdint>
#include <string>

#include "raymap/error.hpp"

#include "src/map/voxel_map.hpp"

namespace raymap::io {

/// @brief Writes a binary little-endian PLY of the map's zero crossings (tsdfZeroCrossings in
/// src/map/tsdf_surface.hpp): float x, y, z (world frame, metres), float nx, ny, nz (the axis
/// the crossing lies on, pointing out of the surface towards the sensor side) and float weight
/// (the smaller of the two voxels' weights), via a temporary file and rename. Crossings between
/// voxels lighter than `min_weight` are left out. Returns the points written. Fails (saying so)
/// for a map without a TSDF layer or a negative or non-finite min_weight.
Result<std::uint64_t> exportTsdfSurface(const VoxelMap& map, const std::string& path,
                                        double min_weight);

/// @brief How many of each a mesh export wrote.
struct TsdfMeshCounts {
  std::uint64_t vertices = 0;
  std::uint64_t triangles = 0;
};

/// @brief Writes a binary little-endian PLY triangle mesh of the map's surface (tsdfMesh in
/// src/map/tsdf_mesh.hpp, marching cubes over cubes whose eight voxels weigh >= min_weight):
/// vertices with float x, y, z (world frame, metres), float nx, ny, nz (unit normal out of the
/// surface, towards the sensor side) and float weight; faces as `list uchar int vertex_indices`,
/// counter-clockwise seen from outside. Via a temporary file and rename. Fails (saying so) for a
/// map without a TSDF layer, a negative or non-finite min_weight, or more vertices than a PLY
/// int index holds.
Result<TsdfMeshCounts> exportTsdfMesh(const VoxelMap& map, const std::string& path,
                                      double min_weight);

}  // namespace raymap::io
