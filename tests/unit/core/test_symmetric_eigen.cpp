// SPDX-License-Identifier: BSD-3-Clause
// The 3x3 symmetric eigen solver: A v = lambda v, ascending order, orthonormal right-handed
// vectors.
#include <array>
#include <cmath>

#include <gtest/gtest.h>

#include "src/core/symmetric_eigen.hpp"

namespace raymap {
namespace {

constexpr double kTolerance = 1e-9;

Vec3d times(const std::array<double, 6>& p, Vec3d v) {
  return Vec3d{p[0] * v.x + p[1] * v.y + p[3] * v.z, p[1] * v.x + p[2] * v.y + p[4] * v.z,
               p[3] * v.x + p[4] * v.y + p[5] * v.z};
}

void expectDecomposes(const std::array<double, 6>& p) {
  const SymmetricEigen3 e = symmetricEigen3(p);
  EXPECT_LE(e.values[0], e.values[1]);
  EXPECT_LE(e.values[1], e.values[2]);
  for (int k = 0; k < 3; ++k) {
    const Vec3d v = e.vectors[static_cast<std::size_t>(k)];
    EXPECT_NEAR(v.norm(), 1.0, kTolerance);
    const Vec3d residual = times(p, v) - v * e.values[static_cast<std::size_t>(k)];
    EXPECT_NEAR(residual.norm(), 0.0, kTolerance) << "eigenpair " << k;
  }
  EXPECT_NEAR(e.vectors[0].dot(e.vectors[1]), 0.0, kTolerance);
  const Vec3d a = e.vectors[0];
  const Vec3d b = e.vectors[1];
  const Vec3d cross{a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
  EXPECT_NEAR(cross.dot(e.vectors[2]), 1.0, kTolerance) << "not right-handed";
}

TEST(SymmetricEigen3, DiagonalMatrixGivesItsDiagonalInOrder) {
  const SymmetricEigen3 e = symmetricEigen3({3.0, 0.0, 1.0, 0.0, 0.0, 2.0});
  EXPECT_NEAR(e.values[0], 1.0, kTolerance);
  EXPECT_NEAR(e.values[1], 2.0, kTolerance);
  EXPECT_NEAR(e.values[2], 3.0, kTolerance);
  EXPECT_NEAR(std::abs(e.vectors[0].y), 1.0, kTolerance);
  EXPECT_NEAR(std::abs(e.vectors[2].x), 1.0, kTolerance);
}

TEST(SymmetricEigen3, FullMatrix) { expectDecomposes({4.0, 1.0, 3.0, -2.0, 0.5, 5.0}); }

TEST(SymmetricEigen3, FlatSurfelHasZeroSmallestEigenvalueAlongItsNormal) {
  // Covariance of points spread in the plane z = x (normal (1, 0, -1) / sqrt 2).
  const double s = 0.3;
  const std::array<double, 6> p = {s, 0.0, 0.1, s, 0.0, s};
  expectDecomposes(p);
  const SymmetricEigen3 e = symmetricEigen3(p);
  EXPECT_NEAR(e.values[0], 0.0, kTolerance);
  EXPECT_NEAR(std::abs(e.vectors[0].x), std::sqrt(0.5), kTolerance);
  EXPECT_NEAR(std::abs(e.vectors[0].z), std::sqrt(0.5), kTolerance);
}

TEST(SymmetricEigen3, RepeatedEigenvaluesAndZeroMatrix) {
  expectDecomposes({2.0, 1.0, 2.0, 1.0, 1.0, 2.0});  // eigenvalues 1, 1, 4
  expectDecomposes({0.0, 0.0, 0.0, 0.0, 0.0, 0.0});
}

}  // namespace
}  // namespace raymap
