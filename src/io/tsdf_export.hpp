// SPDX-License-Identifier: BSD-3-Clause
// Exporting the surface of a TSDF map (its zero crossings) as a PLY point cloud.
#pragma once

#include <cstdint>
#include <string>

#include "src/core/error.hpp"
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

}  // namespace raymap::io
