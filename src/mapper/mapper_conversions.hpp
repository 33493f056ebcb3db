// SPDX-License-Identifier: BSD-3-Clause
// Between the public API's types (include/raymap, Eigen) and the library's own: map and ray
// options, height-map requests and results.
#pragma once

#include <string>
#include <string_view>

#include "raymap/error.hpp"
#include "raymap/heightmap.hpp"
#include "raymap/mapper_config.hpp"

#include "src/device/backend_choice.hpp"
#include "src/heightmap/costmap.hpp"
#include "src/heightmap/height_map.hpp"
#include "src/heightmap/heightmap_plan.hpp"
#include "src/map/ray_preparer.hpp"
#include "src/map/voxel_map.hpp"
#include "src/msgs/depth_image.hpp"

namespace raymap::mapper {

/// @brief The map configuration MapOptions describe (global store). Errors name the option.
Result<MapConfig> toMapConfig(const MapOptions& options);
/// @brief Sets the mode, occupancy and decay_rate of `map` as a mode name says: "occupancy",
/// "ndt-om", "ndt-tm", "tsdf", "decay" (decay rates only, no occupancy), or "<mode>+decay" (that
/// mode with decay rates, as `raymap info` names such maps). The names of `raymap populate
/// --mode` and of the Python module. @return kInvalidArgument naming map.mode and the names.
Expected<void, Error> applyModeName(std::string_view name, MapOptions& map);
/// @brief The mode name of `map` (applyModeName's inverse).
std::string modeName(const MapOptions& map);
/// @brief The MapOptions that describe an existing map (e.g. one loaded from a file).
MapOptions toMapOptions(const MapConfig& config);
/// @brief The ray limits; `device` picks the walk direction RayOptions::Walk::kAuto means.
Result<RayFilter> toRayFilter(const RayOptions& options, bool device);
backends::BackendChoice toBackendChoice(const BackendOptions& options);
heightmap::HeightmapOptions toHeightmapOptions(const HeightmapRequest& request);
/// @brief Copies the layers the public HeightMap has (elevation, clearance, kind, counts).
void copyHeightMap(const heightmap::HeightMap& from, HeightMap& to);
/// @brief The depth decoder's options; errors name the key (depth.downsample …).
Result<msgs::DepthDecodeOptions> toDepthDecodeOptions(const DepthOptions& options);
/// @brief The decoder's view of a caller's image; errors name the field (image.width …) when it
/// does not fit `camera` or holds no pixels.
Result<msgs::DepthPixels> toDepthPixels(const DepthImageView& image,
                                        const CameraIntrinsics& camera);
/// @brief The costmap parameters of `options`; errors name the key (costmap.max_step …) as
/// raymapd's `costmap:` section does.
Result<heightmap::CostmapParams> toCostmapParams(const CostmapOptions& options);

}  // namespace raymap::mapper
