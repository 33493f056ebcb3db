// SPDX-License-Identifier: BSD-3-Clause
// raymap/ros_messages.hpp over the internal decoders (src/msgs): the same bytes give the same
// points, poses and intrinsics as raymapd and the bag reader get.
#include "raymap/ros_messages.hpp"

#include "src/io/trajectory.hpp"
#include "src/msgs/camera_info.hpp"
#include "src/msgs/point_cloud.hpp"
#include "src/msgs/pose.hpp"

namespace raymap::ros {
namespace {

/// The smallest point a PointCloud2 can hold (x, y, z as float32): the most points its bytes
/// can describe, the room the internal decoder needs.
constexpr std::size_t kSmallestPointBytes = 12;
/// TF messages carry a few hundred transforms at most; one takes at least this many bytes.
constexpr std::size_t kSmallestTransformBytes = 64;

Unexpected<Error> decodeError(const char* type, const char* reason) {
  return fail(ErrorCode::kInvalidArgument, std::string(type) + ": " + reason);
}

StampedTransform toPublic(const msgs::StampedTransform& t) {
  StampedTransform out;
  out.stamp_ns = t.stamp_ns;
  out.parent_frame = t.parent;
  out.child_frame = t.child;
  out.transform = io::Pose{{t.tx, t.ty, t.tz}, {t.qw, t.qx, t.qy, t.qz}}.toIsometry();
  return out;
}

}  // namespace

Result<PointCloud> decodePointCloud2(std::span<const std::byte> cdr,
                                     const PointCloudOptions& options) {
  msgs::CloudDecodeOptions settings;
  settings.ignore_time = options.time_field == "none";
  settings.time_field =
      options.time_field.empty() || settings.ignore_time ? nullptr : options.time_field.c_str();
  settings.intensity_field =
      options.intensity_field.empty() ? nullptr : options.intensity_field.c_str();
  settings.origin_is_no_return = options.origin_is_no_return;
  std::vector<msgs::ScanPoint> points(cdr.size() / kSmallestPointBytes + 1);
  const auto header = msgs::decodePointCloud2(cdr, points, settings);
  if (!header) {
    return decodeError("sensor_msgs/PointCloud2", msgs::toString(header.error()));
  }
  PointCloud cloud;
  cloud.stamp_ns = header->stamp_ns;
  cloud.frame_id = header->frame_id;
  cloud.width = header->width;
  cloud.height = header->height;
  cloud.no_return = header->no_return;
  cloud.has_time = header->has_time;
  cloud.has_intensity = header->has_intensity;
  const double stamp_s = static_cast<double>(header->stamp_ns) * 1e-9;
  cloud.points.resize(header->points);
  for (std::uint32_t i = 0; i < header->points; ++i) {
    const msgs::ScanPoint& p = points[i];
    SensorPoint& out = cloud.points[i];
    out.position = Eigen::Vector3d(static_cast<double>(p.x), static_cast<double>(p.y),
                                   static_cast<double>(p.z));
    out.time_s = stamp_s + static_cast<double>(p.time_s);
    out.intensity = p.intensity;
    out.no_return = (p.flags & msgs::kPointNoReturn) != 0u;
  }
  return cloud;
}

Result<StampedTransform> decodeOdometry(std::span<const std::byte> cdr) {
  const auto t = msgs::decodeOdometry(cdr);
  if (!t) {
    return decodeError("nav_msgs/Odometry", msgs::toString(t.error()));
  }
  return toPublic(*t);
}

Result<std::vector<StampedTransform>> decodeTfMessage(std::span<const std::byte> cdr) {
  std::vector<msgs::StampedTransform> decoded(cdr.size() / kSmallestTransformBytes + 1);
  const auto n = msgs::decodeTfMessage(cdr, decoded);
  if (!n) {
    return decodeError("tf2_msgs/TFMessage", msgs::toString(n.error()));
  }
  std::vector<StampedTransform> out;
  out.reserve(*n);
  for (std::uint32_t i = 0; i < *n; ++i) {
    out.push_back(toPublic(decoded[i]));
  }
  return out;
}

Result<CameraInfo> decodeCameraInfo(std::span<const std::byte> cdr) {
  const auto info = msgs::decodeCameraInfo(cdr);
  if (!info) {
    return decodeError("sensor_msgs/CameraInfo", msgs::toString(info.error()));
  }
  return CameraInfo{info->stamp_ns, info->frame_id, info->camera};
}

}  // namespace raymap::ros
