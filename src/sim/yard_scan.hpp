// SPDX-License-Identifier: BSD-3-Clause
// A small built-in scene and lidar, so raymap can demonstrate and test itself without recorded
// data: a walled yard with boxes, a pillar and a table, scanned by a spinning multi-beam lidar
// driven along a straight path.
#pragma once

#include <cstdint>
#include <vector>

#include "src/core/vec3.hpp"
#include "src/map/ray.hpp"

namespace raymap::sim {

/// @brief Axis-aligned solid box, world frame, metres.
struct Box {
  Vec3d min;
  Vec3d max;
};

/// @brief Spinning lidar: `beams` rows evenly over [min, max] elevation, `columns` azimuth steps
/// per revolution, one revolution per scan.
struct LidarModel {
  int beams = 32;
  double elevation_min_deg = -25.0;
  double elevation_max_deg = 15.0;
  int columns = 512;
  double max_range_m = 40.0;    ///< beyond this the lidar reports no return
  double range_noise_m = 0.01;  ///< standard deviation of Gaussian range noise
  double scan_period_s = 0.1;   ///< time of one revolution
};

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

/// @brief Simulates the scans. Rays that hit nothing within max range are no-return rays
/// (kRayNoReturn) ending at max range. Deterministic for a given seed.
std::vector<Ray> simulateYardScans(const YardScanConfig& config);

}  // namespace raymap::sim
