// SPDX-License-Identifier: BSD-3-Clause
// Depth frames to rays for `raymap simulate`. Two ways, one chosen at compile time:
// - decoder: the frame is serialised as sensor_msgs/Image + CameraInfo and decoded by
//   dds::decodeCameraInfo and dds::decodeDepthImage, exactly as raymapd and `populate` will read
//   a real camera, so the simulated recordings test that code;
// - interim: until the serialisers (src/dds/depth_image_writer.hpp) and the decoders' sources are
//   in the tree, the same back-projection written out here, with the decoder's documented
//   choices (nearest valid depth of each block at its own pixel's ray, free-only blocks along the
//   centre pixel's ray).
// NOTE(depth-sim): when the writer lands, __has_include switches to the decoder; then delete
// pointsInterim() and RAYMAP_SIM_DEPTH_VIA_DECODER.
#include "tools/raymap/simulate_depth.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#if __has_include("src/dds/depth_image_writer.hpp")
#define RAYMAP_SIM_DEPTH_VIA_DECODER 1
#include "src/dds/camera_info.hpp"
#include "src/dds/depth_image.hpp"
#include "src/dds/depth_image_writer.hpp"
#else
#define RAYMAP_SIM_DEPTH_VIA_DECODER 0
#endif

namespace raymap::cli {
namespace {

#if RAYMAP_SIM_DEPTH_VIA_DECODER

/// The frame through the wire format and raymapd's decoders into optical-frame points.
Expected<void, Error> pointsViaDecoder(const sim::DepthCamera& camera, double time_s,
                                       std::span<const float> depth_m, DepthRayScratch& s) {
  const sim::DepthCameraModel& m = camera.model();
  const auto stamp_ns = static_cast<std::int64_t>(std::llround(time_s * 1e9));
  const std::string frame_id = m.name + "_optical_frame";
  dds::serializeCameraInfo(stamp_ns, frame_id, camera.intrinsics(), s.camera_info_cdr);
  dds::serializeDepthImage(stamp_ns, frame_id, m.width, m.height, sim::toString(m.encoding), false,
                           depth_m, s.image_cdr);
  const auto info = dds::decodeCameraInfo(s.camera_info_cdr);
  if (!info) {
    return fail(ErrorCode::kFormat,
                std::string("simulated CameraInfo not decoded: ") + dds::toString(info.error()));
  }
  if (auto built = s.rays.build(info->camera); !built) {
    return Unexpected(built.error());
  }
  dds::DepthDecodeOptions options;
  options.downsample = m.downsample;
  options.min_range_m = static_cast<float>(m.min_range_m);
  options.max_range_m = static_cast<float>(m.max_range_m);
  options.invalid_as_free = true;  // no-return rays, as the lidar writes them
  s.points.resize(dds::depthPointCapacity(m.width, m.height, m.downsample));
  const auto decoded = dds::decodeDepthImage(s.image_cdr, s.rays, options, s.points);
  if (!decoded) {
    return fail(ErrorCode::kFormat, std::string("simulated depth image not decoded: ") +
                                        dds::toString(decoded.error()));
  }
  s.points.resize(decoded->points);
  return {};
}

#else

/// The depth a pixel of `encoding` carries on the wire: 16UC1 is whole millimetres, 0 (invalid)
/// for anything not in 1..65535 mm; 32FC1 the float as it is.
float onTheWire(sim::DepthEncoding encoding, float depth_m) noexcept {
  if (encoding == sim::DepthEncoding::k32FC1) {
    return depth_m;
  }
  if (!std::isfinite(depth_m)) {
    return 0.0f;
  }
  const double mm = std::round(static_cast<double>(depth_m) * 1000.0);
  return mm >= 1.0 && mm <= 65535.0 ? static_cast<float>(mm / 1000.0) : 0.0f;
}

/// The interim stand-in for pointsViaDecoder(): the same points from the same ray table, without
/// the wire format.
Expected<void, Error> pointsInterim(const sim::DepthCamera& camera, std::span<const float> depth_m,
                                    DepthRayScratch& s) {
  const sim::DepthCameraModel& m = camera.model();
  if (auto built = s.rays.build(camera.intrinsics()); !built) {
    return Unexpected(built.error());
  }
  const std::uint32_t n = m.downsample;
  const auto min_range = static_cast<float>(m.min_range_m);
  const auto max_range = static_cast<float>(m.max_range_m);
  s.points.clear();
  for (std::uint32_t v0 = 0; v0 < m.height; v0 += n) {
    const std::uint32_t v1 = std::min(v0 + n, m.height);
    for (std::uint32_t u0 = 0; u0 < m.width; u0 += n) {
      const std::uint32_t u1 = std::min(u0 + n, m.width);
      // The nearest valid depth of the block (range along the pixel's ray), first one on ties.
      float best_range = std::numeric_limits<float>::infinity();
      dds::ScanPoint best{};
      for (std::uint32_t v = v0; v < v1; ++v) {
        for (std::uint32_t u = u0; u < u1; ++u) {
          const float z = onTheWire(m.encoding, depth_m[static_cast<std::size_t>(v) * m.width + u]);
          if (!(z > 0.0f) || !std::isfinite(z)) {
            continue;
          }
          const float* r = s.rays.ray(u, v);
          const float range = z * std::sqrt(r[0] * r[0] + r[1] * r[1] + 1.0f);
          if (range >= min_range && range < best_range) {
            best_range = range;
            best = {z * r[0], z * r[1], z, 0.0f, 0.0f, 0U};
          }
        }
      }
      if (best_range == std::numeric_limits<float>::infinity()) {
        const float* r = s.rays.ray(u0 + (u1 - u0 - 1) / 2, v0 + (v1 - v0 - 1) / 2);
        const float scale = max_range / std::sqrt(r[0] * r[0] + r[1] * r[1] + 1.0f);
        best = {scale * r[0], scale * r[1], scale, 0.0f, 0.0f, dds::kPointFreeOnly};
      }
      s.points.push_back(best);
    }
  }
  return {};
}

#endif

}  // namespace

const char* depthRayPath() noexcept { return RAYMAP_SIM_DEPTH_VIA_DECODER ? "decoder" : "interim"; }

Expected<void, Error> appendDepthFrameRays(const sim::DepthCamera& camera,
                                           const sim::CameraPose& pose, double time_s,
                                           std::uint64_t scan, std::span<const float> depth_m,
                                           DepthRayScratch& scratch, std::vector<Ray>& out) {
#if RAYMAP_SIM_DEPTH_VIA_DECODER
  auto points = pointsViaDecoder(camera, time_s, depth_m, scratch);
#else
  auto points = pointsInterim(camera, depth_m, scratch);
#endif
  if (!points) {
    return points;
  }
  for (const dds::ScanPoint& p : scratch.points) {
    Ray ray;
    ray.origin = pose.origin;
    ray.sample = pose.toWorld({p.x, p.y, p.z});
    ray.time_s = time_s;
    ray.scan = scan;
    ray.flags = (p.flags & dds::kPointFreeOnly) != 0 ? kRayNoReturn : 0U;
    out.push_back(ray);
  }
  return {};
}

}  // namespace raymap::cli
