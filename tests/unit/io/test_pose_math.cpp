// SPDX-License-Identifier: BSD-3-Clause
// kernels/common/pose.h, the one definition of pose maths (deskewing, trajectories, TF chains),
// against Eigen 3.4 as the host used it before: bit for bit on x86-64, where Eigen evaluates a
// quaternion product with its SSE2 kernel and a Vector4's squared norm in two lanes, the orders
// pose.h copies. Elsewhere (arm64) Eigen may round otherwise; pose.h is then what all hosts agree
// on, and the comparison is to a few ulps.
#include <cmath>
#include <random>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "kernels/common/pose.h"
#include "src/io/trajectory.hpp"

namespace raymap {
namespace {

#if defined(__x86_64__) && defined(__SSE2__)
constexpr bool kPoseMathEigenOrder = true;
#else
constexpr bool kPoseMathEigenOrder = false;
#endif

rm_quat poseMathToRm(const Eigen::Quaterniond& q) { return rm_quat{q.w(), q.x(), q.y(), q.z()}; }

void expectPoseMathSame(double expected, double actual, const char* what) {
  if (kPoseMathEigenOrder) {
    EXPECT_EQ(expected, actual) << what;  // bit for bit, on purpose
  } else {
    EXPECT_NEAR(expected, actual, 1e-15 * std::max(1.0, std::fabs(expected))) << what;
  }
}

Eigen::Quaterniond poseMathRotation(std::mt19937_64& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  return Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized();
}

TEST(PoseMath, RotationProductAndApplicationAreEigensOnX86) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-80.0, 80.0);
  for (int i = 0; i < 20000; ++i) {
    const Eigen::Quaterniond a = poseMathRotation(rng);
    const Eigen::Quaterniond b = poseMathRotation(rng);
    const Eigen::Vector3d v(u(rng), u(rng), u(rng));
    const Eigen::Vector3d r = a * v;
    const rm_vec3d rr = rm_quat_rotate(poseMathToRm(a), rm_vec3d{v.x(), v.y(), v.z()});
    expectPoseMathSame(r.x(), rr.x, "rotate x");
    expectPoseMathSame(r.y(), rr.y, "rotate y");
    expectPoseMathSame(r.z(), rr.z, "rotate z");
    const Eigen::Quaterniond ab = a * b;
    const rm_quat qab = rm_quat_mul(poseMathToRm(a), poseMathToRm(b));
    expectPoseMathSame(ab.w(), qab.w, "product w");
    expectPoseMathSame(ab.x(), qab.x, "product x");
    expectPoseMathSame(ab.y(), qab.y, "product y");
    expectPoseMathSame(ab.z(), qab.z, "product z");
    if (testing::Test::HasFailure()) {
      return;
    }
  }
}

TEST(PoseMath, InterpolationIsTheNlerpEigenComputed) {
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> u(-50.0, 50.0);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int i = 0; i < 20000; ++i) {
    const io::Pose a{Eigen::Vector3d(u(rng), u(rng), u(rng)), poseMathRotation(rng)};
    const io::Pose b{Eigen::Vector3d(u(rng), u(rng), u(rng)), poseMathRotation(rng)};
    const double f = i % 10 == 0 ? 0.0 : unit(rng);
    // What io::interpolate computed with Eigen before pose.h.
    io::Pose expected = a;
    if (f != 0.0) {
      expected.position = a.position + (b.position - a.position) * f;
      const double sign = a.orientation.dot(b.orientation) < 0.0 ? -1.0 : 1.0;
      expected.orientation.coeffs() =
          (1.0 - f) * a.orientation.coeffs() + (f * sign) * b.orientation.coeffs();
      expected.orientation.normalize();
    }
    const io::Pose got = io::interpolate(a, b, f);
    for (int k = 0; k < 3; ++k) {
      expectPoseMathSame(expected.position[k], got.position[k], "position");
    }
    for (int k = 0; k < 4; ++k) {
      expectPoseMathSame(expected.orientation.coeffs()[k], got.orientation.coeffs()[k],
                         "orientation");
    }
    if (testing::Test::HasFailure()) {
      return;
    }
  }
}

TEST(PoseMath, ComposeAndTransformAreEigensOnX86) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-30.0, 30.0);
  for (int i = 0; i < 20000; ++i) {
    const io::Pose a{Eigen::Vector3d(u(rng), u(rng), u(rng)), poseMathRotation(rng)};
    const io::Pose b{Eigen::Vector3d(u(rng), u(rng), u(rng)), poseMathRotation(rng)};
    const Eigen::Vector3d p(u(rng), u(rng), u(rng));
    const io::Pose c = io::compose(a, b);
    const Eigen::Vector3d expected_position = a.position + a.orientation * b.position;
    const Eigen::Quaterniond expected_orientation = a.orientation * b.orientation;
    const Eigen::Vector3d expected_point = a.position + a.orientation * p;
    const Eigen::Vector3d got_point = a.transform(p);
    for (int k = 0; k < 3; ++k) {
      expectPoseMathSame(expected_position[k], c.position[k], "compose position");
      expectPoseMathSame(expected_point[k], got_point[k], "transform");
    }
    for (int k = 0; k < 4; ++k) {
      expectPoseMathSame(expected_orientation.coeffs()[k], c.orientation.coeffs()[k],
                         "compose orientation");
    }
    if (testing::Test::HasFailure()) {
      return;
    }
  }
}

TEST(PoseMath, InterpolationEndsAndTheShortArc) {
  const rm_pose a{rm_vec3d{1.0, 2.0, 3.0}, rm_quat{1.0, 0.0, 0.0, 0.0}};
  const rm_pose b{rm_vec3d{3.0, 2.0, 1.0}, rm_quat{-0.0, 0.0, 0.0, -1.0}};  // 180 deg about z
  const rm_pose at0 = rm_pose_interpolate(a, b, 0.0);
  EXPECT_EQ(at0.position.x, 1.0);
  EXPECT_EQ(at0.orientation.w, 1.0);
  const rm_pose half = rm_pose_interpolate(a, b, 0.5);
  EXPECT_DOUBLE_EQ(half.position.x, 2.0);
  EXPECT_DOUBLE_EQ(half.position.z, 2.0);
  // q = (0.5, 0, 0, -0.5) normalised: a rotation of -90 degrees about z.
  EXPECT_NEAR(half.orientation.w, std::sqrt(0.5), 1e-15);
  EXPECT_NEAR(half.orientation.z, -std::sqrt(0.5), 1e-15);
  const rm_vec3d x = rm_quat_rotate(half.orientation, rm_vec3d{1.0, 0.0, 0.0});
  EXPECT_NEAR(x.x, 0.0, 1e-15);
  EXPECT_NEAR(x.y, -1.0, 1e-15);
}

}  // namespace
}  // namespace raymap
