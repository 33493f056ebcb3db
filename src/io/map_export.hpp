// SPDX-License-Identifier: BSD-3-Clause
// Exporting a map as a point-cloud PLY that any viewer opens.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "raymap/error.hpp"

#include "src/map/voxel_map.hpp"

namespace raymap::io {

/// Which voxels become points.
enum class ExportMode : std::uint8_t {
  kOccupied,  ///< occupied voxels, at their voxel mean (centre when they have no samples)
  kFree,      ///< free voxels, at their centres
  kMean,      ///< every voxel with samples, at its mean, whatever its state
  /// Decay-rate maps: every voxel whose rate (samples per metre of ray path, kernels/common/
  /// decay.h) is known and at least ExportOptions::decay_threshold, at its mean (centre without
  /// samples)
  kDecay,
};

/// What the modes need beyond the map.
struct ExportOptions {
  /// kDecay: the lowest rate exported, reflections per metre (0: every voxel a ray entered).
  double decay_threshold = 0.0;
};

/// @brief Parses "occupied", "free", "mean" or "decay".
Result<ExportMode> exportModeFromString(const std::string& text);
const char* toString(ExportMode mode) noexcept;

/// @brief The key of every voxel `mode` selects (kOccupied, kFree or kMean), in the export's
/// deterministic order (regions z, y, x; voxels by index). A tiered map's regions stream
/// through its pool. @return kInvalidArgument for kDecay, kUnsupported for a map without the
/// layer the mode reads (as exportPly); a cold region that cannot be read back fails it.
Result<std::vector<Vec3i>> selectedVoxels(const VoxelMap& map, ExportMode mode);

/// @brief Writes a binary little-endian PLY with float x, y, z (world frame, metres), float
/// `probability` (occupancy probability of the voxel) and uint `count` (voxel-mean samples), and
/// for kDecay also float `decay_rate` (per metre; +inf written as the largest float) and float
/// `traversal` (metres), via a temporary file and rename. Returns the number of points written.
/// Fails (naming what is missing) for a map without an occupancy layer, or kDecay without a
/// traversal layer, or a negative or non-finite threshold.
Result<std::uint64_t> exportPly(const VoxelMap& map, ExportMode mode, const std::string& path,
                                const ExportOptions& options = {});

}  // namespace raymap::io
