// SPDX-License-Identifier: BSD-3-Clause
// The pinhole camera of CameraInfo: plumb_bob distortion inverted to 1e-9 pixel over a whole
// image, validate()'s refusals, and the per-pixel ray table.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>

#include <gtest/gtest.h>

#include "src/core/pinhole_camera.hpp"
#include "tests/support/alloc_counter.hpp"

namespace raymap {
namespace {

/// How close projectNormalised(pixelToNormalised(u, v)) comes back to (u, v), pixels.
constexpr double kRoundTripPx = 1e-9;

/// A 640 × 480 depth camera (D435-like focal length) without distortion.
CameraIntrinsics rectified() {
  CameraIntrinsics c;
  c.width = 640;
  c.height = 480;
  c.fx = 385.0;
  c.fy = 386.5;
  c.cx = 321.25;
  c.cy = 238.75;
  return c;
}

/// The same with a realistic barrel distortion (the size of a wide-angle webcam's).
CameraIntrinsics distorted() {
  CameraIntrinsics c = rectified();
  c.distortion = DistortionModel::kPlumbBob;
  c.k1 = -0.28;
  c.k2 = 0.07;
  c.p1 = 1e-3;
  c.p2 = -5e-4;
  c.k3 = 0.0;
  return c;
}

TEST(PixelToNormalised, WithoutDistortionInvertsK) {
  const CameraIntrinsics c = rectified();
  NormalisedPoint p;

  ASSERT_TRUE(pixelToNormalised(c, 10.0, 400.0, &p));

  EXPECT_DOUBLE_EQ(p.x, (10.0 - c.cx) / c.fx);
  EXPECT_DOUBLE_EQ(p.y, (400.0 - c.cy) / c.fy);
}

TEST(ProjectNormalised, AppliesPlumbBobThenK) {
  const CameraIntrinsics c = distorted();
  const double x = 0.3;
  const double y = -0.2;
  const double r2 = x * x + y * y;
  const double radial = 1.0 + c.k1 * r2 + c.k2 * r2 * r2 + c.k3 * r2 * r2 * r2;
  const double xd = x * radial + 2.0 * c.p1 * x * y + c.p2 * (r2 + 2.0 * x * x);
  const double yd = y * radial + c.p1 * (r2 + 2.0 * y * y) + 2.0 * c.p2 * x * y;

  const NormalisedPoint uv = projectNormalised(c, {x, y});

  EXPECT_NEAR(uv.x, c.fx * xd + c.cx, 1e-12);
  EXPECT_NEAR(uv.y, c.fy * yd + c.cy, 1e-12);
}

TEST(PixelToNormalised, RoundTripsEveryPixelToOneNanopixelWithDistortion) {
  const CameraIntrinsics c = distorted();
  double worst = 0.0;
  for (std::uint32_t v = 0; v < c.height; ++v) {
    for (std::uint32_t u = 0; u < c.width; ++u) {
      NormalisedPoint p;
      ASSERT_TRUE(pixelToNormalised(c, u, v, &p)) << u << ", " << v;
      const NormalisedPoint back = projectNormalised(c, p);
      worst = std::max({worst, std::fabs(back.x - u), std::fabs(back.y - v)});
    }
  }
  EXPECT_LT(worst, kRoundTripPx);
}

TEST(PixelToNormalised, RoundTripsSubpixelPositionsAndTheImageBorder) {
  const CameraIntrinsics c = distorted();
  for (const double u : {-0.5, 0.25, 319.7, 639.5}) {
    for (const double v : {-0.5, 0.75, 240.1, 479.5}) {
      NormalisedPoint p;
      ASSERT_TRUE(pixelToNormalised(c, u, v, &p));
      const NormalisedPoint back = projectNormalised(c, p);
      EXPECT_NEAR(back.x, u, kRoundTripPx);
      EXPECT_NEAR(back.y, v, kRoundTripPx);
    }
  }
}

TEST(PixelToNormalised, RefusesAPixelBeyondTheFold) {
  CameraIntrinsics c = rectified();
  c.distortion = DistortionModel::kPlumbBob;
  c.k1 = -0.5;  // r_d = r - 0.5 r^3 peaks at r_d = 0.544: the corners (r_d = 1.04) have no ray
  NormalisedPoint p;

  EXPECT_FALSE(pixelToNormalised(c, 0.0, 0.0, &p));
  EXPECT_TRUE(pixelToNormalised(c, c.cx, c.cy, &p));
}

TEST(CameraIntrinsicsValidate, AcceptsRealisticCameras) {
  EXPECT_TRUE(rectified().validate());
  EXPECT_TRUE(distorted().validate());
}

/// The message of validate()'s error, or "" when it passed.
std::string errorOf(const CameraIntrinsics& c) {
  const auto result = c.validate();
  return result ? std::string() : result.error().message;
}

TEST(CameraIntrinsicsValidate, RefusesZeroOrNonFiniteFocalLengths) {
  for (const double f : {0.0, -385.0, std::nan(""), HUGE_VAL}) {
    CameraIntrinsics fx = rectified();
    fx.fx = f;
    CameraIntrinsics fy = rectified();
    fy.fy = f;
    EXPECT_NE(errorOf(fx).find("focal"), std::string::npos) << f;
    EXPECT_NE(errorOf(fy).find("focal"), std::string::npos) << f;
  }
}

TEST(CameraIntrinsicsValidate, RefusesSizeZeroAndSidesOver65535) {
  CameraIntrinsics no_width = rectified();
  no_width.width = 0;
  CameraIntrinsics no_height = rectified();
  no_height.height = 0;
  CameraIntrinsics huge = rectified();
  huge.width = 65536;

  EXPECT_NE(errorOf(no_width).find("width and height"), std::string::npos);
  EXPECT_NE(errorOf(no_height).find("width and height"), std::string::npos);
  EXPECT_NE(errorOf(huge).find("width and height"), std::string::npos);
}

TEST(CameraIntrinsicsValidate, RefusesNonFinitePrincipalPointAndCoefficients) {
  CameraIntrinsics cx = rectified();
  cx.cx = std::nan("");
  CameraIntrinsics k2 = distorted();
  k2.k2 = HUGE_VAL;
  CameraIntrinsics p1 = distorted();
  p1.p1 = std::nan("");

  EXPECT_NE(errorOf(cx).find("principal point"), std::string::npos);
  EXPECT_NE(errorOf(k2).find("distortion coefficients"), std::string::npos);
  EXPECT_NE(errorOf(p1).find("distortion coefficients"), std::string::npos);
}

TEST(CameraIntrinsicsValidate, RefusesADistortionThatFoldsOverTheImage) {
  CameraIntrinsics c = rectified();
  c.distortion = DistortionModel::kPlumbBob;
  c.k1 = -0.5;

  EXPECT_NE(errorOf(c).find("folds"), std::string::npos) << errorOf(c);
}

TEST(PixelRayTable, HoldsEachPixelsUndistortedRayAsFloat) {
  const CameraIntrinsics c = distorted();
  PixelRayTable table;

  ASSERT_TRUE(table.build(c));

  ASSERT_TRUE(table.built());
  EXPECT_TRUE(table.matches(c));
  EXPECT_EQ(table.width(), 640U);
  EXPECT_EQ(table.height(), 480U);
  for (const std::uint32_t u : {0U, 1U, 320U, 639U}) {
    for (const std::uint32_t v : {0U, 7U, 240U, 479U}) {
      NormalisedPoint p;
      ASSERT_TRUE(pixelToNormalised(c, u, v, &p));
      EXPECT_EQ(table.ray(u, v)[0], static_cast<float>(p.x)) << u << ", " << v;
      EXPECT_EQ(table.ray(u, v)[1], static_cast<float>(p.y)) << u << ", " << v;
    }
  }
}

TEST(PixelRayTable, RebuildsOnlyForOtherIntrinsics) {
  PixelRayTable table;
  ASSERT_TRUE(table.build(rectified()));
  const float* before = table.ray(0, 0);
  const float x_before = before[0];

  ASSERT_TRUE(table.build(rectified()));  // the same: kept
  EXPECT_EQ(table.ray(0, 0), before);
  ASSERT_TRUE(table.build(distorted()));

  EXPECT_TRUE(table.matches(distorted()));
  EXPECT_FALSE(table.matches(rectified()));
  EXPECT_NE(table.ray(0, 0)[0], x_before);  // the corner moved outwards (barrel distortion)
}

TEST(PixelRayTable, AnInvalidCameraLeavesItUnbuilt) {
  PixelRayTable table;
  ASSERT_TRUE(table.build(rectified()));
  CameraIntrinsics folding = rectified();
  folding.distortion = DistortionModel::kPlumbBob;
  folding.k1 = -0.5;

  const auto result = table.build(folding);

  EXPECT_FALSE(result);
  EXPECT_FALSE(table.built());
  EXPECT_FALSE(table.matches(rectified()));
  table.clear();
  EXPECT_FALSE(table.built());
}

TEST(PixelRayTable, BuildDoesNotAllocateAfterReserve) {
  if (!test::allocationCountingAvailable()) {
    GTEST_SKIP() << "allocation counting is off in sanitizer builds";
  }
  PixelRayTable table;
  table.reserve(640 * 480);
  CameraIntrinsics smaller = distorted();
  smaller.width = 320;
  smaller.height = 240;
  smaller.fx *= 0.5;
  smaller.fy *= 0.5;
  test::AllocationScope scope;

  const bool built_full = static_cast<bool>(table.build(distorted()));
  const bool built_rectified = static_cast<bool>(table.build(rectified()));
  const bool built_smaller = static_cast<bool>(table.build(smaller));

  EXPECT_EQ(scope.count(), 0U);
  EXPECT_TRUE(built_full);
  EXPECT_TRUE(built_rectified);
  EXPECT_TRUE(built_smaller);
}

}  // namespace
}  // namespace raymap
