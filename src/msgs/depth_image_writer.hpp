// SPDX-License-Identifier: BSD-3-Clause
// Serializing a depth camera's sensor_msgs/CameraInfo and sensor_msgs/Image as XCDR1 bytes: what
// the simulated camera publishes and records, and what the decoders' tests feed them.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "raymap/depth_image.hpp"

#include "src/core/pinhole_camera.hpp"

namespace raymap::msgs {

/// The depth encodings raymap writes (and reads: src/msgs/depth_image.hpp): the public one.
using raymap::DepthEncoding;

/// @brief Serializes sensor_msgs/CameraInfo for `camera` (CDR_LE, with the 4-byte encapsulation
/// header) into `out`, replacing its contents.
///
/// distortion_model is "plumb_bob" with D = [k1 k2 p1 p2 k3] when camera.distortion is
/// kPlumbBob, else "" with an empty D; K = [fx 0 cx; 0 fy cy; 0 0 1], R = identity,
/// P = [fx 0 cx 0; 0 fy cy 0; 0 0 1 0], no binning (0) and no ROI (all zero).
/// @param[in] stamp_ns header.stamp, nanoseconds since the epoch (negative: before it)
/// @param[in] frame_id header.frame_id (the camera's optical frame)
/// @rt allocates: only when `out`'s capacity is too small; thread: any.
void serializeCameraInfo(std::int64_t stamp_ns, std::string_view frame_id,
                         const CameraIntrinsics& camera, std::vector<std::byte>& out);

/// @brief Serializes a depth image as sensor_msgs/Image (CDR_LE message, encapsulation header
/// included) into `out`, replacing its contents. step = width × pixel size, no row padding.
///
/// 16UC1: each depth is rounded to the nearest millimetre and saturated at 65,535; NaN, ±inf,
/// and depths <= 0 (or rounding to 0) are written as 0 ("no data"). 32FC1: the floats as given.
/// @param[in] depth_m row-major, width × height depths along the optical axis (z), metres
/// @param[in] big_endian the pixels' byte order (is_bigendian); the message itself is CDR_LE
/// @pre depth_m.size() == width × height
/// @rt allocates: only when `out`'s capacity is too small; thread: any.
void serializeDepthImage(std::int64_t stamp_ns, std::string_view frame_id, std::uint32_t width,
                         std::uint32_t height, DepthEncoding encoding, bool big_endian,
                         std::span<const float> depth_m, std::vector<std::byte>& out);

/// @brief The encoding's name on the wire ("16UC1", "32FC1").
const char* toString(DepthEncoding encoding) noexcept;

}  // namespace raymap::msgs
