// SPDX-License-Identifier: BSD-3-Clause
// The principal axes of the NDT ellipsoids (Eigen's solver): A v = lambda v, ascending order,
// orthonormal right-handed vectors.
#include <array>
#include <cmath>

#include <gtest/gtest.h>

#include "src/io/ndt_export.hpp"

namespace raymap::io {
namespace {

constexpr double kTolerance = 1e-9;

Eigen::Vector3d times(const std::array<double, 6>& p, const Eigen::Vector3d& v) {
  return {p[0] * v.x() + p[1] * v.y() + p[3] * v.z(), p[1] * v.x() + p[2] * v.y() + p[4] * v.z(),
          p[3] * v.x() + p[4] * v.y() + p[5] * v.z()};
}

void expectDecomposes(const std::array<double, 6>& p) {
  const PrincipalAxes e = principalAxes(p);
  EXPECT_LE(e.variances[0], e.variances[1]);
  EXPECT_LE(e.variances[1], e.variances[2]);
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d v = e.axes.col(k);
    EXPECT_NEAR(v.norm(), 1.0, kTolerance);
    const Eigen::Vector3d residual = times(p, v) - v * e.variances[k];
    EXPECT_NEAR(residual.norm(), 0.0, kTolerance) << "eigenpair " << k;
  }
  EXPECT_NEAR(e.axes.col(0).dot(e.axes.col(1)), 0.0, kTolerance);
  const Eigen::Vector3d a = e.axes.col(0);
  const Eigen::Vector3d b = e.axes.col(1);
  const Eigen::Vector3d cross{a.y() * b.z() - a.z() * b.y(), a.z() * b.x() - a.x() * b.z(),
                              a.x() * b.y() - a.y() * b.x()};
  EXPECT_NEAR(cross.dot(e.axes.col(2)), 1.0, kTolerance) << "not right-handed";
}

TEST(PrincipalAxes, DiagonalMatrixGivesItsDiagonalInOrder) {
  const PrincipalAxes e = principalAxes({3.0, 0.0, 1.0, 0.0, 0.0, 2.0});
  EXPECT_NEAR(e.variances[0], 1.0, kTolerance);
  EXPECT_NEAR(e.variances[1], 2.0, kTolerance);
  EXPECT_NEAR(e.variances[2], 3.0, kTolerance);
  EXPECT_NEAR(std::abs(e.axes(1, 0)), 1.0, kTolerance);  // the first axis is y
  EXPECT_NEAR(std::abs(e.axes(0, 2)), 1.0, kTolerance);  // the last is x
}

TEST(PrincipalAxes, FullMatrix) { expectDecomposes({4.0, 1.0, 3.0, -2.0, 0.5, 5.0}); }

TEST(PrincipalAxes, FlatSurfelHasZeroSmallestEigenvalueAlongItsNormal) {
  // Covariance of points spread in the plane z = x (normal (1, 0, -1) / sqrt 2).
  const double s = 0.3;
  const std::array<double, 6> p = {s, 0.0, 0.1, s, 0.0, s};
  expectDecomposes(p);
  const PrincipalAxes e = principalAxes(p);
  EXPECT_NEAR(e.variances[0], 0.0, kTolerance);
  EXPECT_NEAR(std::abs(e.axes(0, 0)), std::sqrt(0.5), kTolerance);
  EXPECT_NEAR(std::abs(e.axes(2, 0)), std::sqrt(0.5), kTolerance);
}

TEST(PrincipalAxes, RepeatedEigenvaluesAndZeroMatrix) {
  expectDecomposes({2.0, 1.0, 2.0, 1.0, 1.0, 2.0});  // eigenvalues 1, 1, 4
  expectDecomposes({0.0, 0.0, 0.0, 0.0, 0.0, 0.0});
}

TEST(PrincipalAxes, EveryOrderOfTheDiagonalGivesARightHandedFrame) {
  // Sorting the axes by variance is a permutation; the odd ones are reflections to undo.
  const std::array<std::array<double, 3>, 6> orders = {
      {{1, 2, 3}, {1, 3, 2}, {2, 1, 3}, {2, 3, 1}, {3, 1, 2}, {3, 2, 1}}};
  for (const auto& d : orders) {
    expectDecomposes({d[0], 0.0, d[1], 0.0, 0.0, d[2]});
  }
}

}  // namespace
}  // namespace raymap::io
