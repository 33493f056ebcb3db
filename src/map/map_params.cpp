// SPDX-License-Identifier: BSD-3-Clause
// Validation of map parameters.
#include "src/map/map_params.hpp"

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
                "hit probability must be above 0.5 (got " + number(probability(hit)) + ")");
  }
  if (!(miss < 0.0f)) {
    return fail(ErrorCode::kInvalidArgument,
                "miss probability must be below 0.5 (got " + number(probability(miss)) + ")");
  }
  if (!(clamp_min < threshold) || !(threshold <= clamp_max)) {
    return fail(ErrorCode::kInvalidArgument,
                "occupancy probabilities must satisfy clamp-min < threshold <= clamp-max (got " +
                    number(probability(clamp_min)) + " / " + number(probability(threshold)) +
                    " / " + number(probability(clamp_max)) + ")");
  }
  return {};
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
    return fail(ErrorCode::kInvalidArgument, "region-voxels must be between " +
                                                 std::to_string(kMinRegionVoxels) + " and " +
                                                 std::to_string(kMaxRegionVoxels) + " (got " +
                                                 std::to_string(region_voxels) + ")");
  }
  return {};
}

}  // namespace raymap
