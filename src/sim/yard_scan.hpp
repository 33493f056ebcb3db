// SPDX-License-Identifier: BSD-3-Clause
// A small built-in scene and lidar, so raymap can demonstrate and test itself without recorded
// data: a walled yard with boxes, a pillar and a table, scanned by a spinning multi-beam lidar
// driven along a straight path.
#pragma once

#include <cstdint>
#include <vector>

#include "src/core/vec3.hpp"
#include "src/map/ray.hpp"
#include "src/sim/lidar.hpp"
#include "src/sim/scene.hpp"

namespace raymap::sim {

/// @brief The yard: ground at z = 0, walls, obstacles; the lidar moves from `start` to `end`
/// (world frame, metres) over `scans` scans.
struct YardScanConfig {
  LidarModel lidar;
  Vec3d start{-4.0, -1.0, 1.2};
  Vec3d end{4.0, 1.0, 1.2};
  int scans = 10;
  std::uint64_t seed = 1;
  std::vector<Box> solids;  ///< empty: the default yard (yardSolids())
};

/// @brief The default yard's walls and obstacles (ground excluded: it is the plane z = 0).
std::vector<Box> yardSolids();

/// @brief Distance from a point to the nearest surface of the scene (ground plane z = 0 and the
/// solids), metres; 0 inside a solid or below the ground.
double distanceToSurface(Vec3d p, const std::vector<Box>& solids);

/// @brief Simulates the scans with simulateScans(): the scene is the ground plane z = 0 and the
/// solids; the sensor rests at each scan's position (heading +x) for the whole revolution.
/// Rays that hit nothing within max range are no-return rays (kRayNoReturn) ending at max range.
/// Deterministic for a given seed.
std::vector<Ray> simulateYardScans(const YardScanConfig& config);

}  // namespace raymap::sim
