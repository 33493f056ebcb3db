// SPDX-License-Identifier: BSD-3-Clause
// Cyclic Jacobi eigen-decomposition of a symmetric 3x3 matrix.
#include "src/core/symmetric_eigen.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

namespace raymap {

SymmetricEigen3 symmetricEigen3(const std::array<double, 6>& p) noexcept {
  // a: the matrix, rotated towards diagonal; v: the accumulated rotation (columns = vectors).
  double a[3][3] = {{p[0], p[1], p[3]}, {p[1], p[2], p[4]}, {p[3], p[4], p[5]}};
  double v[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  double norm = 0.0;
  for (const auto& row : a) {
    for (const double x : row) {
      norm += x * x;
    }
  }
  const double tolerance = 1e-24 * norm;  // squared: off-diagonal below 1e-12 of the norm
  constexpr int kMaxSweeps = 50;
  for (int sweep = 0; sweep < kMaxSweeps; ++sweep) {
    const double off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
    if (off <= tolerance) {
      break;
    }
    for (int i = 0; i < 2; ++i) {
      for (int j = i + 1; j < 3; ++j) {
        if (a[i][j] == 0.0) {
          continue;
        }
        // Rotation in the (i, j) plane that zeroes a[i][j] (Golub & Van Loan, sym.schur2).
        const double theta = (a[j][j] - a[i][i]) / (2.0 * a[i][j]);
        const double t =
            (theta >= 0 ? 1.0 : -1.0) / (std::abs(theta) + std::sqrt(theta * theta + 1));
        const double c = 1.0 / std::sqrt(t * t + 1.0);
        const double s = t * c;
        for (int k = 0; k < 3; ++k) {  // a <- a J (columns i and j)
          const double aki = a[k][i];
          const double akj = a[k][j];
          a[k][i] = c * aki - s * akj;
          a[k][j] = s * aki + c * akj;
        }
        for (int k = 0; k < 3; ++k) {  // a <- J^T a (rows i and j)
          const double aik = a[i][k];
          const double ajk = a[j][k];
          a[i][k] = c * aik - s * ajk;
          a[j][k] = s * aik + c * ajk;
        }
        for (int k = 0; k < 3; ++k) {  // v <- v J
          const double vki = v[k][i];
          const double vkj = v[k][j];
          v[k][i] = c * vki - s * vkj;
          v[k][j] = s * vki + c * vkj;
        }
      }
    }
  }
  std::array<int, 3> order = {0, 1, 2};
  std::sort(order.begin(), order.end(), [&](int x, int y) { return a[x][x] < a[y][y]; });
  SymmetricEigen3 out;
  for (int k = 0; k < 3; ++k) {
    const int c = order[static_cast<std::size_t>(k)];
    out.values[static_cast<std::size_t>(k)] = a[c][c];
    out.vectors[static_cast<std::size_t>(k)] = Vec3d{v[0][c], v[1][c], v[2][c]};
  }
  // Sorting may have swapped two columns: make the frame right-handed again.
  const Vec3d& e0 = out.vectors[0];
  const Vec3d& e1 = out.vectors[1];
  const Vec3d& e2 = out.vectors[2];
  if (e0.cross(e1).dot(e2) < 0.0) {
    out.vectors[2] = Vec3d{-e2.x, -e2.y, -e2.z};
  }
  return out;
}

}  // namespace raymap
