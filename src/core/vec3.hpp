// SPDX-License-Identifier: BSD-3-Clause
// Small fixed-size 3-vectors used across the library (host side; kernels have their own C structs).
#pragma once

#include <cmath>
#include <cstdint>
#include <type_traits>

namespace raymap {

/// @brief A 3-vector of doubles: positions and directions in metres (frame given by the name).
struct Vec3d {
  double x = 0.0;
  double y = 0.0;
  double z = 0.0;

  constexpr double operator[](int axis) const noexcept {
    return axis == 0 ? x : (axis == 1 ? y : z);
  }
  constexpr double& operator[](int axis) noexcept { return axis == 0 ? x : (axis == 1 ? y : z); }
  friend constexpr Vec3d operator+(Vec3d a, Vec3d b) noexcept {
    return {a.x + b.x, a.y + b.y, a.z + b.z};
  }
  friend constexpr Vec3d operator-(Vec3d a, Vec3d b) noexcept {
    return {a.x - b.x, a.y - b.y, a.z - b.z};
  }
  friend constexpr Vec3d operator*(Vec3d a, double s) noexcept {
    return {a.x * s, a.y * s, a.z * s};
  }
  friend constexpr Vec3d operator*(double s, Vec3d a) noexcept { return a * s; }
  friend constexpr bool operator==(Vec3d a, Vec3d b) noexcept = default;
  constexpr double dot(Vec3d o) const noexcept { return x * o.x + y * o.y + z * o.z; }
  /// Right-handed cross product, this x o.
  constexpr Vec3d cross(Vec3d o) const noexcept {
    return {y * o.z - z * o.y, z * o.x - x * o.z, x * o.y - y * o.x};
  }
  double norm() const noexcept { return std::sqrt(dot(*this)); }
  bool isFinite() const noexcept {
    return std::isfinite(x) && std::isfinite(y) && std::isfinite(z);
  }
};

/// @brief A 3-vector of 32-bit integers: voxel and region coordinates.
struct Vec3i {
  std::int32_t x = 0;
  std::int32_t y = 0;
  std::int32_t z = 0;

  constexpr std::int32_t operator[](int axis) const noexcept {
    return axis == 0 ? x : (axis == 1 ? y : z);
  }
  constexpr std::int32_t& operator[](int axis) noexcept {
    return axis == 0 ? x : (axis == 1 ? y : z);
  }
  friend constexpr Vec3i operator+(Vec3i a, Vec3i b) noexcept {
    return {a.x + b.x, a.y + b.y, a.z + b.z};
  }
  friend constexpr Vec3i operator-(Vec3i a, Vec3i b) noexcept {
    return {a.x - b.x, a.y - b.y, a.z - b.z};
  }
  friend constexpr bool operator==(Vec3i a, Vec3i b) noexcept = default;
};

static_assert(std::is_trivially_copyable_v<Vec3d> && sizeof(Vec3d) == 24);
static_assert(std::is_trivially_copyable_v<Vec3i> && sizeof(Vec3i) == 12);

}  // namespace raymap
