// SPDX-License-Identifier: BSD-3-Clause
// Eigen-decomposition of a symmetric 3x3 matrix (cyclic Jacobi), for NDT covariances on the host.
#pragma once

#include <array>

#include "src/core/vec3.hpp"

namespace raymap {

/// @brief Eigenvalues in ascending order and their unit eigenvectors (right-handed, so that they
/// form a rotation matrix whose columns are the vectors).
struct SymmetricEigen3 {
  std::array<double, 3> values{};
  std::array<Vec3d, 3> vectors{};
};

/// @brief Decomposes the symmetric matrix given by its packed lower triangle
/// (a00, a10, a11, a20, a21, a22, the packing of kernels/common/ndt.h).
/// Cyclic Jacobi rotations until the off-diagonal is below 1e-12 of the norm (at most 50 sweeps):
/// exact enough for display, and robust for singular and repeated-eigenvalue matrices.
SymmetricEigen3 symmetricEigen3(const std::array<double, 6>& packed) noexcept;

}  // namespace raymap
