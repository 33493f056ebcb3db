// SPDX-License-Identifier: BSD-3-Clause
// Simulated scans of simple shapes with an exact signed distance (plane, sphere, box), for the
// TSDF tests: the rays and the truth they are checked against.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "src/map/ray.hpp"
#include "src/map/voxel_map.hpp"

namespace raymap::test {

/// @brief A shape seen from a few sensor positions.
struct TsdfScene {
  std::string name;
  /// Exact Euclidean signed distance to the shape's surface, metres: positive outside (where the
  /// sensors are), negative inside.
  std::function<double(Vec3d)> truth;
  std::vector<Ray> rays;  ///< returns on the surface, world frame, metres
  /// Where the surface is checked: the box leaves out the band of truncation width along its
  /// edges, where rays that meet one face near an edge go on through the next one (projective
  /// distances round the edges off). Everywhere for the plane and the sphere.
  std::function<bool(Vec3d)> checked = [](Vec3d) { return true; };
};

/// @brief A TSDF-only map at 0.1 m (regions of 16^3 voxels, a 1 GiB pool) with the default
/// truncation (0.3 m) and drop-off (0.1 m) and the given maximum weight.
MapConfig tsdfConfig(double max_weight = TsdfParams::kDefaultMaxWeight);

/// @brief Two TSDF maps voxel by voxel over the union of their regions.
struct TsdfComparison {
  std::uint64_t updated = 0;             ///< voxels with weight in either map
  std::uint64_t within = 0;              ///< of those: distance and weight within the tolerances
  double max_distance_difference = 0.0;  ///< metres
  double max_weight_difference = 0.0;
};
/// Tolerances: |distance difference| <= distance_m, |weight difference| <= weight_relative of
/// the larger weight (plus 1e-6).
TsdfComparison compareTsdf(const VoxelMap& a, const VoxelMap& b, double distance_m,
                           double weight_relative);

/// @brief The plane z = 0.537 m seen from 4 sensors 1.5 m above it (rays_per_sensor each).
TsdfScene planeScene(int rays_per_sensor, std::uint64_t seed = 1);
/// @brief A sphere of radius 0.8 m centred off the voxel grid, seen from 8 sensors around it.
TsdfScene sphereScene(int rays_per_sensor, std::uint64_t seed = 2);
/// @brief A 2.0 x 1.6 x 1.2 m box off the voxel grid, seen from 8 sensors around and above it;
/// checked away from its edges by `edge_margin_m`.
TsdfScene boxScene(int rays_per_sensor, double edge_margin_m, std::uint64_t seed = 3);

/// @brief Shoots rays from `origin` at random points of the box [lo, hi] and keeps those that
/// meet the surface of `truth` (sphere tracing, exact for these shapes) at an incidence below
/// about 75 degrees, with their return on the surface.
void shootAt(const std::function<double(Vec3d)>& truth, Vec3d origin, Vec3d lo, Vec3d hi, int rays,
             std::uint64_t seed, std::vector<Ray>* out);

}  // namespace raymap::test
