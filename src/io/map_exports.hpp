// SPDX-License-Identifier: BSD-3-Clause
// Every export of a map (include/raymap/export.hpp) behind one call: `raymap export` and
// raymap::Mapper::exportPly both write through it.
#pragma once

#include <string>

#include "raymap/error.hpp"
#include "raymap/export.hpp"

#include "src/map/voxel_map.hpp"

namespace raymap::io {

/// @brief Checks a request alone: options of another kind are refused naming their key
/// (export.threshold, export.sigmas, export.min_axis, export.colour, export.min_weight), and values
/// out of range naming the key and the range.
Expected<void, Error> validateExportRequest(const ExportRequest& request);

/// @brief Writes `map` to `path` as the request asks (map_export.hpp, ndt_export.hpp,
/// tsdf_export.hpp: binary little-endian PLY via a temporary file and rename, so a failure leaves
/// any existing file as it was). Fails naming the key for a bad request, and saying what is
/// missing for a map without the layer the kind needs. Thread-safety: reads the map; nothing may
/// write it meanwhile.
Result<ExportCounts> exportMap(const VoxelMap& map, const ExportRequest& request,
                               const std::string& path);

}  // namespace raymap::io
