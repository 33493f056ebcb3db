// SPDX-License-Identifier: BSD-3-Clause
// decodeCameraInfo on hand-built CDR (both byte orders), on Cyclone's own serialization, and on
// serializeCameraInfo's: intrinsics, binning and ROI as image_geometry applies them, and every
// malformed input giving its own error without reading out of bounds or allocating.
#include <cmath>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "sensor_msgs.h"
#include <gtest/gtest.h>

#include "src/dds/topic_types.hpp"
#include "src/msgs/camera_info.hpp"
#include "src/msgs/depth_image_writer.hpp"
#include "tests/support/alloc_counter.hpp"
#include "tests/unit/dds/cdr_test_writer.hpp"
#include "tests/unit/dds/loopback_bytes.hpp"

namespace raymap::dds {

using namespace msgs;  // the ROS 2 message codecs (src/msgs) these tests exercise
namespace {

using test::encodeCameraInfo;
using test::mutateForFuzzing;
using test::TestCameraInfo;

/// Decodes from an exactly sized heap copy (so that ASan sees any read past the end).
Expected<CameraInfoHeader, CameraInfoError> decode(const std::vector<std::byte>& bytes) {
  const std::vector<std::byte> exact(bytes.begin(), bytes.end());
  return decodeCameraInfo(std::span<const std::byte>(exact.data(), exact.size()));
}

CameraInfoError errorOf(const TestCameraInfo& info) {
  const auto result = decode(encodeCameraInfo(info));
  EXPECT_FALSE(result.has_value());
  return result ? CameraInfoError::kMalformed : result.error();
}

/// A D435-like depth camera with a realistic barrel distortion.
TestCameraInfo distortedInfo() {
  TestCameraInfo info;
  info.d = {-0.28, 0.07, 1e-3, -5e-4, 0.0};
  return info;
}

TEST(DecodeCameraInfo, ReadsHeaderSizeKAndPlumbBobInBothByteOrders) {
  for (const bool little : {true, false}) {
    const auto result = decode(encodeCameraInfo(distortedInfo(), little));

    ASSERT_TRUE(result.has_value()) << little;
    EXPECT_EQ(result->stamp_ns, 1'700'000'000'125'000'000);
    EXPECT_STREQ(result->frame_id, "camera_depth_optical_frame");
    const CameraIntrinsics& c = result->camera;
    EXPECT_EQ(c.width, 640U);
    EXPECT_EQ(c.height, 480U);
    EXPECT_EQ(c.fx, 385.0);
    EXPECT_EQ(c.fy, 385.0);
    EXPECT_EQ(c.cx, 320.5);
    EXPECT_EQ(c.cy, 240.5);
    EXPECT_EQ(c.distortion, DistortionModel::kPlumbBob);
    EXPECT_EQ(c.k1, -0.28);
    EXPECT_EQ(c.k2, 0.07);
    EXPECT_EQ(c.p1, 1e-3);
    EXPECT_EQ(c.p2, -5e-4);
    EXPECT_EQ(c.k3, 0.0);
  }
}

TEST(DecodeCameraInfo, ZeroCoefficientsOrNoModelMeanARectifiedImage) {
  TestCameraInfo zeros;  // plumb_bob with D = 0, as rectified depth drivers send it
  TestCameraInfo none;
  none.distortion_model = "";
  none.d = {};

  const auto from_zeros = decode(encodeCameraInfo(zeros));
  const auto from_none = decode(encodeCameraInfo(none));

  ASSERT_TRUE(from_zeros.has_value());
  ASSERT_TRUE(from_none.has_value());
  EXPECT_EQ(from_zeros->camera.distortion, DistortionModel::kNone);
  EXPECT_EQ(from_none->camera.distortion, DistortionModel::kNone);
  EXPECT_EQ(from_zeros->camera, from_none->camera);
}

TEST(DecodeCameraInfo, TakesRationalPolynomialWhoseExtraTermsAreZero) {
  TestCameraInfo info = distortedInfo();
  info.distortion_model = "rational_polynomial";
  info.d = {-0.28, 0.07, 1e-3, -5e-4, 0.01, 0.0, 0.0, 0.0};

  const auto result = decode(encodeCameraInfo(info));

  ASSERT_TRUE(result.has_value());
  EXPECT_EQ(result->camera.distortion, DistortionModel::kPlumbBob);
  EXPECT_EQ(result->camera.k3, 0.01);
}

TEST(DecodeCameraInfo, BinningDividesSizeAndKAsImageGeometryDoes) {
  TestCameraInfo info;
  info.binning_x = 2;
  info.binning_y = 4;

  const auto result = decode(encodeCameraInfo(info));

  ASSERT_TRUE(result.has_value());
  const CameraIntrinsics& c = result->camera;
  EXPECT_EQ(c.width, 320U);
  EXPECT_EQ(c.height, 120U);
  EXPECT_EQ(c.fx, 385.0 / 2);
  EXPECT_EQ(c.cx, 320.5 / 2);
  EXPECT_EQ(c.fy, 385.0 / 4);
  EXPECT_EQ(c.cy, 240.5 / 4);
}

TEST(DecodeCameraInfo, RoiShiftsThePrincipalPointThenBinningDivides) {
  TestCameraInfo info;
  info.roi_x_offset = 100;
  info.roi_y_offset = 40;
  info.roi_width = 400;
  info.roi_height = 300;
  TestCameraInfo binned = info;
  binned.binning_x = 2;
  binned.binning_y = 2;

  const auto roi = decode(encodeCameraInfo(info));
  const auto roi_binned = decode(encodeCameraInfo(binned));

  ASSERT_TRUE(roi.has_value());
  EXPECT_EQ(roi->camera.width, 400U);
  EXPECT_EQ(roi->camera.height, 300U);
  EXPECT_EQ(roi->camera.cx, 220.5);
  EXPECT_EQ(roi->camera.cy, 200.5);
  EXPECT_EQ(roi->camera.fx, 385.0);
  ASSERT_TRUE(roi_binned.has_value());
  EXPECT_EQ(roi_binned->camera.width, 200U);
  EXPECT_EQ(roi_binned->camera.height, 150U);
  EXPECT_EQ(roi_binned->camera.cx, 220.5 / 2);
  EXPECT_EQ(roi_binned->camera.fy, 385.0 / 2);
}

TEST(DecodeCameraInfo, RefusesARoiOutsideTheImage) {
  TestCameraInfo info;
  info.roi_x_offset = 300;
  info.roi_width = 400;  // 300 + 400 > 640
  info.roi_height = 100;
  TestCameraInfo empty;
  empty.roi_x_offset = 10;  // an offset without a size

  EXPECT_EQ(errorOf(info), CameraInfoError::kInvalidIntrinsics);
  EXPECT_EQ(errorOf(empty), CameraInfoError::kInvalidIntrinsics);
}

TEST(DecodeCameraInfo, RefusesZeroFocalLengthAndSizeZero) {
  TestCameraInfo no_fx;
  no_fx.k[0] = 0.0;
  TestCameraInfo no_fy;
  no_fy.k[4] = 0.0;
  TestCameraInfo no_width;
  no_width.width = 0;
  TestCameraInfo too_binned;
  too_binned.binning_y = 481;  // 480 / 481 = 0 rows

  EXPECT_EQ(errorOf(no_fx), CameraInfoError::kInvalidIntrinsics);
  EXPECT_EQ(errorOf(no_fy), CameraInfoError::kInvalidIntrinsics);
  EXPECT_EQ(errorOf(no_width), CameraInfoError::kInvalidIntrinsics);
  EXPECT_EQ(errorOf(too_binned), CameraInfoError::kInvalidIntrinsics);
}

TEST(DecodeCameraInfo, RefusesNonFiniteDAndAFoldingLens) {
  TestCameraInfo nan_d = distortedInfo();
  nan_d.d[1] = std::nan("");
  TestCameraInfo nan_extra = distortedInfo();
  nan_extra.distortion_model = "rational_polynomial";
  nan_extra.d = {0.0, 0.0, 0.0, 0.0, 0.0, std::nan(""), 0.0, 0.0};
  TestCameraInfo folding;
  folding.d = {-0.5, 0.0, 0.0, 0.0, 0.0};

  EXPECT_EQ(errorOf(nan_d), CameraInfoError::kInvalidIntrinsics);
  EXPECT_EQ(errorOf(nan_extra), CameraInfoError::kInvalidIntrinsics);
  EXPECT_EQ(errorOf(folding), CameraInfoError::kInvalidIntrinsics);
}

TEST(DecodeCameraInfo, RefusesDistortionItCannotModel) {
  TestCameraInfo fisheye = distortedInfo();
  fisheye.distortion_model = "equidistant";
  fisheye.d = {0.1, 0.01, 0.0, 0.0};
  TestCameraInfo short_d = distortedInfo();
  short_d.d = {-0.28, 0.07, 0.0, 0.0};
  TestCameraInfo rational = distortedInfo();
  rational.distortion_model = "rational_polynomial";
  rational.d = {-0.28, 0.07, 0.0, 0.0, 0.0, 0.5, 0.0, 0.0};  // k4 != 0
  TestCameraInfo unnamed = distortedInfo();
  unnamed.distortion_model = "";  // coefficients without a model

  EXPECT_EQ(errorOf(fisheye), CameraInfoError::kUnsupportedDistortion);
  EXPECT_EQ(errorOf(short_d), CameraInfoError::kUnsupportedDistortion);
  EXPECT_EQ(errorOf(rational), CameraInfoError::kUnsupportedDistortion);
  EXPECT_EQ(errorOf(unnamed), CameraInfoError::kUnsupportedDistortion);
}

TEST(DecodeCameraInfo, RefusesAFrameIdOf64Characters) {
  TestCameraInfo longest;
  longest.frame_id = std::string(63, 'f');
  TestCameraInfo too_long;
  too_long.frame_id = std::string(64, 'f');

  EXPECT_TRUE(decode(encodeCameraInfo(longest)).has_value());
  EXPECT_EQ(errorOf(too_long), CameraInfoError::kFrameIdTooLong);
}

TEST(DecodeCameraInfo, EveryTruncationIsTruncatedOrBadEncapsulation) {
  const std::vector<std::byte> bytes = encodeCameraInfo(distortedInfo());
  for (std::size_t size = 0; size < bytes.size(); ++size) {
    const auto result = decode(
        std::vector<std::byte>(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(size)));
    ASSERT_FALSE(result.has_value()) << size;
    EXPECT_EQ(result.error(),
              size < 4 ? CameraInfoError::kBadEncapsulation : CameraInfoError::kTruncated)
        << size;
  }
}

TEST(DecodeCameraInfo, AStringWithoutItsNulIsMalformed) {
  std::vector<std::byte> bytes = encodeCameraInfo(TestCameraInfo{});
  // frame_id's NUL: after the 8-byte stamp and the 4-byte length (payload offset 12 + size).
  const std::size_t nul = 4 + 12 + std::string("camera_depth_optical_frame").size();
  ASSERT_EQ(bytes[nul], std::byte{0});
  bytes[nul] = std::byte{'x'};

  const auto result = decode(bytes);

  ASSERT_FALSE(result.has_value());
  EXPECT_EQ(result.error(), CameraInfoError::kMalformed);
  EXPECT_STREQ(toString(result.error()), "malformed");
}

TEST(SerializeCameraInfo, WritesTheBytesOfTheHandBuiltMessage) {
  CameraIntrinsics camera;
  camera.width = 640;
  camera.height = 480;
  camera.fx = 385.0;
  camera.fy = 385.0;
  camera.cx = 320.5;
  camera.cy = 240.5;
  camera.distortion = DistortionModel::kPlumbBob;
  camera.k1 = -0.28;
  camera.k2 = 0.07;
  camera.p1 = 1e-3;
  camera.p2 = -5e-4;
  TestCameraInfo rectified;
  rectified.distortion_model = "";
  rectified.d = {};
  CameraIntrinsics rectified_camera = camera;
  rectified_camera.distortion = DistortionModel::kNone;
  std::vector<std::byte> out;

  serializeCameraInfo(1'700'000'000'125'000'000, "camera_depth_optical_frame", camera, out);
  EXPECT_EQ(out, encodeCameraInfo(distortedInfo()));
  serializeCameraInfo(1'700'000'000'125'000'000, "camera_depth_optical_frame", rectified_camera,
                      out);
  EXPECT_EQ(out, encodeCameraInfo(rectified));
}

TEST(SerializeCameraInfo, RoundTripsThroughTheDecoder) {
  CameraIntrinsics camera;
  camera.width = 424;
  camera.height = 240;
  camera.fx = 211.3;
  camera.fy = 212.9;
  camera.cx = 213.7;
  camera.cy = 118.1;
  camera.distortion = DistortionModel::kPlumbBob;
  camera.k1 = 0.11;
  camera.k2 = -0.02;
  camera.p1 = -2e-4;
  camera.p2 = 3e-4;
  camera.k3 = 0.004;
  std::vector<std::byte> out;

  serializeCameraInfo(-1'500'000'000, "cam", camera, out);  // before the epoch: floor division
  const auto result = decode(out);

  ASSERT_TRUE(result.has_value());
  EXPECT_EQ(result->camera, camera);
  EXPECT_EQ(result->stamp_ns, -1'500'000'000);
  EXPECT_STREQ(result->frame_id, "cam");
}

TEST(SerializeCameraInfo, ReusesTheVectorsCapacity) {
  if (!raymap::test::allocationCountingAvailable()) {
    GTEST_SKIP() << "allocation counting is off in sanitizer builds";
  }
  CameraIntrinsics camera;
  camera.width = 640;
  camera.height = 480;
  camera.fx = camera.fy = 385.0;
  camera.cx = 320.0;
  camera.cy = 240.0;
  std::vector<std::byte> out;
  out.reserve(1024);
  raymap::test::AllocationScope scope;

  serializeCameraInfo(5, "camera", camera, out);

  EXPECT_EQ(scope.count(), 0U);
  EXPECT_FALSE(out.empty());
}

TEST(DecodeCameraInfo, ReadsCyclonesOwnSerialization) {
  // The IDL's CameraInfo_ as Cyclone serializes it: the layout raymapd receives.
  double d[5] = {-0.28, 0.07, 1e-3, -5e-4, 0.0};
  char frame[] = "camera_depth_optical_frame";
  char model[] = "plumb_bob";
  sensor_msgs_msg_dds__CameraInfo_ sample{};
  sample.header.stamp.sec = 1'700'000'000;
  sample.header.stamp.nanosec = 125'000'000;
  sample.header.frame_id = frame;
  sample.height = 480;
  sample.width = 640;
  sample.distortion_model = model;
  sample.d._length = 5;
  sample.d._maximum = 5;
  sample.d._buffer = d;
  const TestCameraInfo reference = distortedInfo();
  std::memcpy(sample.k, reference.k, sizeof(sample.k));
  std::memcpy(sample.r, reference.r, sizeof(sample.r));
  std::memcpy(sample.p, reference.p, sizeof(sample.p));

  const auto bytes = test::cyclonesBytes("rt/decode_test_camera_info", cameraInfoType(), {&sample});
  ASSERT_EQ(bytes.size(), 1U);
  const auto result = decode(bytes[0]);

  ASSERT_TRUE(result.has_value()) << toString(result.error());
  EXPECT_EQ(result->camera, decode(encodeCameraInfo(reference))->camera);
  EXPECT_STREQ(result->frame_id, "camera_depth_optical_frame");
}

TEST(DecodeCameraInfoFuzz, RandomMutationsNeverCrash) {
  const std::vector<std::byte> valid = encodeCameraInfo(distortedInfo());
  std::mt19937 rng(2026);
  int accepted = 0;
  for (int round = 0; round < 3000; ++round) {
    std::vector<std::byte> bytes = valid;
    mutateForFuzzing(bytes, rng);
    const auto result = decode(bytes);
    if (result.has_value()) {
      ++accepted;
      ASSERT_TRUE(result->camera.validate());
      ASSERT_LT(std::strlen(result->frame_id), sizeof(CameraInfoHeader::frame_id));
    }
  }
  EXPECT_GT(accepted, 100);
}

TEST(DecodeCameraInfo, DoesNotAllocate) {
  if (!raymap::test::allocationCountingAvailable()) {
    GTEST_SKIP() << "allocation counting is off in sanitizer builds";
  }
  const std::vector<std::byte> bytes = encodeCameraInfo(distortedInfo());
  raymap::test::AllocationScope scope;

  const auto result = decodeCameraInfo(bytes);

  EXPECT_TRUE(result.has_value());
  EXPECT_EQ(scope.count(), 0U);
}

}  // namespace
}  // namespace raymap::dds
