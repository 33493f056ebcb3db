// SPDX-License-Identifier: BSD-3-Clause
// Simulated scans of simple shapes with an exact signed distance (plane, sphere, box), for the
// TSDF tests: the rays and the truth they are checked against.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "src/map/ray.hpp"

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
