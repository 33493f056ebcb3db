// SPDX-License-Identifier: BSD-3-Clause
// Analytic scenes made of simple solids (ground, boxes, ramps, poles, ditches): ray casting and the
// exact height field, the ground truth of every simulated recording.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "src/core/vec3.hpp"

namespace raymap::sim {

/// @brief Axis-aligned solid box, world frame, metres. @pre min < max on every axis.
struct Box {
  Vec3d min;
  Vec3d max;
};

/// @brief The direction in which a ramp's top rises.
enum class RampAxis : std::uint8_t { kPlusX, kMinusX, kPlusY, kMinusY };

/// @brief Solid wedge over the xy rectangle [min.x, max.x] x [min.y, max.y]. Its bottom is the
/// plane z = min.z; its top rises linearly along `axis` from min.z at the low end (a sharp edge)
/// to max.z at the high end, where a vertical face closes it. @pre min < max on every axis.
struct Ramp {
  Vec3d min;
  Vec3d max;
  RampAxis axis = RampAxis::kPlusX;
};

/// @brief Vertical solid cylinder (a pole) around (x, y), from z_min to z_max, metres.
struct Cylinder {
  double x = 0.0;
  double y = 0.0;
  double radius = 0.0;
  double z_min = 0.0;
  double z_max = 0.0;
};

/// @brief Rectangular hole in the ground over the open rectangle (x_min, x_max) x (y_min, y_max):
/// vertical walls, flat bottom at ground_height - depth. Needs the ground.
struct Ditch {
  double x_min = 0.0;
  double y_min = 0.0;
  double x_max = 0.0;
  double y_max = 0.0;
  double depth = 0.0;
};

/// @brief A scene: the union of its solids. World frame, metres, z up.
struct Scene {
  std::string name;
  bool has_ground = true;      ///< the half-space z <= ground_height is solid (minus the ditches)
  double ground_height = 0.0;  ///< metres
  std::vector<Box> boxes;      ///< walls, crates, table tops and legs, stair steps (expanded)
  std::vector<Ramp> ramps;
  std::vector<Cylinder> poles;
  std::vector<Ditch> ditches;  ///< non-overlapping
};

/// @brief Distance along the unit direction `dir` from `origin` to the first solid surface, or
/// +inf when the ray meets none; 0 when `origin` lies inside a solid (or on its surface).
double castRay(const Scene& scene, Vec3d origin, Vec3d dir) noexcept;

/// @brief The solid intervals [z_low, z_high] of the scene along the vertical line through
/// (x, y), merged (touching intervals join) and sorted bottom-up. The ground is one interval from
/// -inf to ground_height, or to its bottom inside a ditch.
std::vector<std::pair<double, double>> solidIntervals(const Scene& scene, double x, double y);

/// @brief The supporting surface of a column and the free space above it, metres.
struct TrueSurface {
  double height = 0.0;     ///< top of a solid interval
  double clearance = 0.0;  ///< free gap up to the next solid above; +inf when open above
};

/// @brief The true supporting surface of the column through (x, y): among the tops of
/// solidIntervals() whose free gap up to the next solid interval (+inf if none) is at least
/// `min_clearance`, the one nearest to `reference_z` (ties: the lower).
/// @return nullopt when no top has that much clearance (or the column is empty).
std::optional<TrueSurface> trueSurface(const Scene& scene, double x, double y, double reference_z,
                                       double min_clearance);

/// @brief Bounding box of the scene's objects (boxes, ramps, poles, ditches; the infinite ground
/// excluded), or nullopt when there are none.
std::optional<Box> objectBounds(const Scene& scene);

}  // namespace raymap::sim
