// SPDX-License-Identifier: BSD-3-Clause
// SensorDecoder: the decoders of PointCloud2, Image and CameraInfo behind one per-sensor policy.
#include "src/pipeline/sensor_decoder.hpp"

#include <cmath>
#include <cstring>
#include <utility>

#include "src/msgs/cdr_reader.hpp"
#include "src/msgs/ros_time.hpp"

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

Expected<void, msgs::CameraInfoError> SensorDecoder::onCameraInfo(std::span<const std::byte> cdr) {
  auto info = msgs::decodeCameraInfo(cdr);
  if (!info) {
    return Unexpected(info.error());
  }
  const CameraIntrinsics& camera = info.value().camera;
  if (rays_.matches(camera) && std::strcmp(camera_frame_, info.value().frame_id) == 0) {
    return {};  // the same camera again: nothing to do (every frame's CameraInfo comes here)
  }
  if (refused_any_ && camera == refused_camera_) {
    return Unexpected(refused_error_);
  }
  const auto refuse = [&](msgs::CameraInfoError error) {
    refused_camera_ = camera;
    refused_error_ = error;
    refused_any_ = true;
    return Unexpected(error);
  };
  if (settings_.max_points > 0 &&
      msgs::depthPointCapacity(camera.width, camera.height, settings_.depth.downsample) >
          settings_.max_points) {
    return refuse(msgs::CameraInfoError::kTooLarge);
  }
  if (!rays_.build(camera)) {
    // decodeCameraInfo checked the intrinsics; a pixel that cannot be inverted is the same
    // defect seen at a pixel that check did not sample.
    std::memset(camera_frame_, 0, sizeof(camera_frame_));
    return refuse(msgs::CameraInfoError::kInvalidIntrinsics);
  }
  std::memcpy(camera_frame_, info.value().frame_id, sizeof(camera_frame_));
  return {};
}

bool SensorDecoder::rateAllows(bool any, std::int64_t last_ns,
                               std::int64_t stamp_ns) const noexcept {
  if (settings_.max_rate_hz <= 0.0) {
    return true;
  }
  const auto period = static_cast<std::int64_t>(std::llround(1e9 / settings_.max_rate_hz));
  if (any && stamp_ns >= last_ns && stamp_ns - last_ns < period - kRateJitterNs) {
    return false;
  }
  // A stamp that went backwards (a replay restarted, a clock reset) starts the schedule again.
  return true;
}

std::optional<std::int64_t> headerStampNs(std::span<const std::byte> cdr) noexcept {
  msgs::CdrReader reader(cdr);
  std::int32_t sec = 0;
  std::uint32_t nanosec = 0;
  if (!reader.readI32(sec) || !reader.readU32(nanosec)) {
    return std::nullopt;
  }
  return msgs::nanosecondsOf(sec, nanosec);
}

bool SensorDecoder::overRateOnArrival(std::span<const std::byte> cdr) noexcept {
  if (settings_.max_rate_hz <= 0.0) {
    return false;
  }
  const std::optional<std::int64_t> stamp = headerStampNs(cdr);
  if (!stamp) {
    return false;
  }
  const std::int64_t stamp_ns = *stamp;
  if (!rateAllows(arrived_any_, last_arrival_ns_, stamp_ns)) {
    return true;
  }
  last_arrival_ns_ = stamp_ns;
  arrived_any_ = true;
  return false;
}

DecodedScan SensorDecoder::decode(std::span<const std::byte> cdr,
                                  std::span<msgs::ScanPoint> out) noexcept {
  return settings_.kind == SensorInputKind::kDepth ? decodeDepth(cdr, out) : decodeCloud(cdr, out);
}

DecodedScan SensorDecoder::decodeCloud(std::span<const std::byte> cdr,
                                       std::span<msgs::ScanPoint> out) noexcept {
  DecodedScan result;
  msgs::CloudDecodeOptions options;
  options.ignore_time = settings_.time_field == "none";
  options.time_field = settings_.time_field == "auto" || options.ignore_time
                           ? nullptr
                           : settings_.time_field.c_str();
  auto cloud = msgs::decodePointCloud2(cdr, out, options);
  if (!cloud) {
    result.cloud_error = cloud.error();
    result.outcome = cloud.error() == msgs::CloudError::kTooManyPoints ? DecodeOutcome::kTooLarge
                                                                       : DecodeOutcome::kMalformed;
    return result;
  }
  result.header = cloud.value();
  result.outcome = admit(result.header.frame_id, result.header.stamp_ns);
  return result;
}

DecodedScan SensorDecoder::decodeDepth(std::span<const std::byte> cdr,
                                       std::span<msgs::ScanPoint> out) noexcept {
  DecodedScan result;
  // Stamp and frame first: an image of a camera without intrinsics yet, of the wrong frame or
  // above the rate limit is dropped before it is back-projected.
  const auto image = msgs::inspectDepthImage(cdr);
  if (!image) {
    result.image_error = image.error();
    result.outcome = DecodeOutcome::kMalformed;
    return result;
  }
  result.header.stamp_ns = image->stamp_ns;
  std::memcpy(result.header.frame_id, image->frame_id, sizeof(result.header.frame_id));
  if (!rays_.built() || std::strcmp(image->frame_id, camera_frame_) != 0) {
    result.outcome = DecodeOutcome::kNoCameraInfo;  // none for this camera yet
    return result;
  }
  const DecodeOutcome admitted = admit(image->frame_id, image->stamp_ns, /*commit=*/false);
  if (admitted != DecodeOutcome::kAccepted) {
    result.outcome = admitted;
    return result;
  }
  const auto decoded = msgs::decodeDepthImage(cdr, rays_, settings_.depth, out);
  if (!decoded) {
    result.image_error = decoded.error();
    result.outcome = decoded.error() == msgs::DepthImageError::kTooManyPoints
                         ? DecodeOutcome::kTooLarge
                         : DecodeOutcome::kMalformed;
    return result;
  }
  result.header.width = decoded->points;  // an unorganised cloud of the blocks' points
  result.header.height = 1;
  result.header.points = decoded->points;
  result.too_near = decoded->too_near;
  result.header.no_return = 0;  // free-only points have a direction and are integrated
  result.header.has_time = false;
  result.header.has_intensity = false;
  result.outcome = admit(image->frame_id, image->stamp_ns);
  return result;
}

DecodeOutcome SensorDecoder::admit(const char* frame_id, std::int64_t stamp_ns,
                                   bool commit) noexcept {
  if (!settings_.frame.empty() && std::strcmp(frame_id, settings_.frame.c_str()) != 0) {
    return DecodeOutcome::kWrongFrame;
  }
  if (!rateAllows(accepted_any_, last_accepted_ns_, stamp_ns)) {
    return DecodeOutcome::kRateLimited;
  }
  if (commit) {
    last_accepted_ns_ = stamp_ns;
    accepted_any_ = true;
  }
  return DecodeOutcome::kAccepted;
}

std::string cameraInfoTopicFor(const std::string& image_topic) {
  const std::size_t slash = image_topic.rfind('/');
  return (slash == std::string::npos ? std::string() : image_topic.substr(0, slash + 1)) +
         "camera_info";
}

}  // namespace raymap::pipeline
