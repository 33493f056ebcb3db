// SPDX-License-Identifier: BSD-3-Clause
// Conversions between the public API's types and the library's (see the header).
#include "src/mapper/mapper_conversions.hpp"

#include <algorithm>

#include "kernels/common/heightmap.h"
#include "src/core/eigen_conversions.hpp"

namespace raymap::mapper {

// The public defaults are the library's: one set of numbers, checked here.
static_assert(MapOptions{}.resolution == MapGeometry::kDefaultResolution);
static_assert(MapOptions{}.region_voxels == MapGeometry::kDefaultRegionVoxels);
static_assert(MapOptions{}.hit_probability == OccupancyParams::kDefaultHitProbability);
static_assert(MapOptions{}.miss_probability == OccupancyParams::kDefaultMissProbability);
static_assert(MapOptions{}.clamp_min_log_odds == OccupancyParams::kDefaultClampMin);
static_assert(MapOptions{}.clamp_max_log_odds == OccupancyParams::kDefaultClampMax);
static_assert(MapOptions{}.occupied_threshold == OccupancyParams::kDefaultThresholdProbability);
static_assert(MapOptions{}.max_memory_bytes == MapConfig::kDefaultMemoryBudget);
static_assert(static_cast<int>(HeightCell::kUnknown) == RM_HM_UNKNOWN);
static_assert(static_cast<int>(HeightCell::kSurface) == RM_HM_SURFACE);
static_assert(static_cast<int>(HeightCell::kVirtualSurface) == RM_HM_VIRTUAL);
static_assert(static_cast<int>(HeightCell::kVacant) == RM_HM_VACANT);

Result<MapConfig> toMapConfig(const MapOptions& options) {
  for (const auto& [name, p] : {std::pair{"map.hit_probability", options.hit_probability},
                                std::pair{"map.miss_probability", options.miss_probability},
                                std::pair{"map.occupied_threshold", options.occupied_threshold}}) {
    if (!(p > 0.0 && p < 1.0)) {
      return fail(ErrorCode::kInvalidArgument,
                  std::string(name) + " must be a probability in (0, 1), got " + std::to_string(p));
    }
  }
  MapConfig config;
  config.geometry.resolution = options.resolution;
  config.geometry.region_voxels = options.region_voxels;
  config.semantics = options.semantics;
  config.mode = options.mode;
  config.voxel_mean = options.voxel_mean;
  config.occupancy.hit = logOdds(options.hit_probability);
  config.occupancy.miss = logOdds(options.miss_probability);
  config.occupancy.clamp_min = options.clamp_min_log_odds;
  config.occupancy.clamp_max = options.clamp_max_log_odds;
  config.occupancy.threshold = logOdds(options.occupied_threshold);
  config.memory_budget_bytes = options.max_memory_bytes;
  config.policy = StorePolicy::kGlobal;
  if (options.mode == MapMode::kTsdf) {
    config = config.forTsdf();
  }
  if (auto ok = config.validate(); !ok) {
    return Unexpected(Error{ok.error().code, "map options: " + ok.error().message});
  }
  return config;
}

MapOptions toMapOptions(const MapConfig& config) {
  MapOptions options;
  options.resolution = config.geometry.resolution;
  options.region_voxels = config.geometry.region_voxels;
  options.semantics = config.semantics;
  options.mode = config.mode;
  options.voxel_mean = config.voxel_mean;
  options.hit_probability = probability(config.occupancy.hit);
  options.miss_probability = probability(config.occupancy.miss);
  options.clamp_min_log_odds = config.occupancy.clamp_min;
  options.clamp_max_log_odds = config.occupancy.clamp_max;
  options.occupied_threshold = probability(config.occupancy.threshold);
  options.max_memory_bytes = config.memory_budget_bytes;
  return options;
}

Result<RayFilter> toRayFilter(const RayOptions& options, bool device) {
  RayFilter filter;
  filter.min_range_m = options.min_range;
  filter.max_range_m = options.max_range;
  filter.max_length_m = options.max_ray_length;
  filter.segment_length_m = options.segment_length;
  // Device backends walk from the sample back to the sensor unless told otherwise: rays of a scan
  // all start near the sensor, and forward walks make the device's threads collide there.
  filter.reverse = options.walk == RayOptions::Walk::kReverse ||
                   (options.walk == RayOptions::Walk::kAuto && device);
  if (auto ok = filter.validate(); !ok) {
    return Unexpected(ok.error());  // it names the field: "rays.min_range must be ..."
  }
  return filter;
}

backends::BackendChoice toBackendChoice(const BackendOptions& options) {
  backends::BackendChoice choice;
  choice.name = options.name;
  choice.threads = options.threads;
  choice.opencl_platform = options.opencl_platform;
  choice.opencl_device = options.opencl_device;
  choice.cuda_device = options.cuda_device;
  choice.fallback_cpu = options.fallback_cpu;
  choice.device_planning = options.device_planning;
  return choice;
}

heightmap::HeightmapOptions toHeightmapOptions(const HeightmapRequest& request) {
  heightmap::HeightmapOptions options;
  options.centre = toVec3(request.centre);
  options.size = request.size;
  options.mode =
      request.follow_terrain ? heightmap::HeightmapMode::kFill : heightmap::HeightmapMode::kPlanar;
  options.min_clearance = request.min_clearance;
  options.floor_depth = request.floor_depth;
  options.ceiling_height = request.ceiling_height;
  options.virtual_surfaces = request.virtual_surfaces;
  return options;
}

void copyHeightMap(const heightmap::HeightMap& from, HeightMap& to) {
  to.resolution = from.resolution;
  to.cells_x = from.cells_x;
  to.cells_y = from.cells_y;
  to.centre = Eigen::Vector2d(from.centre_x, from.centre_y);
  to.elevation = from.elevation;
  to.clearance = from.clearance;
  to.observed_count = from.observed_count;
  to.kind.resize(from.kind.size());
  std::transform(from.kind.begin(), from.kind.end(), to.kind.begin(),
                 [](std::uint32_t k) { return static_cast<HeightCell>(k); });
}

}  // namespace raymap::mapper
