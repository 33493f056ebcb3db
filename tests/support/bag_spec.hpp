// SPDX-License-Identifier: BSD-3-Clause
// The JSON-lines description of a bag that tests/rosbag/node/write_bag.mjs turns into a rosbag2
// recording with Foxglove's MCAP writer and ROS 2 serializer (an implementation independent of
// raymap's). See tests/rosbag/node/README.md for the format.
#pragma once

#include <cstdint>
#include <fstream>
#include <span>
#include <string>
#include <vector>

#include "src/core/pinhole_camera.hpp"
#include "src/io/trajectory.hpp"
#include "src/msgs/point_cloud.hpp"
#include "tests/support/json_doc.hpp"

namespace raymap::test {

/// @brief One transform of a TFMessage.
struct SpecTransform {
  std::int64_t stamp_ns = 0;
  std::string parent;
  std::string child;
  io::Pose pose;  ///< child in parent
};

/// @brief Writes a bag description line by line. Not thread-safe.
class BagSpecWriter {
 public:
  explicit BagSpecWriter(const std::string& path);
  bool ok() const { return static_cast<bool>(out_); }

  void channel(const std::string& topic, const std::string& type, const std::string& qos = "");
  /// A PointCloud2 in the Ouster driver's layout (point_step 48: x y z float32, intensity
  /// float32 at 16, t uint32 ns at 20, ring uint16 at 26), one row; no-return points (NaN in
  /// `points`) as (0, 0, 0), as Ouster publishes them.
  void ousterCloud(const std::string& topic, std::int64_t log_time_ns, std::int64_t stamp_ns,
                   const std::string& frame, std::span<const msgs::ScanPoint> points,
                   std::span<const std::uint16_t> rings);
  void odometry(const std::string& topic, std::int64_t log_time_ns, std::int64_t stamp_ns,
                const std::string& frame, const std::string& child, const io::Pose& pose);
  void tf(const std::string& topic, std::int64_t log_time_ns,
          const std::vector<SpecTransform>& transforms);
  /// A sensor_msgs/CameraInfo of `camera` (plumb_bob when it has distortion, else "";
  /// R identity, P = [K | 0], no binning, the whole image as ROI).
  void cameraInfo(const std::string& topic, std::int64_t log_time_ns, std::int64_t stamp_ns,
                  const std::string& frame, const CameraIntrinsics& camera);
  /// A depth sensor_msgs/Image, row-major `depth_m` (metres along the optical axis; NaN or 0 =
  /// no depth): 32FC1 (metres), or 16UC1 (millimetres, rounded; invalid -> 0), little-endian,
  /// step = width x pixel size.
  void depthImage(const std::string& topic, std::int64_t log_time_ns, std::int64_t stamp_ns,
                  const std::string& frame, std::uint32_t width, std::uint32_t height,
                  std::span<const float> depth_m, bool millimetres);
  /// Any message, its fields given as JSON text (`body`; not JSON throws).
  void message(const std::string& topic, std::int64_t log_time_ns, const std::string& body);

 private:
  void writeMessage(const std::string& topic, std::int64_t log_time_ns, const Json& body);

  std::ofstream out_;
};

/// @brief Base64 (RFC 4648, with padding).
std::string base64(std::span<const std::byte> bytes);

}  // namespace raymap::test
