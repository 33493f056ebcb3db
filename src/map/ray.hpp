// SPDX-License-Identifier: BSD-3-Clause
// Rays as they come from sensors and files, and the prepared form every backend consumes.
#pragma once

#include <cstdint>
#include <type_traits>

#include "kernels/common/ray.h"
#include "src/core/vec3.hpp"

namespace raymap {

/// Ray flag: the sensor got no return along this ray (REP-117 "no return"); the ray clears free
/// space up to its end point (or max range) and never marks a hit.
inline constexpr std::uint32_t kRayNoReturn = 1u;

/// @brief One measurement: the sensor origin and the sample (return) point, world frame, metres.
/// Plain value type as readers produce it.
struct Ray {
  Vec3d origin;         ///< sensor position, world frame, metres
  Vec3d sample;         ///< return (or no-return end point), world frame, metres
  double time_s = 0.0;  ///< time of the sample, seconds (time base of the source)
  float intensity = 0.0f;
  std::uint32_t flags = 0;  ///< kRay* flags
  std::uint64_t scan = 0;   ///< index of the scan (sensor sweep) the ray belongs to
};

/// @brief A ray ready for integration (see kernels/common/ray.h). Crosses to devices as is.
using PreparedRay = rm_prepared_ray;

static_assert(std::is_trivially_copyable_v<PreparedRay>);
static_assert(sizeof(PreparedRay) == 60, "PreparedRay is part of the device ABI");

}  // namespace raymap
