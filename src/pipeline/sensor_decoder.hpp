// SPDX-License-Identifier: BSD-3-Clause
// One sensor's input: a lidar's PointCloud2, or a depth camera's Image with the CameraInfo it
// is back-projected with, decoded into scan points in the sensor's frame, rate-limited and
// checked against the configured frame. One definition for raymapd's ingest thread and the
// offline readers of bags (raymap populate), so both turn the same messages into the same rays.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>

#include "raymap/expected.hpp"

#include "src/core/pinhole_camera.hpp"
#include "src/msgs/camera_info.hpp"
#include "src/msgs/depth_image.hpp"
#include "src/msgs/point_cloud.hpp"

namespace raymap::pipeline {

/// What a sensor publishes.
enum class SensorInputKind : std::uint8_t {
  kPointCloud,  ///< sensor_msgs/PointCloud2
  kDepth,       ///< sensor_msgs/Image (16UC1 / 32FC1) with sensor_msgs/CameraInfo
};

/// @brief How one sensor's messages are decoded (from raymapd's sensors[] or populate's flags).
struct SensorDecodeSettings {
  SensorInputKind kind = SensorInputKind::kPointCloud;
  /// Point clouds: the per-point time field ("auto", "none" or a name).
  std::string time_field = "auto";
  /// Depth cameras: down-sampling, ranges and invalid pixels (msgs::DepthDecodeOptions).
  msgs::DepthDecodeOptions depth;
  /// The frame messages must carry; empty: any (the message's frame is used).
  std::string frame;
  /// Messages whose stamps follow the last accepted one's by less than 1 / max_rate_hz (less
  /// 1 ms of jitter) are dropped; 0 = every message.
  double max_rate_hz = 0.0;
  /// Depth cameras: pixels the ray table is sized for up front (no allocation for cameras up
  /// to this size; a larger one allocates once, when its CameraInfo first arrives).
  std::size_t reserve_pixels = 640 * 480;
  /// Depth cameras: the most points an image may give (sensors[].max_points). A CameraInfo whose
  /// images would give more is refused (kTooLarge) before its pixel rays are built. 0 = any.
  std::uint32_t max_points = 0;
};

/// Why a message gave no scan.
enum class DecodeOutcome : std::uint8_t {
  kAccepted,
  kRateLimited,   ///< faster than max_rate_hz
  kMalformed,     ///< the decoder refused it (`cloud_error` or `image_error` says why)
  kTooLarge,      ///< more points than the buffer holds
  kWrongFrame,    ///< header.frame_id is not the configured frame
  kNoCameraInfo,  ///< a depth image before any usable CameraInfo of its frame
};

/// @brief What decode() did with one message.
struct DecodedScan {
  DecodeOutcome outcome = DecodeOutcome::kMalformed;
  msgs::CloudHeader header{};  ///< valid when accepted (and frame_id when kWrongFrame)
  msgs::CloudError cloud_error = msgs::CloudError::kTruncated;            ///< point clouds
  msgs::DepthImageError image_error = msgs::DepthImageError::kTruncated;  ///< depth images
  /// Depth images: blocks (pixels at downsample 1) that gave no point because something in them
  /// is nearer than the sensor's min range. Counted, so that a min range beyond what the camera
  /// sees is reported instead of giving empty scans silently.
  std::uint32_t too_near = 0;
};

/// @brief The header stamp (ns since the epoch) of a PointCloud2 or Image, read from the CDR
/// without decoding the rest (both begin with std_msgs/Header, whose stamp comes first);
/// nullopt when the message is too short. @rt allocates: no.
std::optional<std::int64_t> headerStampNs(std::span<const std::byte> cdr) noexcept;

/// @brief Decodes one sensor's messages. Thread-safety: one thread (raymapd's ingest thread).
/// @rt decode(): allocates no, blocks no. onCameraInfo(): allocates only for a camera larger
/// than reserve_pixels (never beyond max_points); builds the pixel ray table when the
/// intrinsics change (a few milliseconds for 640 x 480: once, not per frame).
class SensorDecoder {
 public:
  explicit SensorDecoder(SensorDecodeSettings settings);
  ~SensorDecoder() = default;
  SensorDecoder(const SensorDecoder&) = delete;
  SensorDecoder& operator=(const SensorDecoder&) = delete;
  SensorDecoder(SensorDecoder&&) noexcept = default;
  SensorDecoder& operator=(SensorDecoder&&) noexcept = default;

  /// @brief Takes a CameraInfo (depth cameras). A valid one replaces the intrinsics images are
  /// back-projected with (the newest of its frame is used for every later image: drivers
  /// publish the same intrinsics with every frame). @return why it was refused.
  Expected<void, msgs::CameraInfoError> onCameraInfo(std::span<const std::byte> cdr);

  /// @brief Decodes a PointCloud2 or depth Image into `out` (the sensor's frame).
  DecodedScan decode(std::span<const std::byte> cdr, std::span<msgs::ScanPoint> out) noexcept;

  /// @brief Whether a message comes faster than max_rate_hz, from its header stamp alone (no
  /// decoding). raymapd asks on arrival, before it holds a message undecoded, so that a camera
  /// publishing faster than its limit never pushes a scan out of the queue for an image that
  /// decode() would then drop. A message it lets through starts the next period of this
  /// arrival-side schedule (decode() keeps its own, which then agrees); one whose stamp cannot
  /// be read is let through (decode() names its fault). @rt allocates: no.
  bool overRateOnArrival(std::span<const std::byte> cdr) noexcept;

  const SensorDecodeSettings& settings() const noexcept { return settings_; }
  /// @brief Whether a depth camera has usable intrinsics (always true for point clouds).
  bool ready() const noexcept { return settings_.kind != SensorInputKind::kDepth || rays_.built(); }

 private:
  /// Whether `stamp_ns` is at least a period after `last_ns` (or any is false).
  bool rateAllows(bool any, std::int64_t last_ns, std::int64_t stamp_ns) const noexcept;
  DecodedScan decodeCloud(std::span<const std::byte> cdr, std::span<msgs::ScanPoint> out) noexcept;
  DecodedScan decodeDepth(std::span<const std::byte> cdr, std::span<msgs::ScanPoint> out) noexcept;
  /// The configured frame and the rate limit; `commit`: an accepted message starts the next
  /// rate period.
  DecodeOutcome admit(const char* frame_id, std::int64_t stamp_ns, bool commit = true) noexcept;

  SensorDecodeSettings settings_;
  PixelRayTable rays_;
  char camera_frame_[64] = {};  // frame_id of the CameraInfo the table was built from
  // The last CameraInfo refused, so that the same one arriving with every frame is refused at
  // once (not rebuilt up to its bad pixel each time).
  CameraIntrinsics refused_camera_;
  msgs::CameraInfoError refused_error_ = msgs::CameraInfoError::kInvalidIntrinsics;
  bool refused_any_ = false;
  std::int64_t last_accepted_ns_ = 0;
  bool accepted_any_ = false;
  std::int64_t last_arrival_ns_ = 0;  // overRateOnArrival's schedule
  bool arrived_any_ = false;
};

/// @brief The CameraInfo topic ROS drivers publish beside an image topic: its namespace plus
/// "camera_info" (/camera/depth/image_rect_raw -> /camera/depth/camera_info; the same for DDS
/// names, rt/camera/depth/image_rect_raw -> rt/camera/depth/camera_info).
std::string cameraInfoTopicFor(const std::string& image_topic);

}  // namespace raymap::pipeline
