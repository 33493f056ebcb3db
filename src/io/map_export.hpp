// SPDX-License-Identifier: BSD-3-Clause
// Exporting a map as a point-cloud PLY that any viewer opens.
#pragma once

#include <cstdint>
#include <string>

#include "src/core/error.hpp"
#include "src/map/voxel_map.hpp"

namespace raymap::io {

/// Which voxels become points.
enum class ExportMode : std::uint8_t {
  kOccupied,  ///< occupied voxels, at their voxel mean (centre when they have no samples)
  kFree,      ///< free voxels, at their centres
  kMean,      ///< every voxel with samples, at its mean, whatever its state
};

/// @brief Parses "occupied", "free" or "mean".
Result<ExportMode> exportModeFromString(const std::string& text);
const char* toString(ExportMode mode) noexcept;

/// @brief Writes a binary little-endian PLY with float x, y, z (world frame, metres), float
/// `probability` (occupancy probability of the voxel) and uint `count` (voxel-mean samples), via a
/// temporary file and rename. Returns the number of points written.
Result<std::uint64_t> exportPly(const VoxelMap& map, ExportMode mode, const std::string& path);

}  // namespace raymap::io
