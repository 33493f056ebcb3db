// SPDX-License-Identifier: BSD-3-Clause
// The raymap map file (.rmap): versioned, little-endian, per-region compressed blocks with CRC32s.
// The byte layout is documented in docs/map-format.md.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "raymap/error.hpp"

#include "src/map/voxel_map.hpp"

namespace raymap::io {

/// 1: occupancy maps. 2: adds the map mode and the NDT parameters (version-1 files still load, as
/// occupancy maps).
inline constexpr std::uint32_t kMapFormatVersion = 3;

/// @brief The header of a map file: everything except the voxels.
struct MapFileHeader {
  std::uint32_t format_version = kMapFormatVersion;
  /// Geometry, occupancy, semantics, voxel mean, mode and NDT parameters. Policy is always global;
  /// the memory budget holds exactly region_count regions (at least one).
  MapConfig config;
  std::vector<LayerKind> saved_layers;  ///< layers stored per region, in order
  std::uint64_t region_count = 0;
  std::vector<std::pair<std::string, std::string>> info;  ///< provenance
};

/// @brief Writes every region and parameter of `map` to `path` (temporary file + rename, so an
/// existing file is replaced only by a complete new one).
Expected<void, Error> saveMap(const VoxelMap& map, const std::string& path);

/// @brief Options for loading.
struct MapLoadOptions {
  /// Pool size of the loaded map in bytes; 0 = just enough for the file's regions.
  std::uint64_t memory_budget_bytes = 0;
  /// With tiers.enabled and a memory budget, the pool is the budget alone and a file with more
  /// regions streams through it into the cold tiers (docs/large-maps.md).
  RegionTierConfig tiers;
};

/// @brief Reads a map. A corrupt, truncated or foreign file fails with an error naming the file and
/// what is wrong (which region, which offset); it never crashes and never returns a partial map.
/// The map is global, with room for max(file's regions, options.memory_budget_bytes / bytes per
/// region) regions; a per-scan map gets a fresh (zeroed) scan-mark layer.
Result<VoxelMap> loadMap(const std::string& path, const MapLoadOptions& options = {});

/// @brief Reads and checks only the header (fast; for `raymap info` without counts).
Result<MapFileHeader> readMapHeader(const std::string& path);

}  // namespace raymap::io
