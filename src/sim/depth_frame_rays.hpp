// SPDX-License-Identifier: BSD-3-Clause
// Simulated depth cameras' frames as world-frame rays, the way raymapd turns a camera's Image +
// CameraInfo into rays (raymap simulate's recordings, sim::recordScene).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "raymap/error.hpp"

#include "src/core/pinhole_camera.hpp"
#include "src/map/ray.hpp"
#include "src/msgs/point_cloud.hpp"
#include "src/sim/depth_camera.hpp"

namespace raymap::sim {

/// @brief Buffers reused from frame to frame. Not thread-safe: one per thread.
struct DepthRayScratch {
  std::vector<std::byte> camera_info_cdr;
  std::vector<std::byte> image_cdr;
  std::vector<msgs::ScanPoint> points;  ///< one frame's points, optical frame
  PixelRayTable rays;                   ///< the CameraInfo's rays, as the decoder builds them
};

/// @brief Appends the rays of one frame (`depth_m` from camera.render()) to `out`, world frame:
/// origin the optical centre, every `downsample` × `downsample` block of pixels one ray to its
/// nearest valid depth (raymapd's `downsample`), and a block without a valid depth (REP 117
/// ±inf, 0 in 16UC1) a no-return ray (kRayNoReturn, as the lidar's) max_range along the ray of
/// its centre pixel. 16UC1 frames are rounded to millimetres first, as on the wire.
/// Each ray gets `time_s` and `scan`.
/// @return an error when the frame cannot be serialised or decoded (a bug: the camera was
/// validated).
Expected<void, Error> appendDepthFrameRays(const DepthCamera& camera, const CameraPose& pose,
                                           double time_s, std::uint64_t scan,
                                           std::span<const float> depth_m, DepthRayScratch& scratch,
                                           std::vector<Ray>& out);

}  // namespace raymap::sim
