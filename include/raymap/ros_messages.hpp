// SPDX-License-Identifier: BSD-3-Clause
// The ROS 2 messages raymap reads, decoded from their serialized bytes into the library's types:
// for a program that receives messages itself (an rclcpp node's SerializedMessage, a rosbag2 or
// MCAP reader of its own) and feeds raymap::Mapper. No DDS, no ROS installation needed: these are
// raymapd's and the bag reader's own decoders (src/msgs).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "raymap/depth_image.hpp"
#include "raymap/error.hpp"
#include "raymap/expected.hpp"
#include "raymap/scan.hpp"
#include <Eigen/Geometry>

namespace raymap::ros {

/// @brief Which fields of a PointCloud2 to read. Plain value type.
struct PointCloudOptions {
  /// The per-point time field: empty = the first of "t", "time", "timestamp", "time_stamp" the
  /// cloud has (none: every point at the header stamp); "none" = ignore any; another name = that
  /// field, which the cloud must have. Its unit follows the field (integer nanoseconds after the
  /// stamp, float seconds after it, or absolute seconds since the epoch), as raymapd reads it.
  std::string time_field;
  std::string intensity_field = "intensity";  ///< any numeric type; empty = none
  /// Points at exactly (0, 0, 0) are no-returns (the Ouster driver writes missing returns so).
  bool origin_is_no_return = true;
};

/// @brief A decoded sensor_msgs/PointCloud2, ready for Mapper::integrate. Plain value type.
struct PointCloud {
  std::int64_t stamp_ns = 0;  ///< header.stamp, nanoseconds since the epoch of the sender's clock
  std::string frame_id;       ///< header.frame_id: the frame the points are in
  std::uint32_t width = 0;    ///< points per row
  std::uint32_t height = 0;   ///< rows (1: unorganised)
  /// Every point, row by row, in frame_id (metres). time_s is the point's time in seconds since
  /// the epoch of the header's clock (the stamp plus the point's offset), the time base of
  /// nav_msgs/Odometry and TF stamps (decodeOdometry), so a pose table of those deskews the scan.
  /// no_return marks points with non-finite coordinates (and (0, 0, 0), see the options).
  std::vector<SensorPoint> points;
  std::uint32_t no_return = 0;  ///< points marked no_return
  bool has_time = false;        ///< a time field was read
  bool has_intensity = false;   ///< an intensity field was read
};

/// @brief A transform with its stamp: child_frame in parent_frame (p_parent = transform *
/// p_child), metres. Plain value type.
struct StampedTransform {
  std::int64_t stamp_ns = 0;
  std::string parent_frame;
  std::string child_frame;
  Eigen::Isometry3d transform = Eigen::Isometry3d::Identity();  ///< rotation from a unit quaternion
};

/// @brief Camera intrinsics from a sensor_msgs/CameraInfo, with its header. Plain value type.
struct CameraInfo {
  std::int64_t stamp_ns = 0;
  std::string frame_id;     ///< the camera's optical frame
  CameraIntrinsics camera;  ///< for Mapper::integrate(DepthImageView, camera, …)
};

// Every function takes the serialized message as a rosbag2 file, an MCAP file or an rclcpp
// SerializedMessage holds it: XCDR1, little- or big-endian, starting with its 4-byte
// encapsulation header. A message that does not decode gives kInvalidArgument naming the type and
// the reason ("sensor_msgs/PointCloud2: truncated"); nothing is read outside `cdr`. Thread-safe
// (no shared state); each allocates only its result (not for a real-time loop: raymapd decodes
// into preallocated buffers with the internal decoders).

/// @brief Decodes a sensor_msgs/PointCloud2. x, y and z must be FLOAT32 or FLOAT64.
Result<PointCloud> decodePointCloud2(std::span<const std::byte> cdr,
                                     const PointCloudOptions& options = {});
/// @brief Decodes a nav_msgs/Odometry's pose: header.frame_id -> child_frame_id (covariances and
/// twist are not read).
Result<StampedTransform> decodeOdometry(std::span<const std::byte> cdr);
/// @brief Decodes every transform of a tf2_msgs/TFMessage (/tf or /tf_static); one bad transform
/// refuses the message.
Result<std::vector<StampedTransform>> decodeTfMessage(std::span<const std::byte> cdr);
/// @brief Decodes a sensor_msgs/CameraInfo: the plumb_bob (or rational_polynomial with k4..k6
/// zero) model, binning and region of interest applied as image_geometry applies them.
Result<CameraInfo> decodeCameraInfo(std::span<const std::byte> cdr);

}  // namespace raymap::ros
