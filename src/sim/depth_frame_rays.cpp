// SPDX-License-Identifier: BSD-3-Clause
// Depth frames to rays for simulated recordings: each frame is serialised as sensor_msgs/Image +
// CameraInfo and decoded by msgs::decodeCameraInfo and msgs::decodeDepthImage, exactly as raymapd
// and `raymap populate` read a real camera, so the simulated recordings test that code.
#include "src/sim/depth_frame_rays.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "src/msgs/camera_info.hpp"
#include "src/msgs/depth_image.hpp"
#include "src/msgs/depth_image_writer.hpp"

namespace raymap::sim {
namespace {

/// The frame through the wire format and raymapd's decoders into optical-frame points.
Expected<void, Error> pointsViaDecoder(const DepthCamera& camera, double time_s,
                                       std::span<const float> depth_m, DepthRayScratch& s) {
  const DepthCameraModel& m = camera.model();
  const auto stamp_ns = static_cast<std::int64_t>(std::llround(time_s * 1e9));
  const std::string frame_id = m.name + "_optical_frame";
  msgs::serializeCameraInfo(stamp_ns, frame_id, camera.intrinsics(), s.camera_info_cdr);
  msgs::serializeDepthImage(stamp_ns, frame_id, m.width, m.height, m.encoding, false, depth_m,
                            s.image_cdr);
  const auto info = msgs::decodeCameraInfo(s.camera_info_cdr);
  if (!info) {
    return fail(ErrorCode::kFormat,
                std::string("simulated CameraInfo not decoded: ") + msgs::toString(info.error()));
  }
  if (auto built = s.rays.build(info->camera); !built) {
    return Unexpected(built.error());
  }
  msgs::DepthDecodeOptions options;
  options.downsample = m.downsample;
  options.min_range_m = static_cast<float>(m.min_range_m);
  options.max_range_m = static_cast<float>(m.max_range_m);
  options.invalid_as_free = true;  // no-return rays, as the lidar writes them
  s.points.resize(msgs::depthPointCapacity(m.width, m.height, m.downsample));
  const auto decoded = msgs::decodeDepthImage(s.image_cdr, s.rays, options, s.points);
  if (!decoded) {
    return fail(ErrorCode::kFormat, std::string("simulated depth image not decoded: ") +
                                        msgs::toString(decoded.error()));
  }
  s.points.resize(decoded->points);
  return {};
}

}  // namespace

Expected<void, Error> appendDepthFrameRays(const DepthCamera& camera, const CameraPose& pose,
                                           double time_s, std::uint64_t scan,
                                           std::span<const float> depth_m, DepthRayScratch& scratch,
                                           std::vector<Ray>& out) {
  auto points = pointsViaDecoder(camera, time_s, depth_m, scratch);
  if (!points) {
    return points;
  }
  for (const msgs::ScanPoint& p : scratch.points) {
    Ray ray;
    ray.origin = pose.origin;
    ray.sample = pose.toWorld(
        {static_cast<double>(p.x), static_cast<double>(p.y), static_cast<double>(p.z)});
    ray.time_s = time_s;
    ray.scan = scan;
    ray.flags = (p.flags & msgs::kPointFreeOnly) != 0 ? kRayNoReturn : 0U;
    out.push_back(ray);
  }
  return {};
}

}  // namespace raymap::sim
