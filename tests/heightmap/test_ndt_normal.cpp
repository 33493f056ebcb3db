// SPDX-License-Identifier: BSD-3-Clause
// rm_ndt_normal (kernels/common/ndt_normal.h) on Gaussians folded from known samples: the normal
// of a plane, its orientation, the validity rule, and the eigen-decomposition against P.
#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "kernels/common/ndt_normal.h"

namespace raymap {
namespace {

constexpr double kNormalPi = 3.14159265358979323846;

/// A Gaussian folded from samples given in voxel units (voxel frame).
rm_ndt_voxel fold(const std::vector<std::array<float, 3>>& samples) {
  rm_ndt_voxel v{};
  for (const auto& p : samples) {
    rm_ndt_fold_sample(&v, rm_vec3f_make(p[0], p[1], p[2]));
  }
  return v;
}

/// Samples of the plane through (0.5, 0.5, 0.5) with unit normal n, on a 5 x 5 grid of spacing
/// 0.15 voxel along two in-plane axes.
std::vector<std::array<float, 3>> planeSamples(const std::array<double, 3>& n) {
  // Two unit vectors perpendicular to n.
  std::array<double, 3> a =
      std::fabs(n[0]) < 0.9 ? std::array<double, 3>{1, 0, 0} : std::array<double, 3>{0, 1, 0};
  const double d = a[0] * n[0] + a[1] * n[1] + a[2] * n[2];
  for (std::size_t k = 0; k < 3; ++k) {
    a[k] -= d * n[k];
  }
  const double la = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
  for (double& c : a) {
    c /= la;
  }
  const std::array<double, 3> b{n[1] * a[2] - n[2] * a[1], n[2] * a[0] - n[0] * a[2],
                                n[0] * a[1] - n[1] * a[0]};
  std::vector<std::array<float, 3>> out;
  for (int i = -2; i <= 2; ++i) {
    for (int j = -2; j <= 2; ++j) {
      std::array<float, 3> p{};
      for (std::size_t k = 0; k < 3; ++k) {
        p[k] = static_cast<float>(0.5 + 0.15 * i * a[k] + 0.15 * j * b[k]);
      }
      out.push_back(p);
    }
  }
  return out;
}

double angleDegrees(rm_vec3f n, const std::array<double, 3>& truth) {
  const double c = static_cast<double>(n.x) * truth[0] + static_cast<double>(n.y) * truth[1] +
                   static_cast<double>(n.z) * truth[2];
  return std::acos(std::clamp(c, -1.0, 1.0)) * 180.0 / kNormalPi;
}

TEST(NdtNormal, APlanesNormalPointsUp) {
  // Slopes of 0 to 80 degrees in several azimuths; the normal is given pointing down, so the
  // result must be flipped up.
  for (double slope = 0.0; slope <= 80.0; slope += 20.0) {
    for (double azimuth = 0.0; azimuth < 360.0; azimuth += 45.0) {
      const double s = slope * kNormalPi / 180.0;
      const double a = azimuth * kNormalPi / 180.0;
      const std::array<double, 3> up{-std::sin(s) * std::cos(a), -std::sin(s) * std::sin(a),
                                     std::cos(s)};
      const rm_ndt_voxel v = fold(planeSamples({-up[0], -up[1], -up[2]}));
      const rm_vec3f n = rm_ndt_normal(v.s, v.count, 4);
      ASSERT_FALSE(std::isnan(n.z)) << "slope " << slope << " azimuth " << azimuth;
      EXPECT_LT(angleDegrees(n, up), 0.05) << "slope " << slope << " azimuth " << azimuth;
      EXPECT_GT(n.z, 0.0f);
      EXPECT_NEAR(n.x * n.x + n.y * n.y + n.z * n.z, 1.0, 1e-5);
    }
  }
}

TEST(NdtNormal, AVerticalPlaneFacesPositiveX) {
  // n.z == 0: the first non-zero of x, y is made positive.
  const rm_ndt_voxel v = fold(planeSamples({-1.0, 0.0, 0.0}));
  const rm_vec3f n = rm_ndt_normal(v.s, v.count, 4);
  EXPECT_NEAR(n.x, 1.0f, 1e-5f);
  EXPECT_NEAR(n.y, 0.0f, 1e-5f);
  EXPECT_NEAR(n.z, 0.0f, 1e-5f);
}

TEST(NdtNormal, FewerSamplesThanTheThresholdGiveNoNormal) {
  // Four corners of a square in the plane z = 0.5 voxel: a plane, with exactly 4 samples.
  const std::vector<std::array<float, 3>> samples = {
      {0.2f, 0.2f, 0.5f}, {0.8f, 0.2f, 0.5f}, {0.2f, 0.8f, 0.5f}, {0.8f, 0.8f, 0.5f}};
  const rm_ndt_voxel v = fold(samples);
  EXPECT_FALSE(std::isnan(rm_ndt_normal(v.s, v.count, 4).z));
  EXPECT_TRUE(std::isnan(rm_ndt_normal(v.s, v.count, 5).z));
  const rm_ndt_voxel empty{};
  EXPECT_TRUE(std::isnan(rm_ndt_normal(empty.s, empty.count, 0).z));
}

TEST(NdtNormal, CollinearSamplesGiveNoNormal) {
  std::vector<std::array<float, 3>> samples;
  for (int k = 0; k < 10; ++k) {
    const float t = 0.1f * static_cast<float>(k);
    samples.push_back({t, 0.5f * t, 0.3f + 0.2f * t});
  }
  const rm_ndt_voxel v = fold(samples);
  const rm_vec3f n = rm_ndt_normal(v.s, v.count, 4);
  EXPECT_TRUE(std::isnan(n.x) && std::isnan(n.y) && std::isnan(n.z));
}

TEST(NdtNormal, AnIsotropicCloudGivesNoNormal) {
  // The 8 corners of a cube: P is a multiple of the identity.
  std::vector<std::array<float, 3>> samples;
  for (int k = 0; k < 8; ++k) {
    samples.push_back({0.25f + 0.5f * static_cast<float>(k & 1),
                       0.25f + 0.5f * static_cast<float>((k >> 1) & 1),
                       0.25f + 0.5f * static_cast<float>((k >> 2) & 1)});
  }
  rm_ndt_voxel v = fold(samples);
  EXPECT_TRUE(std::isnan(rm_ndt_normal(v.s, v.count, 4).z));
  // Flattened to a quarter of the height: thickness l0 / l1 = 1/16, a normal along z.
  for (auto& p : samples) {
    p[2] = 0.5f + (p[2] - 0.5f) * 0.25f;
  }
  v = fold(samples);
  const rm_vec3f n = rm_ndt_normal(v.s, v.count, 4);
  EXPECT_NEAR(n.z, 1.0f, 1e-5f);
}

TEST(NdtNormal, EigenpairsSatisfyPvEqualsLambdaV) {
  const rm_ndt_voxel v = fold({{0.1f, 0.2f, 0.3f},
                               {0.9f, 0.1f, 0.4f},
                               {0.5f, 0.8f, 0.2f},
                               {0.3f, 0.6f, 0.9f},
                               {0.7f, 0.4f, 0.6f},
                               {0.2f, 0.9f, 0.5f}});
  float p[6];
  rm_ndt_covariance(v.s, p);
  const float full[3][3] = {{p[0], p[1], p[3]}, {p[1], p[2], p[4]}, {p[3], p[4], p[5]}};
  float value[3];
  rm_vec3f vector[3];
  rm_ndt_eigen(v.s, value, vector);
  for (int k = 0; k < 3; ++k) {
    const float e[3] = {vector[k].x, vector[k].y, vector[k].z};
    for (int r = 0; r < 3; ++r) {
      const float pv = full[r][0] * e[0] + full[r][1] * e[1] + full[r][2] * e[2];
      EXPECT_NEAR(pv, value[k] * e[r], 1e-6f) << "eigenpair " << k << " row " << r;
    }
  }
  EXPECT_NEAR(value[0] + value[1] + value[2], p[0] + p[2] + p[5], 1e-6f);  // the trace
}

}  // namespace
}  // namespace raymap
