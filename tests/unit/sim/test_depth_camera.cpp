// SPDX-License-Identifier: BSD-3-Clause
// The simulated depth camera: intrinsics from the field of view, the mount convention, depth as
// z along the optical axis (with and without distortion), an edge at its projected pixel, noise,
// determinism, REP 117 invalid pixels, and a full 640 × 480 frame.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "src/sim/depth_camera.hpp"

namespace raymap::sim {
namespace {

constexpr double kAxisTolerance = 1e-12;
/// Depths are float metres: a few float ulps at a few metres.
constexpr double kDepthTolerance = 2e-6;
/// A moderate plumb_bob lens (barrel, with a little tangential distortion).
constexpr std::array<double, 5> kLens = {-0.2, 0.05, 0.001, 0.002, 0.0};

/// A camera on a body at the origin, looking straight down from `height_m`.
DepthCameraModel downward(double height_m, std::uint32_t width = 160, std::uint32_t height = 120) {
  DepthCameraModel m;
  m.width = width;
  m.height = height;
  m.hfov_deg = 87.0;
  m.mount.position_m = {0.0, 0.0, height_m};
  m.mount.pitch_deg = 90.0;
  m.max_range_m = 10.0;
  m.min_range_m = 0.1;
  return m;
}

Scene groundOnly() { return Scene{}; }

std::vector<float> renderOnce(const DepthCamera& camera, const Scene& scene, std::uint64_t seed,
                              const SensorPose& body = {}) {
  std::vector<float> depth(camera.pixels());
  camera.render(scene, cameraPose(camera.model().mount, body), seed, depth);
  return depth;
}

void expectNear(Vec3d a, Vec3d b) {
  EXPECT_NEAR(a.x, b.x, kAxisTolerance);
  EXPECT_NEAR(a.y, b.y, kAxisTolerance);
  EXPECT_NEAR(a.z, b.z, kAxisTolerance);
}

// ---- model ----

TEST(DepthCamera, FocalLengthFromTheFieldOfViewAndCentredPrincipalPoint) {
  DepthCameraModel m;
  m.width = 640;
  m.height = 480;
  m.hfov_deg = 90.0;

  const CameraIntrinsics k = intrinsics(m);

  EXPECT_NEAR(k.fx, 320.0, 1e-9);  // half the width over tan 45°
  EXPECT_EQ(k.fy, k.fx);
  EXPECT_EQ(k.cx, 319.5);  // the centre of the image, pixel (0, 0) being the top-left's centre
  EXPECT_EQ(k.cy, 239.5);
  EXPECT_EQ(k.distortion, DistortionModel::kNone);
  m.cx = 300.0;
  m.distortion = kLens;
  EXPECT_EQ(intrinsics(m).cx, 300.0);
  EXPECT_EQ(intrinsics(m).distortion, DistortionModel::kPlumbBob);
  EXPECT_EQ(intrinsics(m).k1, kLens[0]);
}

TEST(DepthCamera, MountConventionPitchTiltsDownAndTheOpticalFrameIsRightDownForward) {
  CameraMount level;
  level.position_m = {0.3, 0.1, 0.2};
  CameraMount down45 = level;
  down45.pitch_deg = 45.0;
  const SensorPose body{0.0, {1.0, 2.0, 0.5}, std::numbers::pi / 2.0};  // heading +y

  const CameraPose at_zero = cameraPose(level, SensorPose{});
  const CameraPose pitched = cameraPose(down45, SensorPose{});
  const CameraPose turned = cameraPose(level, body);

  // Pitch 0: looking along body +x, image right = body -y, image down = body -z.
  expectNear(at_zero.z_axis, {1.0, 0.0, 0.0});
  expectNear(at_zero.x_axis, {0.0, -1.0, 0.0});
  expectNear(at_zero.y_axis, {0.0, 0.0, -1.0});
  expectNear(at_zero.origin, {0.3, 0.1, 0.2});
  // Pitch +45: forward and down.
  const double h = std::sqrt(0.5);
  expectNear(pitched.z_axis, {h, 0.0, -h});
  expectNear(pitched.y_axis, {-h, 0.0, -h});
  // The body's yaw turns the mount offset and the axes with it.
  expectNear(turned.z_axis, {0.0, 1.0, 0.0});
  expectNear(turned.origin, {1.0 - 0.1, 2.0 + 0.3, 0.7});
}

TEST(DepthCamera, CreateRefusesBadModelsNamingTheField) {
  DepthCameraModel no_fov = downward(1.0);
  no_fov.hfov_deg = 180.0;
  DepthCameraModel ranges = downward(1.0);
  ranges.min_range_m = 5.0;
  ranges.max_range_m = 4.0;
  DepthCameraModel folding = downward(1.0);
  folding.distortion = {-0.5, 0.0, 0.0, 0.0, 0.0};  // r (1 - 0.5 r²) turns back at r = 0.82

  const auto a = DepthCamera::create(no_fov);
  const auto b = DepthCamera::create(ranges);
  const auto c = DepthCamera::create(folding);

  ASSERT_FALSE(a.has_value());
  EXPECT_NE(a.error().message.find("hfov_deg"), std::string::npos) << a.error().message;
  ASSERT_FALSE(b.has_value());
  EXPECT_NE(b.error().message.find("min_range"), std::string::npos) << b.error().message;
  ASSERT_FALSE(c.has_value());
  EXPECT_NE(c.error().message.find("distortion"), std::string::npos) << c.error().message;
}

TEST(DepthCamera, FramesAtTheRateOverTheDurationWithIndependentSeeds) {
  EXPECT_EQ(frameCount(2.0, 5.0), 10);
  EXPECT_EQ(frameCount(0.7, 15.0), 10);  // 10.5 frames
  EXPECT_EQ(frameCount(0.0, 15.0), 0);
  EXPECT_NE(frameSeed(1, 0, 0), frameSeed(1, 0, 1));
  EXPECT_NE(frameSeed(1, 0, 0), frameSeed(1, 1, 0));
  EXPECT_NE(frameSeed(1, 0, 0), frameSeed(2, 0, 0));
  EXPECT_EQ(frameSeed(7, 3, 9), frameSeed(7, 3, 9));
}

// ---- rendering ----

/// Looking straight down at the ground from h, depth (z) is h at every pixel, whatever the lens.
TEST(DepthCamera, DepthIsZSoAPlaneFacingTheCameraIsFlat) {
  for (const bool distorted : {false, true}) {
    SCOPED_TRACE(distorted ? "plumb_bob" : "no distortion");
    DepthCameraModel m = downward(1.5);
    if (distorted) {
      m.distortion = kLens;
    }
    const auto camera = DepthCamera::create(m);
    ASSERT_TRUE(camera.has_value()) << camera.error().message;

    const std::vector<float> depth = renderOnce(*camera, groundOnly(), 1);

    EXPECT_FLOAT_EQ(depth[60 * 160 + 80], 1.5f);
    int off = 0;
    for (const float d : depth) {
      off += std::fabs(static_cast<double>(d) - 1.5) > kDepthTolerance ? 1 : 0;
    }
    EXPECT_EQ(off, 0) << "pixels whose depth is not 1.5 m";
  }
}

/// A box's top edge, 1 m below the camera, appears at the pixel its edge projects to; beyond it
/// the rays meet the box's side, then the ground 2 m down.
TEST(DepthCamera, BoxEdgeLandsAtItsProjectedPixel) {
  Scene scene;
  scene.boxes.push_back({{0.5, -5.0, 0.0}, {5.0, 5.0, 1.0}});
  for (const bool distorted : {false, true}) {
    SCOPED_TRACE(distorted ? "plumb_bob" : "no distortion");
    DepthCameraModel m = downward(2.0);
    if (distorted) {
      m.distortion = kLens;
    }
    const auto camera = DepthCamera::create(m);
    ASSERT_TRUE(camera.has_value()) << camera.error().message;
    const CameraIntrinsics& k = camera->intrinsics();

    const std::vector<float> depth = renderOnce(*camera, scene, 1);

    // Image up is world +x (towards the box); the top edge (x 0.5, z 1) is at normalised
    // (0, -0.5) in the optical frame, the side face's foot (x 0.5, z 0) at (0, -0.25).
    int checked = 0;
    for (std::uint32_t v = 0; v < m.height; ++v) {
      for (std::uint32_t u = 0; u < m.width; ++u) {
        NormalisedPoint p;
        ASSERT_TRUE(pixelToNormalised(k, u, v, &p));
        if (std::fabs(p.y + 0.5) < 1e-4 || std::fabs(p.y + 0.25) < 1e-4) {
          continue;  // a ray grazing an edge: either side is right
        }
        const double expected = p.y < -0.5 ? 1.0 : (p.y < -0.25 ? 0.5 / -p.y : 2.0);
        ASSERT_NEAR(depth[v * m.width + u], expected, 1e-5) << "pixel " << u << ", " << v;
        ++checked;
      }
    }
    EXPECT_GT(checked, 19000);
    // Down the centre column, the depth leaves 1 m between the rows around the edge's
    // projection.
    const NormalisedPoint edge = projectNormalised(k, {0.0, -0.5});
    const auto u = static_cast<std::uint32_t>(std::lround(k.cx));
    const auto last_top = static_cast<std::uint32_t>(std::floor(edge.y));
    EXPECT_FLOAT_EQ(depth[last_top * m.width + u], 1.0f);
    EXPECT_GT(depth[(last_top + 1) * m.width + u], 1.0f);
  }
}

TEST(DepthCamera, NoiseIsGaussianAlongZWithTheGivenSigma) {
  DepthCameraModel m = downward(1.0, 200, 150);
  m.depth_noise_m = 0.01;
  const auto camera = DepthCamera::create(m);
  ASSERT_TRUE(camera.has_value());

  const std::vector<float> depth = renderOnce(*camera, groundOnly(), 42);

  double sum = 0.0;
  double sum2 = 0.0;
  for (const float d : depth) {
    const double e = static_cast<double>(d) - 1.0;
    sum += e;
    sum2 += e * e;
  }
  const double n = static_cast<double>(depth.size());
  const double mean = sum / n;
  const double sd = std::sqrt(sum2 / n - mean * mean);
  EXPECT_NEAR(mean, 0.0, 4.0 * 0.01 / std::sqrt(n));  // 4 standard errors
  EXPECT_NEAR(sd, 0.01, 0.0003);                      // 30,000 samples: about 0.4 % spread
}

TEST(DepthCamera, SameSeedSameImageOtherSeedOtherImage) {
  DepthCameraModel m = downward(1.0);
  m.depth_noise_m = 0.005;
  const auto camera = DepthCamera::create(m);
  ASSERT_TRUE(camera.has_value());

  const std::vector<float> a = renderOnce(*camera, groundOnly(), 5);
  const std::vector<float> b = renderOnce(*camera, groundOnly(), 5);
  const std::vector<float> c = renderOnce(*camera, groundOnly(), 6);

  EXPECT_TRUE(a == b);
  EXPECT_FALSE(a == c);
}

TEST(DepthCamera, InvalidPixelsFollowRep117) {
  // Looking forward (pitch 0) from 1 m: the lower half of the image sees the ground, the upper
  // half nothing at all; a box close ahead on the left is nearer than min_range.
  DepthCameraModel m = downward(1.0);
  m.mount.pitch_deg = 0.0;
  m.max_range_m = 4.0;
  m.min_range_m = 0.5;
  const auto camera = DepthCamera::create(m);
  ASSERT_TRUE(camera.has_value());
  Scene scene;
  scene.boxes.push_back({{0.2, 0.01, 0.9}, {0.3, 5.0, 1.1}});  // left of the optical axis
  const CameraIntrinsics& k = camera->intrinsics();

  const std::vector<float> depth = renderOnce(*camera, scene, 1);

  constexpr float kInf = std::numeric_limits<float>::infinity();
  const auto at = [&](std::uint32_t u, std::uint32_t v) { return depth[v * m.width + u]; };
  EXPECT_EQ(at(80, 10), kInf);            // the sky
  EXPECT_EQ(at(10, 60), -kInf);           // the near box, 0.2 m ahead
  EXPECT_EQ(at(150, 61), kInf);           // the ground at the horizon, beyond 4 m
  EXPECT_EQ(at(150, 119), at(150, 119));  // the ground at the bottom row: valid
  NormalisedPoint p;
  ASSERT_TRUE(pixelToNormalised(k, 150, 119, &p));
  EXPECT_NEAR(at(150, 119), 1.0 / p.y, 1e-5);  // ground 1 m down: z = 1 / (y/z)
}

/// A full-size frame of a stairs-like scene: every pixel, looking down at the floor, the steps
/// and the walls around them, gets a depth. (How long the render takes is a figure for
/// raymap-depth-bench, "simulator_render_640x480_ms", not for a test: docs/testing.md.)
TEST(DepthCamera, RendersA640x480FrameOfTheStairsWithADepthAtEveryPixel) {
  Scene scene;
  for (int k = 1; k <= 6; ++k) {
    scene.boxes.push_back({{2.0 + 0.3 * (k - 1), -0.6, 0.0}, {2.0 + 0.3 * k, 0.6, 0.17 * k}});
  }
  scene.boxes.push_back({{3.8, -0.6, 0.0}, {5.0, 0.6, 1.02}});
  scene.boxes.push_back({{1.9, -0.85, 0.0}, {5.1, -0.65, 2.5}});
  scene.boxes.push_back({{1.9, 0.65, 0.0}, {5.1, 0.85, 2.5}});
  scene.boxes.push_back({{5.0, -0.85, 0.0}, {5.2, 0.85, 2.5}});
  DepthCameraModel m;
  m.width = 640;
  m.height = 480;
  m.mount = {{0.3, 0.0, 0.0}, 0.0, 45.0, 0.0};
  m.depth_noise_m = 0.002;
  const auto camera = DepthCamera::create(m);
  ASSERT_TRUE(camera.has_value());
  const SensorPose body{0.0, {1.0, 0.0, 0.55}, 0.0};
  std::vector<float> depth(camera->pixels());

  camera->render(scene, cameraPose(m.mount, body), 0, depth);

  std::size_t valid = 0;
  for (const float z : depth) {
    valid += std::isfinite(z) && z > 0.0F && z <= static_cast<float>(m.max_range_m) ? 1U : 0U;
  }
  EXPECT_EQ(valid, depth.size());
}

}  // namespace
}  // namespace raymap::sim
