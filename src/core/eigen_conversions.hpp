// SPDX-License-Identifier: BSD-3-Clause
// Conversions between raymap's plain Vec3d (rays, maps and everything that crosses the backend
// boundary) and Eigen's Vector3d (host-side poses and rotations). Both are three doubles in the
// same frame and units; a conversion only copies them (inlined to nothing on the hot paths).
#pragma once

#include <Eigen/Core>

#include "src/core/vec3.hpp"

namespace raymap {

/// @brief The same vector as an Eigen vector (frame and units unchanged).
inline Eigen::Vector3d toEigen(const Vec3d& v) noexcept { return {v.x, v.y, v.z}; }

/// @brief The same vector as a plain Vec3d (frame and units unchanged).
inline Vec3d toVec3(const Eigen::Vector3d& v) noexcept { return {v.x(), v.y(), v.z()}; }

}  // namespace raymap
