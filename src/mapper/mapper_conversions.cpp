// SPDX-License-Identifier: BSD-3-Clause
// Conversions between the public API's types and the library's (see the header).
#include "src/mapper/mapper_conversions.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "kernels/common/heightmap.h"
#include "src/core/eigen_conversions.hpp"

namespace raymap::mapper {

// The public defaults are the library's: one set of numbers, checked by the unit test
// MapperDefaults.AreTheLibrarys (MapOptions holds a std::string, which Clang with libstdc++ 12
// does not construct in a constant expression).
static_assert(static_cast<int>(HeightCell::kUnknown) == RM_HM_UNKNOWN);
static_assert(static_cast<int>(HeightCell::kSurface) == RM_HM_SURFACE);
static_assert(static_cast<int>(HeightCell::kVirtualSurface) == RM_HM_VIRTUAL);
static_assert(static_cast<int>(HeightCell::kVacant) == RM_HM_VACANT);

namespace {

Result<MapConfig> fail(const std::string& message) {
  return raymap::fail(ErrorCode::kInvalidArgument, message);
}

/// NdtParams and TsdfParams name a parameter as "ndt sensor-noise ..." / "tsdf max-weight ...":
/// the same error naming its key, "map.ndt.sensor_noise ...".
Error withKey(Error error) {
  std::string& m = error.message;
  const std::size_t space = m.find(' ');
  const std::size_t end = m.find(' ', space + 1);
  if (space == std::string::npos || end == std::string::npos) {
    return error;
  }
  std::string name = m.substr(space + 1, end - space - 1);
  for (char& c : name) {
    c = c == '-' ? '_' : c;
  }
  m = "map." + m.substr(0, space) + "." + name + m.substr(end);
  return error;
}

/// The first NDT or TSDF option set (as its key), or nullptr when none is.
const char* firstNdtOption(const NdtOptions& n) {
  const std::pair<bool, const char*> given[] = {
      {n.sensor_noise.has_value(), "map.ndt.sensor_noise"},
      {n.regulariser.has_value(), "map.ndt.regulariser"},
      {n.sample_threshold.has_value(), "map.ndt.sample_threshold"},
      {n.reinit_probability.has_value(), "map.ndt.reinit_probability"},
      {n.reinit_count.has_value(), "map.ndt.reinit_count"},
      {n.adaptation_rate.has_value(), "map.ndt.adaptation_rate"},
      {n.initial_intensity_variance.has_value(), "map.ndt.initial_intensity_variance"}};
  for (const auto& [set, key] : given) {
    if (set) {
      return key;
    }
  }
  return nullptr;
}

const char* firstTsdfOption(const TsdfOptions& t) {
  if (t.truncation) {
    return "map.tsdf.truncation";
  }
  if (t.max_weight) {
    return "map.tsdf.max_weight";
  }
  return t.dropoff ? "map.tsdf.dropoff" : nullptr;
}

/// The name of the mode the options ask for, as `raymap info` and `--mode` spell it.
std::string modeName(const MapOptions& options) {
  if (!options.occupancy && options.mode != MapMode::kTsdf) {
    return "decay";
  }
  return toString(options.mode);
}

/// Refuses NDT or TSDF parameters for a map of another mode, naming the first one set.
Expected<void, Error> checkModeParameters(const MapOptions& options) {
  const char* ndt = firstNdtOption(options.ndt);
  if (ndt != nullptr && !isNdt(options.mode)) {
    return raymap::fail(ErrorCode::kInvalidArgument,
                        std::string(ndt) + " applies only to map.mode ndt-om or ndt-tm (it is " +
                            modeName(options) + ")");
  }
  const char* tsdf = firstTsdfOption(options.tsdf);
  if (tsdf != nullptr && options.mode != MapMode::kTsdf) {
    return raymap::fail(
        ErrorCode::kInvalidArgument,
        std::string(tsdf) + " applies only to map.mode tsdf (it is " + modeName(options) + ")");
  }
  return {};
}

/// The mode's layers and parameters (after the geometry, semantics and occupancy are set): the
/// combinations `raymap populate --mode` allows, named by the keys of raymapd's `map:` section.
Expected<void, Error> applyMode(const MapOptions& options, MapConfig& config) {
  const bool ndt = isNdt(options.mode);
  const bool tsdf = options.mode == MapMode::kTsdf;
  const bool decay_only = !options.occupancy && !tsdf;
  if (decay_only && (!options.decay_rate || options.mode != MapMode::kOccupancy)) {
    return raymap::fail(ErrorCode::kInvalidArgument,
                        "map.occupancy: false is a map of decay rates only: it needs "
                        "map.decay_rate: true and map.mode occupancy");
  }
  if (tsdf && options.decay_rate) {
    return raymap::fail(ErrorCode::kInvalidArgument,
                        "map.decay_rate does not combine with map.mode tsdf (a TSDF map has no "
                        "occupancy or voxel mean for the rate)");
  }
  if (options.decay_rate && !options.voxel_mean) {
    return raymap::fail(ErrorCode::kInvalidArgument,
                        "map.mode decay and map.decay_rate need the voxel mean (its sample count "
                        "over the metres of ray path is the rate): map.voxel_mean: true");
  }
  if ((ndt || tsdf || decay_only) && options.semantics != Semantics::kPerRay) {
    return raymap::fail(ErrorCode::kInvalidArgument,
                        "map.mode " + modeName(options) +
                            " needs map.semantics: ray (every ray's own update counts)");
  }
  if (auto ok = checkModeParameters(options); !ok) {
    return ok;
  }
  if (tsdf) {
    config = config.forTsdf();
    config.tsdf.truncation_m = options.tsdf.truncation;
    config.tsdf.max_weight = options.tsdf.max_weight.value_or(config.tsdf.max_weight);
    config.tsdf.dropoff_m = options.tsdf.dropoff;
    if (auto ok = config.tsdf.validate(config.geometry.resolution); !ok) {
      return Unexpected(withKey(ok.error()));
    }
    return {};
  }
  config.decay_rate = options.decay_rate;
  if (decay_only) {
    config = config.forDecay();
  }
  if (ndt) {
    const NdtOptions& n = options.ndt;
    NdtParams& p = config.ndt;
    p.sensor_noise = n.sensor_noise.value_or(p.sensor_noise);
    p.regulariser = n.regulariser.value_or(p.regulariser);
    p.sample_threshold = n.sample_threshold.value_or(p.sample_threshold);
    p.reinit_probability = n.reinit_probability.value_or(p.reinit_probability);
    p.reinit_count = n.reinit_count.value_or(p.reinit_count);
    p.adaptation_rate = n.adaptation_rate;
    p.initial_intensity_variance =
        n.initial_intensity_variance.value_or(p.initial_intensity_variance);
    if (auto ok = p.validate(); !ok) {
      return Unexpected(withKey(ok.error()));
    }
  }
  return {};
}

/// map.window: a rolling map whose pool is the window.
Expected<void, Error> applyWindow(const MapOptions& options, MapConfig& config) {
  if (!options.window) {
    return {};
  }
  const Eigen::Vector3i& w = *options.window;
  if (w.minCoeff() < 1 || w.maxCoeff() > 4096) {
    return fail(ErrorCode::kInvalidArgument,
                "map.window must be 1 to 4096 regions on each axis (x, y, z)");
  }
  if (options.tiers.enabled) {
    return fail(ErrorCode::kInvalidArgument,
                "map.window: a rolling window keeps its regions in its pool; it has no cold "
                "tiers (map.tiers.enabled must be false)");
  }
  config.policy = StorePolicy::kRolling;
  config.window_regions = Vec3i{w.x(), w.y(), w.z()};
  return {};
}

}  // namespace

Expected<void, Error> applyModeName(std::string_view name, MapOptions& map) {
  constexpr std::string_view kSuffix = "+decay";
  std::string_view mode = name;
  bool decay = false;
  if (mode.size() > kSuffix.size() && mode.ends_with(kSuffix)) {
    mode.remove_suffix(kSuffix.size());
    decay = true;
  }
  if (mode == "decay" && !decay) {
    map.mode = MapMode::kOccupancy;
    map.occupancy = false;
    map.decay_rate = true;
    return {};
  }
  const std::optional<MapMode> parsed = mapModeFromName(mode);
  if (!parsed || (decay && *parsed == MapMode::kTsdf)) {
    return fail(ErrorCode::kInvalidArgument,
                "map.mode: '" + std::string(name) +
                    "' is not a mode: occupancy, ndt-om, ndt-tm, decay, tsdf, occupancy+decay, "
                    "ndt-om+decay or ndt-tm+decay");
  }
  map.mode = *parsed;
  map.occupancy = true;
  map.decay_rate = map.decay_rate || decay;
  return {};
}

std::string modeName(const MapOptions& map) {
  if (map.mode == MapMode::kOccupancy && !map.occupancy && map.decay_rate) {
    return "decay";
  }
  return std::string(toString(map.mode)) + (map.decay_rate ? "+decay" : "");
}

Result<MapConfig> toMapConfig(const MapOptions& options) {
  for (const auto& [name, p] :
       {std::pair{"map.hit_probability", options.hit_probability},
        std::pair{"map.miss_probability", options.miss_probability},
        std::pair{"map.occupied_threshold", options.occupied_threshold},
        std::pair{"map.clamp_min_probability", options.clamp_min_probability},
        std::pair{"map.clamp_max_probability", options.clamp_max_probability}}) {
    if (!(p > 0.0 && p < 1.0)) {
      char got[32];
      std::snprintf(got, sizeof(got), "%g", p);
      return fail(std::string(name) + " must be a probability between 0 and 1 (exclusive), got " +
                  got);
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
  config.occupancy.clamp_min = logOdds(options.clamp_min_probability);
  config.occupancy.clamp_max = logOdds(options.clamp_max_probability);
  config.occupancy.threshold = logOdds(options.occupied_threshold);
  config.memory_budget_bytes = options.max_memory_bytes;
  config.policy = StorePolicy::kGlobal;
  config.tiers.enabled = options.tiers.enabled;
  config.tiers.compressed_bytes = options.tiers.compressed_memory_bytes;
  config.tiers.spill_dir = options.tiers.spill_dir;
  if (auto ok = applyWindow(options, config); !ok) {
    return Unexpected(ok.error());
  }
  if (auto ok = applyMode(options, config); !ok) {
    return Unexpected(Error{ok.error().code, "map options: " + ok.error().message});
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
  options.clamp_min_probability = probability(config.occupancy.clamp_min);
  options.clamp_max_probability = probability(config.occupancy.clamp_max);
  options.occupied_threshold = probability(config.occupancy.threshold);
  options.max_memory_bytes = config.memory_budget_bytes;
  if (config.policy == StorePolicy::kRolling) {
    const Vec3i& w = config.window_regions;
    options.window = Eigen::Vector3i(w.x, w.y, w.z);
  }
  options.decay_rate = config.decay_rate;
  options.occupancy = config.occupancy_layer;
  if (isNdt(config.mode)) {
    options.ndt.sensor_noise = config.ndt.sensor_noise;
    options.ndt.regulariser = config.ndt.regulariser;
    options.ndt.sample_threshold = config.ndt.sample_threshold;
    options.ndt.reinit_probability = config.ndt.reinit_probability;
    options.ndt.reinit_count = config.ndt.reinit_count;
    options.ndt.adaptation_rate = config.ndt.adaptation_rate;
    options.ndt.initial_intensity_variance = config.ndt.initial_intensity_variance;
  }
  if (config.mode == MapMode::kTsdf) {
    options.tsdf.truncation = config.tsdf.truncation_m;
    options.tsdf.max_weight = config.tsdf.max_weight;
    options.tsdf.dropoff = config.tsdf.dropoff_m;
  }
  options.tiers.enabled = config.tiers.enabled;
  options.tiers.compressed_memory_bytes = config.tiers.compressed_bytes;
  options.tiers.spill_dir = config.tiers.spill_dir;
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
  choice.gpu_cache_bytes = options.gpu_cache_bytes;
  choice.gpu_cache_regions = options.gpu_cache_regions;
  choice.gpu_memory = options.gpu_memory;
  choice.opencl_span_work = options.opencl_span_work;
  if (options.batch_rays != 0) {
    choice.gpu_batch_rays = options.batch_rays;  // as `raymap populate --batch-rays`
  }
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

Result<heightmap::CostmapParams> toCostmapParams(const CostmapOptions& o) {
  const auto bad = [](const char* key, const char* why) {
    return fail(ErrorCode::kInvalidArgument, std::string("costmap.") + key + " " + why);
  };
  if (!(std::isfinite(o.max_step) && o.max_step > 0.0)) {
    return bad("max_step", "must be a positive height in metres");
  }
  if (!(std::isfinite(o.max_slope_deg) && o.max_slope_deg > 0.0 && o.max_slope_deg < 90.0)) {
    return bad("max_slope", "must be above 0 and below 90 degrees");
  }
  if (!(std::isfinite(o.min_clearance) && o.min_clearance >= 0.0)) {
    return bad("min_clearance", "must be a height >= 0 in metres");
  }
  if (o.max_free_cost < 0 || o.max_free_cost > 99) {
    return bad("max_free_cost", "must be 0 to 99");
  }
  heightmap::CostmapParams params;
  params.max_step_m = o.max_step;
  params.max_slope_deg = o.max_slope_deg;
  params.min_clearance_m = o.min_clearance;
  params.virtual_lethal = o.virtual_lethal;
  params.max_free_cost = o.max_free_cost;
  return params;
}

Result<msgs::DepthDecodeOptions> toDepthDecodeOptions(const DepthOptions& o) {
  const auto bad = [](const char* key, const char* why) {
    return fail(ErrorCode::kInvalidArgument, std::string("depth.") + key + " " + why);
  };
  if (o.downsample < 1 || o.downsample > 64) {
    return bad("downsample", "must be 1 to 64 (pixels per block side)");
  }
  if (!(std::isfinite(o.min_range) && o.min_range >= 0.0)) {
    return bad("min_range", "must be a distance >= 0 in metres");
  }
  if (!(std::isfinite(o.max_range) && o.max_range >= 0.0)) {
    return bad("max_range", "must be a distance >= 0 in metres (0: none)");
  }
  if (o.invalid_as_free && o.max_range <= 0.0) {
    return bad("invalid_as_free", "needs depth.max_range (the length of the free rays)");
  }
  msgs::DepthDecodeOptions options;
  options.downsample = o.downsample;
  options.min_range_m = static_cast<float>(o.min_range);
  options.max_range_m = static_cast<float>(o.max_range);
  options.invalid_as_free = o.invalid_as_free;
  return options;
}

Result<msgs::DepthPixels> toDepthPixels(const DepthImageView& image,
                                        const CameraIntrinsics& camera) {
  const auto bad = [](const std::string& why) {
    return fail(ErrorCode::kInvalidArgument, "image." + why);
  };
  if (image.width != camera.width || image.height != camera.height) {
    return bad("width, image.height: " + std::to_string(image.width) + " x " +
               std::to_string(image.height) + " pixels, but the camera's are " +
               std::to_string(camera.width) + " x " + std::to_string(camera.height));
  }
  const bool millimetres = image.encoding == DepthEncoding::k16UC1;
  const std::size_t pixel_bytes = millimetres ? 2 : 4;
  if (image.step < std::size_t{image.width} * pixel_bytes) {
    return bad("step: " + std::to_string(image.step) + " bytes per row is less than " +
               std::to_string(image.width) + " pixels of " + std::to_string(pixel_bytes) +
               " bytes");
  }
  if (image.data == nullptr) {
    return bad("data: no pixels (nullptr)");
  }
  return msgs::DepthPixels{static_cast<const std::byte*>(image.data),
                           image.step,
                           image.width,
                           image.height,
                           millimetres,
                           image.big_endian};
}

}  // namespace raymap::mapper
