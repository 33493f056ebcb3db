// SPDX-License-Identifier: BSD-3-Clause
// SensorDecoder: the decoders of PointCloud2, Image and CameraInfo behind one per-sensor policy.
#include "src/pipeline/sensor_decoder.hpp"

#include <cmath>
#include <cstring>
#include <utility>

namespace raymap::pipeline {
namespace {

/// Stamps may jitter by this much against the rate limit's period.
constexpr std::int64_t kRateJitterNs = 1000000;

}  // namespace

SensorDecoder::SensorDecoder(SensorDecodeSettings settings) : settings_(std::move(settings)) {
  if (settings_.kind == SensorInputKind::kDepth) {
    rays_.reserve(settings_.reserve_pixels);
  }
}

Expected<void, dds::CameraInfoError> SensorDecoder::onCameraInfo(std::span<const std::byte> cdr) {
  auto info = dds::decodeCameraInfo(cdr);
  if (!info) {
    return Unexpected(info.error());
  }
  if (rays_.matches(info.value().camera) &&
      std::strcmp(camera_frame_, info.value().frame_id) == 0) {
    return {};  // the same camera again: nothing to do (every frame's CameraInfo comes here)
  }
  if (!rays_.build(info.value().camera)) {
    // decodeCameraInfo validated the intrinsics; a pixel that cannot be inverted is the same
    // defect seen at a pixel the validation did not sample.
    std::memset(camera_frame_, 0, sizeof(camera_frame_));
    return Unexpected(dds::CameraInfoError::kInvalidIntrinsics);
  }
  std::memcpy(camera_frame_, info.value().frame_id, sizeof(camera_frame_));
  return {};
}

bool SensorDecoder::rateAllows(std::int64_t stamp_ns) noexcept {
  if (settings_.max_rate_hz <= 0.0) {
    return true;
  }
  const auto period = static_cast<std::int64_t>(std::llround(1e9 / settings_.max_rate_hz));
  if (accepted_any_ && stamp_ns >= last_accepted_ns_ &&
      stamp_ns - last_accepted_ns_ < period - kRateJitterNs) {
    return false;
  }
  // A stamp that went backwards (a replay restarted, a clock reset) starts the schedule again.
  return true;
}

DecodedScan SensorDecoder::decode(std::span<const std::byte> cdr,
                                  std::span<dds::ScanPoint> out) noexcept {
  DecodedScan result;
  if (settings_.kind == SensorInputKind::kPointCloud) {
    dds::CloudDecodeOptions options;
    options.ignore_time = settings_.time_field == "none";
    options.time_field = settings_.time_field == "auto" || options.ignore_time
                             ? nullptr
                             : settings_.time_field.c_str();
    auto cloud = dds::decodePointCloud2(cdr, out, options);
    if (!cloud) {
      result.cloud_error = cloud.error();
      result.outcome = cloud.error() == dds::CloudError::kTooManyPoints ? DecodeOutcome::kTooLarge
                                                                        : DecodeOutcome::kMalformed;
      return result;
    }
    result.header = cloud.value();
  } else {
    if (!rays_.built()) {
      result.outcome = DecodeOutcome::kNoCameraInfo;
      return result;
    }
    auto image = dds::decodeDepthImage(cdr, rays_, settings_.depth, out);
    if (!image) {
      result.image_error = image.error();
      result.outcome = image.error() == dds::DepthImageError::kTooManyPoints
                           ? DecodeOutcome::kTooLarge
                           : DecodeOutcome::kMalformed;
      return result;
    }
    const dds::DepthImageHeader& h = image.value();
    result.header.stamp_ns = h.stamp_ns;
    std::memcpy(result.header.frame_id, h.frame_id, sizeof(result.header.frame_id));
    result.header.width = h.points;  // an unorganised cloud of the blocks' points
    result.header.height = 1;
    result.header.points = h.points;
    result.header.no_return = 0;  // free-only points have a direction and are integrated
    result.header.has_time = false;
    result.header.has_intensity = false;
    if (std::strcmp(h.frame_id, camera_frame_) != 0) {
      // The intrinsics came for another camera: none for this one yet.
      result.outcome = DecodeOutcome::kNoCameraInfo;
      return result;
    }
  }
  if (!settings_.frame.empty() &&
      std::strcmp(result.header.frame_id, settings_.frame.c_str()) != 0) {
    result.outcome = DecodeOutcome::kWrongFrame;
    return result;
  }
  if (!rateAllows(result.header.stamp_ns)) {
    result.outcome = DecodeOutcome::kRateLimited;
    return result;
  }
  last_accepted_ns_ = result.header.stamp_ns;
  accepted_any_ = true;
  result.outcome = DecodeOutcome::kAccepted;
  return result;
}

std::string cameraInfoTopicFor(const std::string& image_topic) {
  const std::size_t slash = image_topic.rfind('/');
  return (slash == std::string::npos ? std::string() : image_topic.substr(0, slash + 1)) +
         "camera_info";
}

}  // namespace raymap::pipeline
