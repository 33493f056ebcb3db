// SPDX-License-Identifier: BSD-3-Clause
// NDT-OM / NDT-TM rules (kernels/common/ndt.h): the square-root covariance against an independent
// double-precision batch covariance, and misses that erode a surfel only where a ray crosses it.
#include <array>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "kernels/common/ndt.h"
#include "src/map/map_params.hpp"

namespace raymap {
namespace {

using Samples = std::vector<std::array<double, 3>>;

/// The maximum-likelihood covariance of `samples`, in double, two passes (mean, then spread).
std::array<double, 6> batchCovariance(const Samples& samples) {
  std::array<double, 3> mean{};
  for (const auto& s : samples) {
    for (std::size_t k = 0; k < 3; ++k) {
      mean[k] += s[k] / static_cast<double>(samples.size());
    }
  }
  std::array<double, 6> p{};  // packed like rm_ndt_covariance: 00, 10, 11, 20, 21, 22
  for (const auto& s : samples) {
    const double d[3] = {s[0] - mean[0], s[1] - mean[1], s[2] - mean[2]};
    const double n = static_cast<double>(samples.size());
    p[0] += d[0] * d[0] / n;
    p[1] += d[1] * d[0] / n;
    p[2] += d[1] * d[1] / n;
    p[3] += d[2] * d[0] / n;
    p[4] += d[2] * d[1] / n;
    p[5] += d[2] * d[2] / n;
  }
  return p;
}

/// Frobenius norm of a packed symmetric matrix (off-diagonal entries count twice).
double frobenius(const std::array<double, 6>& p) {
  return std::sqrt(p[0] * p[0] + p[2] * p[2] + p[5] * p[5] +
                   2.0 * (p[1] * p[1] + p[3] * p[3] + p[4] * p[4]));
}

rm_ndt_voxel foldAll(const Samples& samples) {
  rm_ndt_voxel v{};
  for (const auto& s : samples) {
    rm_ndt_fold_sample(&v, rm_vec3f_make(static_cast<float>(s[0]), static_cast<float>(s[1]),
                                         static_cast<float>(s[2])));
  }
  return v;
}

/// Relative Frobenius error of the folded covariance against the batch covariance of the float
/// samples the fold saw.
double relativeError(const rm_ndt_voxel& v, const Samples& samples) {
  Samples rounded;
  for (const auto& s : samples) {
    rounded.push_back({double(float(s[0])), double(float(s[1])), double(float(s[2]))});
  }
  const std::array<double, 6> batch = batchCovariance(rounded);
  float p[6];
  rm_ndt_covariance(v.s, p);
  std::array<double, 6> diff{};
  for (std::size_t k = 0; k < 6; ++k) {
    diff[k] = double(p[k]) - batch[k];
  }
  return frobenius(diff) / frobenius(batch);
}

enum class Shape { kPlanar, kTiltedPlanar, kLinear, kSpherical, kAnisotropic };

const char* shapeName(Shape s) {
  switch (s) {
    case Shape::kPlanar:
      return "planar";
    case Shape::kTiltedPlanar:
      return "tilted_planar";
    case Shape::kLinear:
      return "linear";
    case Shape::kSpherical:
      return "spherical";
    case Shape::kAnisotropic:
      return "anisotropic";
  }
  return "?";
}

/// Samples in a voxel (voxel units, [0,1]^3). Planar and linear sets are exactly degenerate in
/// double (before the rounding to float the fold sees).
Samples makeSamples(Shape shape, int count, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.1, 0.9);
  std::normal_distribution<double> g(0.0, 1.0);
  Samples out;
  for (int i = 0; i < count; ++i) {
    switch (shape) {
      case Shape::kPlanar:
        out.push_back({u(rng), u(rng), 0.5});
        break;
      case Shape::kTiltedPlanar: {
        const double x = u(rng);
        const double y = u(rng);
        out.push_back({x, y, 0.2 + 0.3 * x + 0.25 * y});  // a plane through the voxel
        break;
      }
      case Shape::kLinear: {
        const double t = u(rng);
        out.push_back({t, 0.3 + 0.4 * t, 0.8 - 0.5 * t});
        break;
      }
      case Shape::kSpherical: {
        double d[3] = {g(rng), g(rng), g(rng)};
        const double r = 0.35 * std::cbrt(std::uniform_real_distribution<double>(0, 1)(rng)) /
                         std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        out.push_back({0.5 + r * d[0], 0.5 + r * d[1], 0.5 + r * d[2]});
        break;
      }
      case Shape::kAnisotropic:
        out.push_back(
            {0.5 + 0.2 * g(rng), 0.5 + 0.05 * g(rng) + 0.1 * g(rng), 0.5 + 0.01 * g(rng)});
        break;
    }
  }
  return out;
}

struct CovarianceCase {
  Shape shape;
  int count;
};

class SquareRootCovariance : public ::testing::TestWithParam<CovarianceCase> {};

TEST_P(SquareRootCovariance, MatchesTheDoubleBatchCovarianceOfTheSameSamples) {
  const CovarianceCase& c = GetParam();
  const Samples samples =
      makeSamples(c.shape, c.count, 1234u + static_cast<std::uint64_t>(c.count));
  const rm_ndt_voxel v = foldAll(samples);
  ASSERT_EQ(v.count, static_cast<std::uint32_t>(c.count));
  EXPECT_LE(relativeError(v, samples), 1e-4) << shapeName(c.shape) << " x" << c.count;
  // The factor is lower-triangular with a non-negative diagonal, and the mean is the batch mean.
  EXPECT_GE(v.s[0], 0.0f);
  EXPECT_GE(v.s[2], 0.0f);
  EXPECT_GE(v.s[5], 0.0f);
  std::array<double, 3> mean{};
  for (const auto& s : samples) {
    for (std::size_t k = 0; k < 3; ++k) {
      mean[k] += double(float(s[k])) / static_cast<double>(samples.size());
    }
  }
  EXPECT_NEAR(v.mean_x, mean[0], 1e-5);
  EXPECT_NEAR(v.mean_y, mean[1], 1e-5);
  EXPECT_NEAR(v.mean_z, mean[2], 1e-5);
}

std::vector<CovarianceCase> covarianceCases() {
  std::vector<CovarianceCase> cases;
  for (Shape s : {Shape::kPlanar, Shape::kTiltedPlanar, Shape::kLinear, Shape::kSpherical,
                  Shape::kAnisotropic}) {
    for (int n : {2, 5, 100, 10000}) {
      cases.push_back({s, n});
    }
  }
  return cases;
}

INSTANTIATE_TEST_SUITE_P(Shapes, SquareRootCovariance, ::testing::ValuesIn(covarianceCases()),
                         [](const ::testing::TestParamInfo<CovarianceCase>& param) {
                           return std::string(shapeName(param.param.shape)) + "_" +
                                  std::to_string(param.param.count);
                         });

TEST(SquareRootCovariance, DegenerateSetsStaySingularInTheFactor) {
  // Coplanar samples: the factor keeps a zero variance across the plane (the regulariser is
  // applied only where the inverse is needed), and collinear samples keep rank one.
  const rm_ndt_voxel plane = foldAll(makeSamples(Shape::kPlanar, 500, 7));
  float p[6];
  rm_ndt_covariance(plane.s, p);
  EXPECT_LT(std::fabs(p[5]), 1e-9f);
  EXPECT_GT(p[0], 0.04f);  // uniform on 0.8 voxel: 0.8^2 / 12 = 0.053
  const rm_ndt_voxel line = foldAll(makeSamples(Shape::kLinear, 500, 8));
  rm_ndt_covariance(line.s, p);
  // Rank one: every 2x2 minor vanishes.
  EXPECT_LT(std::fabs(p[0] * p[2] - p[1] * p[1]), 1e-7f);
  EXPECT_LT(std::fabs(p[0] * p[5] - p[3] * p[3]), 1e-7f);
}

// ---- misses ----

rm_occupancy_params occupancy() { return OccupancyParams().toKernel(); }

rm_ndt_params ndtParams(double resolution = 0.1) {
  return NdtParams().toKernel(resolution, OccupancyParams(), MapMode::kNdtTm);
}

/// The change of log-odds a ray from `o` to `z` (voxel frame) makes to a voxel holding `v` at
/// log-odds 2.0.
float missDelta(const rm_ndt_voxel& v, rm_vec3f o, rm_vec3f z, int* is_miss = nullptr) {
  int miss = 0;
  const float start = 2.0f;
  const float after = rm_ndt_miss(start, &v, o, z, 1, occupancy(), ndtParams(), &miss);
  if (is_miss != nullptr) {
    *is_miss = miss;
  }
  return after - start;
}

/// The log-odds change of a ray straight through the centre of a surfel: logit(1/2 - alpha/2).
float fullErosion() {
  const float a = ndtParams().adaptation_rate;
  return std::log((0.5f - 0.5f * a) / (0.5f + 0.5f * a));
}

TEST(NdtMiss, DefaultsFollowTheMissProbability) {
  const rm_ndt_params p = ndtParams(0.1);
  EXPECT_NEAR(p.adaptation_rate, 0.2f, 1e-6f);       // 2 (1 - 2 * 0.45)
  EXPECT_NEAR(p.sensor_noise, 0.5f, 1e-6f);          // 0.05 m at 0.1 m voxels
  EXPECT_NEAR(p.reinit_threshold, -1.3863f, 1e-4f);  // logit(0.2)
  EXPECT_EQ(p.sample_threshold, 4u);
  EXPECT_EQ(p.reinit_count, 100u);
  EXPECT_NEAR(fullErosion(), -0.4055f, 1e-4f);  // about twice a plain miss (-0.2007)
}

TEST(NdtMiss, PlanarSurfelErodesOnlyWhereARayCrossesIt) {
  const rm_ndt_voxel wall = foldAll(makeSamples(Shape::kPlanar, 200, 11));  // z = 0.5
  // Straight through the surfel, the return far behind it: the full erosion.
  EXPECT_NEAR(missDelta(wall, {0.5f, 0.5f, -20.0f}, {0.5f, 0.5f, 30.0f}), fullErosion(), 0.02f);
  // Grazing: parallel to the wall, 0.4 voxel above it (4 regulariser sigmas): nothing.
  EXPECT_GT(missDelta(wall, {-20.0f, 0.5f, 0.9f}, {30.0f, 0.5f, 0.9f}), -0.01f);
  // Ending on the surfel: the ray's own return, not evidence against it.
  EXPECT_GT(missDelta(wall, {0.5f, 0.5f, -20.0f}, {0.5f, 0.5f, 0.5f}), -0.01f);
  // Ending short of it (the ray stops 0.4 voxel before the wall): it never reached it.
  EXPECT_GT(missDelta(wall, {0.5f, 0.5f, -20.0f}, {0.5f, 0.5f, 0.1f}), -0.01f);
}

TEST(NdtMiss, PoleErodesOnlyWhenTheRayHitsItsAxis) {
  // A thin vertical pole (radius 0.03 voxel) along x = y = 0.5.
  Samples pole;
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int i = 0; i < 300; ++i) {
    const double a = 6.283185307 * u(rng);
    pole.push_back({0.5 + 0.03 * std::cos(a), 0.5 + 0.03 * std::sin(a), u(rng)});
  }
  const rm_ndt_voxel v = foldAll(pole);
  // Horizontal rays through the voxel: beside the pole (0.4 voxel off the axis) and through it.
  EXPECT_GT(missDelta(v, {-20.0f, 0.9f, 0.5f}, {30.0f, 0.9f, 0.5f}), -0.01f);
  EXPECT_GT(missDelta(v, {-20.0f, 0.1f, 0.3f}, {30.0f, 0.1f, 0.3f}), -0.01f);
  EXPECT_NEAR(missDelta(v, {-20.0f, 0.5f, 0.5f}, {30.0f, 0.5f, 0.5f}), fullErosion(), 0.02f);
  // A plain miss would have eroded all of them.
  EXPECT_LT(occupancy().miss, -0.2f);
}

TEST(NdtMiss, SphereErodesByDistanceFromItsCentre) {
  const rm_ndt_voxel ball = foldAll(makeSamples(Shape::kSpherical, 2000, 3));  // radius 0.35
  const float through = missDelta(ball, {-20.0f, 0.5f, 0.5f}, {30.0f, 0.5f, 0.5f});
  const float edge = missDelta(ball, {-20.0f, 0.65f, 0.5f}, {30.0f, 0.65f, 0.5f});
  const float beside = missDelta(ball, {-20.0f, 0.98f, 0.98f}, {30.0f, 0.98f, 0.98f});
  EXPECT_NEAR(through, fullErosion(), 0.02f);
  EXPECT_LT(through, edge);  // less erosion off centre ...
  EXPECT_LT(edge, beside);   // ... and nearly none at the voxel's corner
  EXPECT_GT(beside, -0.03f);
}

TEST(NdtMiss, YoungOrUnobservedVoxelsTakeAPlainMiss) {
  const rm_occupancy_params occ = occupancy();
  const rm_ndt_params p = ndtParams();
  int is_miss = 0;
  const rm_ndt_voxel empty{};
  EXPECT_FLOAT_EQ(
      rm_ndt_miss(RM_OCC_UNOBSERVED, &empty, {0, 0, -5}, {0, 0, 5}, 1, occ, p, &is_miss), occ.miss);
  EXPECT_EQ(is_miss, 1);
  const rm_ndt_voxel young = foldAll(makeSamples(Shape::kPlanar, 3, 1));  // below 4 samples
  // Even a ray far beside it: too few samples to know where the surface is.
  EXPECT_FLOAT_EQ(
      rm_ndt_miss(1.0f, &young, {-20, 0.95f, 0.95f}, {20, 0.95f, 0.95f}, 1, occ, p, &is_miss),
      1.0f + occ.miss);
}

TEST(NdtMiss, RaysWithoutAReturnErodeUpToTheirEnd) {
  const rm_ndt_voxel wall = foldAll(makeSamples(Shape::kPlanar, 200, 11));
  int is_miss = 0;
  // A ray clipped at max range exactly on the surfel is no return there: it erodes.
  const float clipped = rm_ndt_miss(2.0f, &wall, {0.5f, 0.5f, -20.0f}, {0.5f, 0.5f, 0.5f}, 0,
                                    occupancy(), ndtParams(), &is_miss);
  EXPECT_NEAR(clipped - 2.0f, fullErosion(), 0.02f);
}

TEST(NdtMiss, ClampsAtTheLowerBound) {
  const rm_ndt_voxel wall = foldAll(makeSamples(Shape::kPlanar, 200, 11));
  int is_miss = 0;
  const rm_occupancy_params occ = occupancy();
  EXPECT_FLOAT_EQ(rm_ndt_miss(occ.clamp_min + 0.01f, &wall, {0.5f, 0.5f, -20.0f},
                              {0.5f, 0.5f, 30.0f}, 1, occ, ndtParams(), &is_miss),
                  occ.clamp_min);
}

// ---- hits and NDT-TM ----

TEST(NdtHit, RaisesOccupancyAndFoldsTheSample) {
  rm_ndt_voxel v{};
  float value = RM_OCC_UNOBSERVED;
  rm_ndt_hit(&value, &v, nullptr, nullptr, {0.5f, 0.5f, -10.0f}, {0.2f, 0.3f, 0.4f}, 0.0f,
             occupancy(), ndtParams());
  EXPECT_FLOAT_EQ(value, occupancy().hit);
  EXPECT_EQ(v.count, 1u);
  EXPECT_FLOAT_EQ(v.mean_x, 0.2f);
  rm_ndt_hit(&value, &v, nullptr, nullptr, {0.5f, 0.5f, -10.0f}, {0.4f, 0.3f, 0.4f}, 0.0f,
             occupancy(), ndtParams());
  EXPECT_EQ(v.count, 2u);
  EXPECT_FLOAT_EQ(v.mean_x, 0.3f);
  EXPECT_NEAR(v.s[0] * v.s[0], 0.01f, 1e-6f);  // variance of {0.2, 0.4}
}

TEST(NdtHit, ReinitialisesATransientSurfaceThatBecameFree) {
  rm_ndt_params p = ndtParams();
  p.reinit_count = 10;
  rm_ndt_voxel v = foldAll(makeSamples(Shape::kPlanar, 20, 4));
  // Likely free now (below logit(0.2)) with >= reinit_count samples: the Gaussian restarts.
  float value = -1.5f;
  rm_ndt_hit(&value, &v, nullptr, nullptr, {0.5f, 0.5f, -10.0f}, {0.7f, 0.7f, 0.1f}, 0.0f,
             occupancy(), p);
  EXPECT_EQ(v.count, 1u);
  EXPECT_FLOAT_EQ(v.mean_z, 0.1f);
  EXPECT_FLOAT_EQ(v.s[0], 0.0f);
  // Above the threshold it keeps folding.
  rm_ndt_voxel w = foldAll(makeSamples(Shape::kPlanar, 20, 4));
  value = -1.0f;
  rm_ndt_hit(&value, &w, nullptr, nullptr, {0.5f, 0.5f, -10.0f}, {0.7f, 0.7f, 0.1f}, 0.0f,
             occupancy(), p);
  EXPECT_EQ(w.count, 21u);
}

TEST(NdtTm, IntensityIsTheRunningMeanAndVarianceWithAOneSamplePrior) {
  rm_ndt_voxel v{};
  rm_ndt_hit_miss hm{};
  rm_ndt_intensity in{};
  float value = RM_OCC_UNOBSERVED;
  const rm_ndt_params p = ndtParams();
  std::mt19937_64 rng(9);
  std::normal_distribution<double> g(40.0, 6.0);
  std::vector<double> values;
  for (int i = 0; i < 500; ++i) {
    const auto intensity = static_cast<float>(g(rng));
    values.push_back(static_cast<double>(intensity));
    rm_ndt_hit(&value, &v, &hm, &in, {0.5f, 0.5f, -10.0f}, {0.5f, 0.5f, 0.5f}, intensity,
               occupancy(), p);
  }
  double mean = 0.0;
  const auto n = static_cast<double>(values.size());
  for (double x : values) {
    mean += x / n;
  }
  double m2 = 0.0;
  for (double x : values) {
    m2 += (x - mean) * (x - mean);
  }
  EXPECT_NEAR(in.mean, mean, 1e-3);
  // (prior + sum of squares) / n
  EXPECT_NEAR(in.variance, (double(p.initial_intensity_variance) + m2) / n, 1e-2);
}

TEST(NdtTm, PassesBesideASurfelCountAsMissesAndHitsOnItAsHits) {
  rm_ndt_voxel wall = foldAll(makeSamples(Shape::kPlanar, 200, 11));
  rm_ndt_hit_miss hm{};
  int is_miss = 0;
  (void)missDelta(wall, {-20.0f, 0.5f, 0.9f}, {30.0f, 0.5f, 0.9f}, &is_miss);  // beside
  rm_ndt_count_miss(&hm, is_miss);
  EXPECT_EQ(hm.miss, 1u);
  (void)missDelta(wall, {0.5f, 0.5f, -20.0f}, {0.5f, 0.5f, 30.0f}, &is_miss);  // through
  rm_ndt_count_miss(&hm, is_miss);
  EXPECT_EQ(hm.miss, 1u);
  // A return on the surfel is a hit.
  hm = {5, 1};
  rm_ndt_intensity in{10.0f, 1.0f};
  float value = 2.0f;
  rm_ndt_hit(&value, &wall, &hm, &in, {0.5f, 0.5f, -20.0f}, {0.5f, 0.5f, 0.5f}, 10.0f, occupancy(),
             ndtParams());
  EXPECT_EQ(hm.hit, 6u);
  EXPECT_EQ(hm.miss, 1u);
  // A first hit starts the counts afresh.
  rm_ndt_voxel fresh{};
  value = RM_OCC_UNOBSERVED;
  rm_ndt_hit(&value, &fresh, &hm, &in, {0.5f, 0.5f, -20.0f}, {0.5f, 0.5f, 0.5f}, 3.0f, occupancy(),
             ndtParams());
  EXPECT_EQ(hm.hit, 1u);
  EXPECT_EQ(hm.miss, 0u);
  EXPECT_FLOAT_EQ(in.mean, 3.0f);
  EXPECT_FLOAT_EQ(in.variance, ndtParams().initial_intensity_variance);
}

}  // namespace
}  // namespace raymap
