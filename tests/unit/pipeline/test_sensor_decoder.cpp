// SPDX-License-Identifier: BSD-3-Clause
// SensorDecoder: the per-sensor policy over the decoders (CameraInfo pairing, a camera too large
// for the sensor, refused cameras remembered, frame and rate checks before back-projection).
#include <cstddef>
#include <vector>

#include <gtest/gtest.h>

#include "src/msgs/depth_image_writer.hpp"
#include "src/pipeline/sensor_decoder.hpp"

namespace raymap::pipeline {
namespace {

constexpr std::int64_t kDecoderStamp = 1700000000000000000;

CameraIntrinsics camera(std::uint32_t width, std::uint32_t height) {
  CameraIntrinsics c;
  c.width = width;
  c.height = height;
  c.fx = 100.0;
  c.fy = 100.0;
  c.cx = (width - 1.0) / 2.0;
  c.cy = (height - 1.0) / 2.0;
  return c;
}

std::vector<std::byte> info(const CameraIntrinsics& c, const char* frame = "cam") {
  std::vector<std::byte> cdr;
  msgs::serializeCameraInfo(kDecoderStamp, frame, c, cdr);
  return cdr;
}

std::vector<std::byte> image(std::uint32_t width, std::uint32_t height, std::int64_t stamp,
                             const char* frame = "cam") {
  std::vector<float> depth(std::size_t{width} * height, 1.5f);
  std::vector<std::byte> cdr;
  msgs::serializeDepthImage(stamp, frame, width, height, msgs::DepthEncoding::k32FC1, false, depth,
                            cdr);
  return cdr;
}

SensorDecodeSettings depthSettings() {
  SensorDecodeSettings s;
  s.kind = SensorInputKind::kDepth;
  s.depth.max_range_m = 3.0f;
  s.reserve_pixels = 64 * 48;
  s.max_points = 64 * 48;
  return s;
}

TEST(SensorDecoder, ImagesWaitForTheCameraInfoOfTheirOwnFrame) {
  SensorDecoder decoder(depthSettings());
  std::vector<msgs::ScanPoint> out(64 * 48);
  EXPECT_EQ(decoder.decode(image(64, 48, kDecoderStamp), out).outcome,
            DecodeOutcome::kNoCameraInfo);
  ASSERT_TRUE(decoder.onCameraInfo(info(camera(64, 48), "other")));
  // Another camera's intrinsics (even of another size) are not this image's.
  EXPECT_EQ(decoder.decode(image(32, 24, kDecoderStamp), out).outcome,
            DecodeOutcome::kNoCameraInfo);
  ASSERT_TRUE(decoder.onCameraInfo(info(camera(64, 48))));
  const DecodedScan scan = decoder.decode(image(64, 48, kDecoderStamp), out);
  ASSERT_EQ(scan.outcome, DecodeOutcome::kAccepted);
  EXPECT_EQ(scan.header.points, 64U * 48U);
  EXPECT_STREQ(scan.header.frame_id, "cam");
}

TEST(SensorDecoder, ACameraLargerThanTheSensorTakesIsRefusedAndRemembered) {
  SensorDecoder decoder(depthSettings());
  // 65535 x 65535 pixels: refused before a 34 GB ray table is built.
  const auto huge = decoder.onCameraInfo(info(camera(65535, 65535)));
  ASSERT_FALSE(huge);
  EXPECT_EQ(huge.error(), msgs::CameraInfoError::kTooLarge);
  EXPECT_FALSE(decoder.ready());
  // With down-sampling the same sensor takes a larger camera.
  SensorDecodeSettings blocks = depthSettings();
  blocks.depth.downsample = 2;
  SensorDecoder coarse(blocks);
  EXPECT_TRUE(coarse.onCameraInfo(info(camera(128, 96))));
  // Refused again each time it comes (with every frame), and a lens that folds over the image
  // likewise; the sensor stays without intrinsics.
  const auto again = decoder.onCameraInfo(info(camera(65535, 65535)));
  ASSERT_FALSE(again);
  EXPECT_EQ(again.error(), msgs::CameraInfoError::kTooLarge);
  CameraIntrinsics folding = camera(64, 48);
  folding.distortion = DistortionModel::kPlumbBob;
  folding.k1 = -3.0;
  for (int i = 0; i < 2; ++i) {
    const auto refused = decoder.onCameraInfo(info(folding));
    ASSERT_FALSE(refused);
    EXPECT_EQ(refused.error(), msgs::CameraInfoError::kInvalidIntrinsics);
  }
  EXPECT_FALSE(decoder.ready());
}

TEST(SensorDecoder, TheRateLimitAndTheFrameApplyBeforeBackProjection) {
  SensorDecodeSettings settings = depthSettings();
  settings.max_rate_hz = 5.0;
  settings.frame = "cam";
  SensorDecoder decoder(settings);
  ASSERT_TRUE(decoder.onCameraInfo(info(camera(64, 48))));
  std::vector<msgs::ScanPoint> out(64 * 48);
  EXPECT_EQ(decoder.decode(image(64, 48, kDecoderStamp), out).outcome, DecodeOutcome::kAccepted);
  // 33 ms later: above 5 Hz; 200 ms after the accepted one: taken (1 ms of jitter allowed).
  EXPECT_EQ(decoder.decode(image(64, 48, kDecoderStamp + 33000000), out).outcome,
            DecodeOutcome::kRateLimited);
  EXPECT_EQ(decoder.decode(image(64, 48, kDecoderStamp + 199500000), out).outcome,
            DecodeOutcome::kAccepted);
  // A stamp that goes back (a replay restarted) starts again.
  EXPECT_EQ(decoder.decode(image(64, 48, kDecoderStamp - 1000000000), out).outcome,
            DecodeOutcome::kAccepted);
  // An image in another frame than the configured one, whose CameraInfo came too.
  SensorDecoder typo(settings);
  ASSERT_TRUE(typo.onCameraInfo(info(camera(64, 48), "camera")));
  EXPECT_EQ(typo.decode(image(64, 48, kDecoderStamp, "camera"), out).outcome,
            DecodeOutcome::kWrongFrame);
}

TEST(SensorDecoder, TheRateLimitIsKnownOnArrivalFromTheStampAlone) {
  // raymapd asks before it holds an image undecoded: a 30 Hz camera limited to 5 Hz must not
  // take a queue place from a lidar scan for an image decode() would drop.
  SensorDecodeSettings settings = depthSettings();
  settings.max_rate_hz = 5.0;
  SensorDecoder decoder(settings);  // no CameraInfo needed: only the header is read
  int let_through = 0;
  for (int k = 0; k < 30; ++k) {  // one second at 30 Hz
    let_through += decoder.overRateOnArrival(image(64, 48, kDecoderStamp + k * 33333333)) ? 0 : 1;
  }
  EXPECT_EQ(let_through, 5);
  // A stamp that goes back starts again; unreadable bytes are let through for decode() to name.
  EXPECT_FALSE(decoder.overRateOnArrival(image(64, 48, kDecoderStamp - 1000000000)));
  EXPECT_FALSE(decoder.overRateOnArrival(std::vector<std::byte>(3)));
  // Without a limit nothing is held back, point clouds included.
  SensorDecoder unlimited(depthSettings());
  EXPECT_FALSE(unlimited.overRateOnArrival(image(64, 48, kDecoderStamp)));
  EXPECT_FALSE(unlimited.overRateOnArrival(image(64, 48, kDecoderStamp + 1)));
}

TEST(SensorDecoder, AnImageLargerThanItsBufferIsTooLarge) {
  SensorDecoder decoder(depthSettings());
  ASSERT_TRUE(decoder.onCameraInfo(info(camera(64, 48))));
  std::vector<msgs::ScanPoint> out(100);  // the sensor's own max_points (raymapd slices slots)
  const DecodedScan scan = decoder.decode(image(64, 48, kDecoderStamp), out);
  EXPECT_EQ(scan.outcome, DecodeOutcome::kTooLarge);
  EXPECT_EQ(scan.image_error, msgs::DepthImageError::kTooManyPoints);
}

TEST(SensorDecoder, CameraInfoTopicIsBesideTheImageTopic) {
  EXPECT_EQ(cameraInfoTopicFor("/camera/depth/image_rect_raw"), "/camera/depth/camera_info");
  EXPECT_EQ(cameraInfoTopicFor("rt/cam/depth"), "rt/cam/camera_info");
  EXPECT_EQ(cameraInfoTopicFor("image"), "camera_info");
}

}  // namespace
}  // namespace raymap::pipeline
