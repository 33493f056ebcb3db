// SPDX-License-Identifier: BSD-3-Clause
// Validation of map parameters.
#include "src/map/map_params.hpp"

#include <algorithm>
#include <cstdio>
#include <string>

namespace raymap {
namespace {

std::string number(double v) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%g", v);
  return buffer;
}

}  // namespace

Expected<void, Error> OccupancyParams::validate() const {
  if (!std::isfinite(hit) || !std::isfinite(miss) || !std::isfinite(clamp_min) ||
      !std::isfinite(clamp_max) || !std::isfinite(threshold)) {
    return fail(ErrorCode::kInvalidArgument, "occupancy parameters must be finite probabilities");
  }
  if (!(hit > 0.0f)) {
    return fail(ErrorCode::kInvalidArgument,
                "map.hit_probability must be above 0.5 (a hit raises occupancy; got " +
                    number(probability(hit)) + ")");
  }
  if (!(miss < 0.0f)) {
    return fail(ErrorCode::kInvalidArgument,
                "map.miss_probability must be below 0.5 (a miss lowers occupancy; got " +
                    number(probability(miss)) + ")");
  }
  if (!(clamp_min < threshold) || !(threshold <= clamp_max)) {
    return fail(ErrorCode::kInvalidArgument,
                "occupancy probabilities must satisfy map.clamp_min_probability < "
                "map.occupied_threshold <= map.clamp_max_probability (got " +
                    number(probability(clamp_min)) + " / " + number(probability(threshold)) +
                    " / " + number(probability(clamp_max)) + ")");
  }
  return {};
}

const char* toString(MapMode mode) noexcept {
  switch (mode) {
    case MapMode::kOccupancy:
      return "occupancy";
    case MapMode::kNdtOm:
      return "ndt-om";
    case MapMode::kNdtTm:
      return "ndt-tm";
    case MapMode::kTsdf:
      return "tsdf";
  }
  return "?";
}

std::optional<MapMode> mapModeFromName(std::string_view name) noexcept {
  for (MapMode mode : {MapMode::kOccupancy, MapMode::kNdtOm, MapMode::kNdtTm, MapMode::kTsdf}) {
    if (name == toString(mode)) {
      return mode;
    }
  }
  return std::nullopt;
}

double NdtParams::adaptationRate(const OccupancyParams& occupancy) const noexcept {
  if (adaptation_rate) {
    return *adaptation_rate;
  }
  const double p_miss = probability(occupancy.miss);
  return std::clamp(kAdaptationScale * (1.0 - 2.0 * p_miss), 0.0, 1.0);
}

Expected<void, Error> NdtParams::validate() const {
  if (!std::isfinite(sensor_noise) || !(sensor_noise > 0.0)) {
    return fail(ErrorCode::kInvalidArgument,
                "ndt sensor-noise must be a positive distance in metres (got " +
                    number(sensor_noise) + ")");
  }
  if (!std::isfinite(regulariser) || !(regulariser > 0.0) || regulariser > 1.0) {
    return fail(ErrorCode::kInvalidArgument,
                "ndt regulariser must be in (0, 1] voxel edges (got " + number(regulariser) + ")");
  }
  if (sample_threshold < 1) {
    return fail(ErrorCode::kInvalidArgument, "ndt sample-threshold must be at least 1");
  }
  if (!(reinit_probability > 0.0) || !(reinit_probability < 0.5)) {
    return fail(ErrorCode::kInvalidArgument, "ndt reinit-probability must be in (0, 0.5) (got " +
                                                 number(reinit_probability) + ")");
  }
  if (adaptation_rate &&
      (!std::isfinite(*adaptation_rate) || *adaptation_rate < 0.0 || *adaptation_rate > 1.0)) {
    return fail(ErrorCode::kInvalidArgument,
                "ndt adaptation-rate must be in [0, 1] (got " + number(*adaptation_rate) + ")");
  }
  if (!std::isfinite(initial_intensity_variance) || !(initial_intensity_variance >= 0.0)) {
    return fail(ErrorCode::kInvalidArgument,
                "ndt initial-intensity-variance must be non-negative (got " +
                    number(initial_intensity_variance) + ")");
  }
  return {};
}

rm_ndt_params NdtParams::toKernel(double resolution, const OccupancyParams& occupancy,
                                  MapMode mode) const noexcept {
  rm_ndt_params p{};
  p.sensor_noise = static_cast<float>(sensor_noise / resolution);
  p.regulariser = static_cast<float>(regulariser);
  p.adaptation_rate = static_cast<float>(adaptationRate(occupancy));
  p.reinit_threshold = logOdds(reinit_probability);
  p.reinit_count = reinit_count;
  p.sample_threshold = sample_threshold;
  p.initial_intensity_variance = static_cast<float>(initial_intensity_variance);
  p.traversability = mode == MapMode::kNdtTm ? 1u : 0u;
  return p;
}

Expected<void, Error> TsdfParams::validate(double resolution) const {
  const double tau = truncationMetres(resolution);
  const double eps = dropoffMetres(resolution);
  if (!std::isfinite(tau) || !(tau > 0.0)) {
    return fail(ErrorCode::kInvalidArgument,
                "tsdf truncation must be a positive distance in metres (got " + number(tau) + ")");
  }
  if (!std::isfinite(eps) || eps < 0.0 || !(eps < tau)) {
    return fail(ErrorCode::kInvalidArgument,
                "tsdf dropoff must be a distance in metres from 0 to below the truncation " +
                    number(tau) + " (got " + number(eps) + ")");
  }
  if (!std::isfinite(max_weight) || !(max_weight > 0.0)) {
    return fail(ErrorCode::kInvalidArgument,
                "tsdf max-weight must be positive (got " + number(max_weight) + ")");
  }
  return {};
}

rm_tsdf_params TsdfParams::toKernel(double resolution) const noexcept {
  rm_tsdf_params p{};
  p.truncation = static_cast<float>(truncationMetres(resolution));
  p.max_weight = static_cast<float>(max_weight);
  p.dropoff = static_cast<float>(dropoffMetres(resolution));
  p.resolution = static_cast<float>(resolution);
  return p;
}

const char* toString(Semantics semantics) noexcept {
  return semantics == Semantics::kPerScan ? "scan" : "ray";
}

Expected<void, Error> MapGeometry::validate() const {
  if (!std::isfinite(resolution) || resolution < 0.001 || resolution > 100.0) {
    return fail(ErrorCode::kInvalidArgument,
                "resolution must be between 0.001 and 100 metres (got " + number(resolution) + ")");
  }
  if (region_voxels < kMinRegionVoxels || region_voxels > kMaxRegionVoxels) {
    return fail(ErrorCode::kInvalidArgument, "map.region_voxels must be between " +
                                                 std::to_string(kMinRegionVoxels) + " and " +
                                                 std::to_string(kMaxRegionVoxels) + " (got " +
                                                 std::to_string(region_voxels) + ")");
  }
  return {};
}

}  // namespace raymap
