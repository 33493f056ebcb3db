// SPDX-License-Identifier: BSD-3-Clause
// decodeDepthImage: exact back-projection of a tilted plane (with and without lens distortion),
// block-minimum down-sampling, range limits and free-only points, both byte orders, the
// serializer against hand-built and Cyclone-built bytes, and every malformed image giving its
// own error without reading out of bounds or allocating.
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "sensor_msgs.h"
#include <gtest/gtest.h>

#include "src/dds/topic_types.hpp"
#include "src/msgs/depth_image.hpp"
#include "src/msgs/depth_image_writer.hpp"
#include "tests/support/alloc_counter.hpp"
#include "tests/unit/dds/cdr_test_writer.hpp"
#include "tests/unit/dds/loopback_bytes.hpp"

namespace raymap::dds {

using namespace msgs;  // the ROS 2 message codecs (src/msgs) these tests exercise
namespace {

using test::encodeImage;
using test::makeDepthImage;
using test::mutateForFuzzing;
using test::TestImage;

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();
/// Float rounding of a back-projected point a few metres away (a few ulps of 4 m), metres.
constexpr double kFloatRoundingM = 4e-6;

/// A 160 × 120 depth camera, optionally with a realistic barrel distortion.
CameraIntrinsics camera(bool distorted) {
  CameraIntrinsics c;
  c.width = 160;
  c.height = 120;
  c.fx = 100.0;
  c.fy = 101.0;
  c.cx = 79.25;
  c.cy = 60.5;
  if (distorted) {
    c.distortion = DistortionModel::kPlumbBob;
    c.k1 = -0.28;
    c.k2 = 0.07;
    c.p1 = 1e-3;
    c.p2 = -5e-4;
  }
  return c;
}

/// A small rectified camera for the hand-made images (ray of pixel (u, v): ((u - 1.5) / 2,
/// (v - 1.5) / 2), exact in float).
CameraIntrinsics tinyCamera(std::uint32_t width, std::uint32_t height) {
  CameraIntrinsics c;
  c.width = width;
  c.height = height;
  c.fx = 2.0;
  c.fy = 2.0;
  c.cx = 1.5;
  c.cy = 1.5;
  return c;
}

PixelRayTable tableOf(const CameraIntrinsics& c) {
  PixelRayTable table;
  EXPECT_TRUE(table.build(c));
  return table;
}

/// Decodes from an exactly sized heap copy (so that ASan sees any read past the end).
Expected<DepthImageHeader, DepthImageError> decode(const std::vector<std::byte>& bytes,
                                                   const PixelRayTable& rays,
                                                   std::vector<ScanPoint>& out,
                                                   const DepthDecodeOptions& options = {}) {
  const std::vector<std::byte> exact(bytes.begin(), bytes.end());
  return decodeDepthImage(std::span<const std::byte>(exact.data(), exact.size()), rays, options,
                          out);
}

DepthImageError errorOf(const TestImage& image, const PixelRayTable& rays,
                        std::size_t capacity = 1024, const DepthDecodeOptions& options = {}) {
  std::vector<ScanPoint> out(capacity);
  const auto result = decode(encodeImage(image), rays, out, options);
  EXPECT_FALSE(result.has_value());
  return result ? DepthImageError::kMalformed : result.error();
}

/// The camera's optical frame in the world: 0.6 m above the floor (z = 0), looking along +x and
/// pitched 60° down (every pixel of the distorted camera sees the floor within 4 m). Row-major
/// rotation (optical -> world) and translation.
struct Pose {
  double r[3][3];
  double t[3];
};

Pose cameraPose() {
  const double pitch = 60.0 * M_PI / 180.0;
  const double c = std::cos(pitch);
  const double s = std::sin(pitch);
  // Level: optical x -> -y, y -> -z, z -> +x. Then pitched about world y (x towards -z).
  const double level[3][3] = {{0, 0, 1}, {-1, 0, 0}, {0, -1, 0}};
  const double pitch_y[3][3] = {{c, 0, s}, {0, 1, 0}, {-s, 0, c}};
  Pose pose{};
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      for (int k = 0; k < 3; ++k) {
        pose.r[i][j] += pitch_y[i][k] * level[k][j];
      }
    }
  }
  pose.t[2] = 0.6;
  return pose;
}

/// The world height of a point of the optical frame.
double worldZ(const Pose& pose, double x, double y, double z) {
  return pose.r[2][0] * x + pose.r[2][1] * y + pose.r[2][2] * z + pose.t[2];
}

/// The depth (optical z) at which pixel (u, v)'s exact ray meets the floor, in double.
std::vector<double> floorDepths(const CameraIntrinsics& c, const Pose& pose) {
  std::vector<double> depth;
  for (std::uint32_t v = 0; v < c.height; ++v) {
    for (std::uint32_t u = 0; u < c.width; ++u) {
      NormalisedPoint n;
      EXPECT_TRUE(pixelToNormalised(c, u, v, &n));
      const double down = worldZ(pose, n.x, n.y, 1.0) - pose.t[2];  // world z per unit depth
      depth.push_back(-pose.t[2] / down);
    }
  }
  return depth;
}

/// The depths as the float pixels of a 32FC1 image.
std::vector<float> toFloat(const std::vector<double>& depth) {
  std::vector<float> out;
  out.reserve(depth.size());
  for (const double d : depth) {
    out.push_back(static_cast<float>(d));
  }
  return out;
}

class DepthPlane : public ::testing::TestWithParam<bool> {};

TEST_P(DepthPlane, Float32PixelsBackProjectOntoTheFloorWithinFloatRounding) {
  const CameraIntrinsics c = camera(GetParam());
  const PixelRayTable rays = tableOf(c);
  const Pose pose = cameraPose();
  const std::vector<double> truth = floorDepths(c, pose);
  std::vector<float> depth = toFloat(truth);
  const TestImage image = makeDepthImage(c.width, c.height, depth, false);
  std::vector<ScanPoint> out(c.width * c.height);

  const auto result = decode(encodeImage(image), rays, out);

  ASSERT_TRUE(result.has_value()) << toString(result.error());
  ASSERT_EQ(result->points, c.width * c.height);
  EXPECT_EQ(result->invalid, 0U);
  EXPECT_FALSE(result->millimetres);
  double worst = 0.0;
  for (std::size_t i = 0; i < out.size(); ++i) {
    const ScanPoint& p = out[i];
    EXPECT_EQ(p.z, depth[i]);
    EXPECT_EQ(p.flags, 0U);
    worst = std::max(worst, std::fabs(worldZ(pose, static_cast<double>(p.x),
                                             static_cast<double>(p.y), static_cast<double>(p.z))));
  }
  EXPECT_LT(worst, kFloatRoundingM);
}

TEST_P(DepthPlane, MillimetrePixelsBackProjectWithinTheirRounding) {
  const CameraIntrinsics c = camera(GetParam());
  const PixelRayTable rays = tableOf(c);
  const Pose pose = cameraPose();
  const std::vector<double> truth = floorDepths(c, pose);
  const std::vector<float> depth = toFloat(truth);
  const TestImage image = makeDepthImage(c.width, c.height, depth, true);
  std::vector<ScanPoint> out(c.width * c.height);

  const auto result = decode(encodeImage(image), rays, out);

  ASSERT_TRUE(result.has_value());
  ASSERT_EQ(result->points, c.width * c.height);
  EXPECT_TRUE(result->millimetres);
  for (std::size_t i = 0; i < out.size(); ++i) {
    // The depth is the whole millimetre nearest the truth; the point lies exactly on its ray.
    const double mm = std::round(truth[i] * 1000.0);
    ASSERT_EQ(out[i].z, static_cast<float>(mm) / 1000.0f) << i;
    const float* ray =
        rays.ray(static_cast<std::uint32_t>(i % c.width), static_cast<std::uint32_t>(i / c.width));
    ASSERT_EQ(out[i].x, out[i].z * ray[0]);
    ASSERT_EQ(out[i].y, out[i].z * ray[1]);
  }
}

TEST_P(DepthPlane, AWallAtWholeMillimetresBackProjectsWithinFloatRounding) {
  // A plane facing the camera at 1.5 m: every pixel is exactly 1500 mm.
  const CameraIntrinsics c = camera(GetParam());
  const PixelRayTable rays = tableOf(c);
  const std::vector<float> depth(c.width * c.height, 1.5f);
  std::vector<ScanPoint> out(c.width * c.height);

  const auto result =
      decode(encodeImage(makeDepthImage(c.width, c.height, depth, true)), rays, out);

  ASSERT_TRUE(result.has_value());
  for (std::uint32_t v = 0; v < c.height; ++v) {
    for (std::uint32_t u = 0; u < c.width; ++u) {
      const ScanPoint& p = out[v * c.width + u];
      NormalisedPoint n;
      ASSERT_TRUE(pixelToNormalised(c, u, v, &n));
      ASSERT_EQ(p.z, 1.5f);
      EXPECT_NEAR(p.x, 1.5 * n.x, kFloatRoundingM);
      EXPECT_NEAR(p.y, 1.5 * n.y, kFloatRoundingM);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Lens, DepthPlane, ::testing::Values(false, true),
                         [](const auto& lens) { return lens.param ? "Distorted" : "Rectified"; });

TEST(DecodeDepthImage, MillimetresBecomeTheNearestFloatMetre) {
  // Every 16-bit value once: a 65535 × 1 image (the widest CameraIntrinsics takes) plus 65535.
  const CameraIntrinsics c = tinyCamera(65535, 1);
  const PixelRayTable rays = tableOf(c);
  TestImage image;
  image.width = 65535;
  image.height = 1;
  image.encoding = "16UC1";
  image.step = 2 * 65535;
  image.data.resize(image.step);
  for (std::uint32_t raw = 0; raw < 65535; ++raw) {
    test::putValue(image.data, 2 * raw, 4, raw + 1.0, false);  // 1 .. 65535 mm
  }
  std::vector<ScanPoint> out(65535);

  const auto result = decode(encodeImage(image), rays, out);

  ASSERT_TRUE(result.has_value());
  ASSERT_EQ(result->points, 65535U);
  for (std::uint32_t i = 0; i < 65535; ++i) {
    ASSERT_EQ(out[i].z, static_cast<float>(i + 1) / 1000.0f) << i + 1;
  }
}

TEST(DecodeDepthImage, DownsamplePicksEachBlocksNearestDepthAtItsOwnPixel) {
  // 5 × 4 pixels in 2 × 2 blocks: 3 × 2 blocks, the last column of blocks one pixel wide.
  const PixelRayTable rays = tableOf(tinyCamera(5, 4));
  // clang-format off
  const std::vector<float> depth = {
      3.0f, 2.0f,   4.0f, 4.0f,   kNaN,
      2.5f, 9.0f,   4.0f, 3.5f,   1.25f,
      1.0f, 0.0f,   kNaN, kNaN,   2.0f,
      kNaN, 5.0f,   kNaN, 0.75f,  0.5f};
  // clang-format on
  std::vector<ScanPoint> out(6);
  DepthDecodeOptions options;
  options.downsample = 2;

  const auto result = decode(encodeImage(makeDepthImage(5, 4, depth, false)), rays, out, options);

  ASSERT_TRUE(result.has_value());
  ASSERT_EQ(result->points, 6U);
  EXPECT_EQ(result->invalid, 0U);
  const struct {
    std::uint32_t u, v;
    float depth;
  } expected[6] = {{1, 0, 2.0f}, {3, 1, 3.5f},  {4, 1, 1.25f},
                   {0, 2, 1.0f}, {3, 3, 0.75f}, {4, 3, 0.5f}};
  for (std::size_t i = 0; i < 6; ++i) {
    const float* ray = rays.ray(expected[i].u, expected[i].v);
    EXPECT_EQ(out[i].z, expected[i].depth) << i;
    EXPECT_EQ(out[i].x, expected[i].depth * ray[0]) << i;
    EXPECT_EQ(out[i].y, expected[i].depth * ray[1]) << i;
    EXPECT_EQ(out[i].flags, 0U);
  }
}

TEST(DecodeDepthImage, CapacityCountsPartialBlocks) {
  EXPECT_EQ(depthPointCapacity(640, 480, 1), 640U * 480U);
  EXPECT_EQ(depthPointCapacity(640, 480, 6), 107U * 80U);
  EXPECT_EQ(depthPointCapacity(5, 4, 2), 6U);
  EXPECT_EQ(depthPointCapacity(0, 4, 2), 0U);
  EXPECT_EQ(depthPointCapacity(65535, 65535, 1), 65535U * 65535U);
}

TEST(DecodeDepthImage, MinRangeIsAlongTheRayAndLeavesNearPixelsOutOfTheBlockMinimum) {
  // Pixel (0, 0)'s ray is (-0.75, -0.75, 1): range = depth × 1.4577; pixel (1, 1)'s is
  // (-0.25, -0.25, 1): range = depth × 1.0607.
  const PixelRayTable rays = tableOf(tinyCamera(2, 2));
  const std::vector<float> depth = {0.8f, 2.0f, 3.0f, 1.0f};
  std::vector<ScanPoint> out(4);
  DepthDecodeOptions options;
  options.min_range_m = 1.1f;  // (0,0): 0.8 m deep but 1.166 m away: kept; (1,1): 1.061: out

  const auto every = decode(encodeImage(makeDepthImage(2, 2, depth, false)), rays, out, options);
  ASSERT_TRUE(every.has_value());
  ASSERT_EQ(every->points, 3U);
  EXPECT_EQ(every->invalid, 1U);
  EXPECT_EQ(every->too_near, 1U);  // counted: health reports a min range beyond the scene
  EXPECT_EQ(out[0].z, 0.8f);
  EXPECT_EQ(out[1].z, 2.0f);
  EXPECT_EQ(out[2].z, 3.0f);

  options.downsample = 2;      // the nearest one at or beyond min range: (0, 0)
  options.min_range_m = 1.2f;  // now (0, 0) (1.166 m) is out too: (1, 0) at 2 m wins
  const auto block = decode(encodeImage(makeDepthImage(2, 2, depth, false)), rays, out, options);
  ASSERT_TRUE(block.has_value());
  ASSERT_EQ(block->points, 1U);
  EXPECT_EQ(out[0].z, 2.0f);
  EXPECT_EQ(out[0].x, 2.0f * rays.ray(1, 0)[0]);
}

TEST(DecodeDepthImage, ReturnsBeyondMaxRangeAreKeptForTheRayPreparerToClip) {
  const PixelRayTable rays = tableOf(tinyCamera(2, 1));
  std::vector<ScanPoint> out(2);
  DepthDecodeOptions options;
  options.max_range_m = 2.0f;

  const auto result =
      decode(encodeImage(makeDepthImage(2, 1, {1.0f, 7.5f}, false)), rays, out, options);

  ASSERT_TRUE(result.has_value());
  ASSERT_EQ(result->points, 2U);
  EXPECT_EQ(out[1].z, 7.5f);
  EXPECT_EQ(out[1].flags, 0U);
}

TEST(DecodeDepthImage, InvalidPixelsAreLeftOutOrFreeToMaxRangeAlongTheirRay) {
  const PixelRayTable rays = tableOf(tinyCamera(4, 1));
  const std::vector<float> depth = {kNaN, 0.0f, 2.0f, kInf};
  std::vector<ScanPoint> out(4);
  DepthDecodeOptions options;
  options.max_range_m = 3.0f;

  const auto left_out = decode(encodeImage(makeDepthImage(4, 1, depth, false)), rays, out, options);
  ASSERT_TRUE(left_out.has_value());
  EXPECT_EQ(left_out->points, 1U);
  EXPECT_EQ(left_out->invalid, 3U);
  EXPECT_EQ(left_out->free_only, 0U);

  options.invalid_as_free = true;
  const auto free = decode(encodeImage(makeDepthImage(4, 1, depth, false)), rays, out, options);
  ASSERT_TRUE(free.has_value());
  ASSERT_EQ(free->points, 4U);
  EXPECT_EQ(free->invalid, 3U);
  EXPECT_EQ(free->free_only, 3U);
  for (const std::uint32_t u : {0U, 1U, 3U}) {
    const ScanPoint& p = out[u];
    EXPECT_EQ(p.flags, kPointFreeOnly);
    EXPECT_NEAR(std::sqrt(p.x * p.x + p.y * p.y + p.z * p.z), 3.0, 1e-6);
    EXPECT_NEAR(p.x / p.z, rays.ray(u, 0)[0], 1e-7);
    EXPECT_NEAR(p.y / p.z, rays.ray(u, 0)[1], 1e-7);
  }
  EXPECT_EQ(out[2].flags, 0U);
  EXPECT_EQ(out[2].z, 2.0f);

  options.max_range_m = 0.0f;  // no length for a free-only ray: left out
  const auto no_length =
      decode(encodeImage(makeDepthImage(4, 1, depth, false)), rays, out, options);
  ASSERT_TRUE(no_length.has_value());
  EXPECT_EQ(no_length->points, 1U);
}

TEST(DecodeDepthImage, ABlockWithoutAValidDepthIsFreeAlongItsCentrePixel) {
  const PixelRayTable rays = tableOf(tinyCamera(5, 3));
  std::vector<float> depth(15, 0.0f);
  std::vector<ScanPoint> out(6);
  DepthDecodeOptions options;
  options.downsample = 3;
  options.min_range_m = 0.5f;
  options.max_range_m = 2.0f;
  options.invalid_as_free = true;

  const auto result = decode(encodeImage(makeDepthImage(5, 3, depth, true)), rays, out, options);

  ASSERT_TRUE(result.has_value());
  ASSERT_EQ(result->points, 2U);  // blocks u 0..2 and 3..4 (partial)
  EXPECT_EQ(result->free_only, 2U);
  const std::uint32_t centres[2][2] = {{1, 1}, {3, 1}};  // the partial block (u 3..4): 3
  for (std::size_t i = 0; i < 2; ++i) {
    const float* ray = rays.ray(centres[i][0], centres[i][1]);
    EXPECT_EQ(out[i].flags, kPointFreeOnly);
    EXPECT_NEAR(out[i].x / out[i].z, ray[0], 1e-7) << i;
    EXPECT_NEAR(out[i].y / out[i].z, ray[1], 1e-7) << i;
  }
}

TEST(DecodeDepthImage, ABlockOccludedByTheRobotIsNeverFree) {
  // A pixel nearer than min range (the robot's own leg) or at -inf (REP 117: too close to
  // measure) means something is there: its block gives no free space behind it.
  const PixelRayTable rays = tableOf(tinyCamera(6, 3));
  std::vector<float> depth(18, kNaN);
  depth[0] = 0.2f;   // block u 0..2: nearer than min range
  depth[4] = -kInf;  // block u 3..5: too close to measure
  std::vector<ScanPoint> out(6);
  DepthDecodeOptions options;
  options.downsample = 3;
  options.min_range_m = 0.5f;
  options.max_range_m = 2.0f;
  options.invalid_as_free = true;
  const auto blocks = decode(encodeImage(makeDepthImage(6, 3, depth, false)), rays, out, options);
  ASSERT_TRUE(blocks.has_value());
  EXPECT_EQ(blocks->points, 0U);
  EXPECT_EQ(blocks->invalid, 2U);
  EXPECT_EQ(blocks->too_near, 2U);
  // The same, pixel by pixel: only the pixels without a depth are free.
  options.downsample = 1;
  std::vector<ScanPoint> all(18);
  const auto pixels = decode(encodeImage(makeDepthImage(6, 3, depth, false)), rays, all, options);
  ASSERT_TRUE(pixels.has_value());
  EXPECT_EQ(pixels->free_only, 16U);
  EXPECT_EQ(pixels->points, 16U);
  EXPECT_EQ(pixels->too_near, 2U);
}

TEST(DecodeDepthImage, BigEndianPixelsAndMessagesReadTheSame) {
  const CameraIntrinsics c = camera(true);
  const PixelRayTable rays = tableOf(c);
  const std::vector<double> truth = floorDepths(c, cameraPose());
  std::vector<float> depth = toFloat(truth);
  depth[7] = kNaN;
  depth[100] = 0.0f;
  for (const bool millimetres : {false, true}) {
    std::vector<ScanPoint> little_out(depth.size());
    const auto little = decode(encodeImage(makeDepthImage(c.width, c.height, depth, millimetres)),
                               rays, little_out);
    ASSERT_TRUE(little.has_value());
    for (const bool cdr_little : {true, false}) {
      std::vector<ScanPoint> out(depth.size());
      // Big-endian pixels with row padding, in a message of either byte order.
      const TestImage image = makeDepthImage(c.width, c.height, depth, millimetres, true, 3);
      const auto big = decode(encodeImage(image, cdr_little), rays, out);

      ASSERT_TRUE(big.has_value()) << millimetres << cdr_little;
      ASSERT_EQ(big->points, little->points);
      EXPECT_EQ(big->invalid, 2U);
      EXPECT_EQ(std::memcmp(out.data(), little_out.data(), big->points * sizeof(ScanPoint)), 0);
    }
  }
}

TEST(DecodeDepthImage, ReadsHeaderAndMono16) {
  const PixelRayTable rays = tableOf(tinyCamera(2, 1));
  TestImage image = makeDepthImage(2, 1, {1.0f, 2.0f}, true);
  image.encoding = "mono16";
  std::vector<ScanPoint> out(2);

  const auto result = decode(encodeImage(image), rays, out);

  ASSERT_TRUE(result.has_value());
  EXPECT_EQ(result->stamp_ns, 1'700'000'000'125'000'000);
  EXPECT_STREQ(result->frame_id, "camera_depth_optical_frame");
  EXPECT_EQ(result->width, 2U);
  EXPECT_EQ(result->height, 1U);
  EXPECT_TRUE(result->millimetres);
  EXPECT_EQ(out[1].z, 2.0f);
}

TEST(DecodeDepthImage, EveryMalformedImageGivesItsOwnError) {
  const PixelRayTable rays = tableOf(tinyCamera(4, 3));
  const TestImage valid = makeDepthImage(4, 3, std::vector<float>(12, 1.0f), true);
  std::vector<ScanPoint> out(12);
  ASSERT_TRUE(decode(encodeImage(valid), rays, out).has_value());

  TestImage rgb = valid;
  rgb.encoding = "rgb8";
  TestImage signed16 = valid;
  signed16.encoding = "16SC1";
  TestImage short_step = valid;
  short_step.step = 7;  // < 4 × 2
  TestImage short_data = valid;
  short_data.data.pop_back();
  TestImage other_size = makeDepthImage(3, 4, std::vector<float>(12, 1.0f), true);
  TestImage long_frame = valid;
  long_frame.frame_id = std::string(64, 'c');
  TestImage huge_step = valid;
  huge_step.step = 0xFFFFFFFFU;  // step × height overflows 32 bits: data too short

  EXPECT_EQ(errorOf(rgb, rays), DepthImageError::kUnsupportedEncoding);
  EXPECT_EQ(errorOf(signed16, rays), DepthImageError::kUnsupportedEncoding);
  EXPECT_EQ(errorOf(short_step, rays), DepthImageError::kStepTooSmall);
  EXPECT_EQ(errorOf(short_data, rays), DepthImageError::kDataTooShort);
  EXPECT_EQ(errorOf(huge_step, rays), DepthImageError::kDataTooShort);
  EXPECT_EQ(errorOf(other_size, rays), DepthImageError::kCameraInfoMismatch);
  EXPECT_EQ(errorOf(valid, rays, 11), DepthImageError::kTooManyPoints);
  EXPECT_EQ(errorOf(long_frame, rays), DepthImageError::kFrameIdTooLong);
  DepthDecodeOptions by_two;
  by_two.downsample = 2;
  EXPECT_EQ(errorOf(valid, rays, 3, by_two), DepthImageError::kTooManyPoints);  // needs 4
  EXPECT_STREQ(toString(DepthImageError::kStepTooSmall), "step_too_small");
  EXPECT_STREQ(toString(DepthImageError::kUnsupportedEncoding), "unsupported_encoding");
}

TEST(DecodeDepthImage, EveryTruncationIsTruncatedOrBadEncapsulation) {
  const PixelRayTable rays = tableOf(tinyCamera(4, 3));
  const std::vector<std::byte> bytes =
      encodeImage(makeDepthImage(4, 3, std::vector<float>(12, 1.0f), false));
  std::vector<ScanPoint> out(12);
  for (std::size_t size = 0; size < bytes.size(); ++size) {
    const auto result = decode(
        std::vector<std::byte>(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(size)),
        rays, out);
    ASSERT_FALSE(result.has_value()) << size;
    EXPECT_EQ(result.error(),
              size < 4 ? DepthImageError::kBadEncapsulation : DepthImageError::kTruncated)
        << size;
  }
}

TEST(DecodeDepthImage, AStringWithoutItsNulIsMalformed) {
  const PixelRayTable rays = tableOf(tinyCamera(1, 1));
  std::vector<std::byte> bytes = encodeImage(makeDepthImage(1, 1, {1.0f}, false));
  const std::size_t nul = 4 + 12 + std::string("camera_depth_optical_frame").size();
  ASSERT_EQ(bytes[nul], std::byte{0});
  bytes[nul] = std::byte{'x'};
  std::vector<ScanPoint> out(1);

  const auto result = decode(bytes, rays, out);

  ASSERT_FALSE(result.has_value());
  EXPECT_EQ(result.error(), DepthImageError::kMalformed);
}

TEST(SerializeDepthImage, WritesTheBytesOfTheHandBuiltMessageInBothPixelOrders) {
  const std::vector<float> depth = {1.0f, 2.25f, kNaN, 0.0f, 0.0004f, 70.0f, -1.0f, kInf};
  std::vector<std::byte> out;
  for (const bool big : {false, true}) {
    serializeDepthImage(1'700'000'000'125'000'000, "camera_depth_optical_frame", 4, 2,
                        DepthEncoding::k32FC1, big, depth, out);
    EXPECT_EQ(out, encodeImage(makeDepthImage(4, 2, depth, false, big))) << big;

    // 16UC1: millimetres rounded, invalid and negative depths 0, saturated at 65535.
    TestImage expected = makeDepthImage(4, 2, {1.0f, 2.25f, 0, 0, 0, 0, 0, 0}, true, big);
    test::putValue(expected.data, 10, 4, 65535.0, big);
    serializeDepthImage(1'700'000'000'125'000'000, "camera_depth_optical_frame", 4, 2,
                        DepthEncoding::k16UC1, big, depth, out);
    EXPECT_EQ(out, encodeImage(expected)) << big;
  }
}

TEST(SerializeDepthImage, RoundTripsThroughTheDecoder) {
  const CameraIntrinsics c = camera(true);
  const PixelRayTable rays = tableOf(c);
  const std::vector<double> truth = floorDepths(c, cameraPose());
  const std::vector<float> depth = toFloat(truth);
  std::vector<std::byte> bytes;
  std::vector<ScanPoint> direct(depth.size());
  std::vector<ScanPoint> serialized(depth.size());
  for (const bool millimetres : {false, true}) {
    for (const bool big : {false, true}) {
      serializeDepthImage(42, "cam", c.width, c.height,
                          millimetres ? DepthEncoding::k16UC1 : DepthEncoding::k32FC1, big, depth,
                          bytes);
      const auto a = decode(bytes, rays, serialized);
      const auto b =
          decode(encodeImage(makeDepthImage(c.width, c.height, depth, millimetres)), rays, direct);
      ASSERT_TRUE(a.has_value());
      ASSERT_TRUE(b.has_value());
      EXPECT_EQ(a->stamp_ns, 42);
      EXPECT_STREQ(a->frame_id, "cam");
      ASSERT_EQ(a->points, b->points);
      EXPECT_EQ(std::memcmp(serialized.data(), direct.data(), a->points * sizeof(ScanPoint)), 0);
    }
  }
}

TEST(SerializeDepthImage, ReusesTheVectorsCapacity) {
  if (!raymap::test::allocationCountingAvailable()) {
    GTEST_SKIP() << "allocation counting is off in sanitizer builds";
  }
  const std::vector<float> depth(640 * 480, 1.25f);
  std::vector<std::byte> out;
  serializeDepthImage(1, "camera", 640, 480, DepthEncoding::k32FC1, false, depth, out);
  raymap::test::AllocationScope scope;

  serializeDepthImage(2, "camera", 640, 480, DepthEncoding::k16UC1, false, depth, out);
  serializeDepthImage(3, "camera", 640, 480, DepthEncoding::k32FC1, true, depth, out);

  EXPECT_EQ(scope.count(), 0U);
}

TEST(DecodeDepthImage, ReadsCyclonesOwnSerializationAsTheSerializerWritesIt) {
  // The IDL's Image_ as Cyclone serializes it: what raymapd receives from a ROS 2 driver.
  std::vector<float> depth = {1.0f, 2.0f, 0.0f, 3.5f, 1.25f, 0.5f};
  std::vector<std::byte> mine;
  serializeDepthImage(1'700'000'000'125'000'000, "camera_depth_optical_frame", 3, 2,
                      DepthEncoding::k16UC1, false, depth, mine);
  std::vector<std::uint8_t> pixels;  // the last 3 × 2 × 2 bytes
  for (auto it = mine.end() - 12; it != mine.end(); ++it) {
    pixels.push_back(static_cast<std::uint8_t>(*it));
  }
  char frame[] = "camera_depth_optical_frame";
  char encoding[] = "16UC1";
  sensor_msgs_msg_dds__Image_ sample{};
  sample.header.stamp.sec = 1'700'000'000;
  sample.header.stamp.nanosec = 125'000'000;
  sample.header.frame_id = frame;
  sample.height = 2;
  sample.width = 3;
  sample.encoding = encoding;
  sample.step = 6;
  sample.data._length = 12;
  sample.data._maximum = 12;
  sample.data._buffer = pixels.data();

  const auto bytes = test::cyclonesBytes("rt/decode_test_depth_image", imageType(), {&sample});
  ASSERT_EQ(bytes.size(), 1U);
  const PixelRayTable rays = tableOf(tinyCamera(3, 2));
  std::vector<ScanPoint> out(6);
  const auto result = decode(bytes[0], rays, out);

  ASSERT_TRUE(result.has_value()) << toString(result.error());
  EXPECT_EQ(result->points, 5U);
  EXPECT_EQ(out[2].z, 3.5f);
  // The same body bytes (Cyclone may pad the end to 4 bytes and say so in the options).
  ASSERT_GE(bytes[0].size(), mine.size());
  EXPECT_TRUE(std::equal(mine.begin() + 4, mine.end(), bytes[0].begin() + 4));
  EXPECT_EQ(bytes[0][1], mine[1]);  // CDR_LE
}

TEST(DecodeDepthImageFuzz, RandomMutationsNeverCrash) {
  const PixelRayTable rays = tableOf(tinyCamera(6, 4));
  std::vector<float> depth(24);
  for (std::size_t i = 0; i < depth.size(); ++i) {
    depth[i] = 0.5f + 0.1f * static_cast<float>(i);
  }
  depth[5] = kNaN;
  std::mt19937 rng(4242);
  std::vector<ScanPoint> out(24);
  int accepted = 0;
  for (int variant = 0; variant < 4; ++variant) {
    const bool millimetres = (variant & 1) != 0;
    const std::vector<std::byte> valid =
        encodeImage(makeDepthImage(6, 4, depth, millimetres, (variant & 2) != 0));
    for (int round = 0; round < 1500; ++round) {
      std::vector<std::byte> bytes = valid;
      mutateForFuzzing(bytes, rng);
      DepthDecodeOptions options;
      options.downsample = 1 + static_cast<std::uint32_t>(rng() % 3);
      options.max_range_m = 2.0f;
      options.invalid_as_free = (rng() & 1U) != 0;
      const auto result = decode(bytes, rays, out, options);
      if (result.has_value()) {
        ++accepted;
        ASSERT_LE(result->points, out.size());
        ASSERT_LE(result->free_only, result->points);
        ASSERT_LT(std::strlen(result->frame_id), sizeof(DepthImageHeader::frame_id));
      }
    }
  }
  // Mutations of pixel values leave valid images: the fuzzing reaches the pixel loops.
  EXPECT_GT(accepted, 200);
}

TEST(DecodeDepthImage, DoesNotAllocate) {
  if (!raymap::test::allocationCountingAvailable()) {
    GTEST_SKIP() << "allocation counting is off in sanitizer builds";
  }
  const CameraIntrinsics c = camera(true);
  const PixelRayTable rays = tableOf(c);
  std::vector<float> depth(c.width * c.height, 1.5f);
  depth[3] = kNaN;
  const std::vector<std::byte> bytes = encodeImage(makeDepthImage(c.width, c.height, depth, true));
  std::vector<ScanPoint> out(depth.size());
  DepthDecodeOptions free;
  free.max_range_m = 2.0f;
  free.invalid_as_free = true;
  DepthDecodeOptions blocks = free;
  blocks.downsample = 6;
  raymap::test::AllocationScope scope;

  const auto every = decodeDepthImage(bytes, rays, free, out);
  const auto by_six = decodeDepthImage(bytes, rays, blocks, out);

  EXPECT_EQ(scope.count(), 0U);
  EXPECT_TRUE(every.has_value());
  EXPECT_TRUE(by_six.has_value());
}

}  // namespace
}  // namespace raymap::dds
