// SPDX-License-Identifier: BSD-3-Clause
// Decoding sensor_msgs/CameraInfo straight from its serialized XCDR1 bytes: the intrinsics a
// depth camera's images are back-projected with.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <type_traits>

#include "raymap/expected.hpp"

#include "src/core/pinhole_camera.hpp"

namespace raymap::msgs {

/// @brief A decoded CameraInfo: its header and the pinhole model it describes.
struct CameraInfoHeader {
  std::int64_t stamp_ns = 0;  ///< header.stamp, nanoseconds since the epoch of the sender's clock
  char frame_id[64] = {};     ///< header.frame_id, NUL-terminated (the camera's optical frame)
  /// width, height, K (fx, fy, cx, cy) and D. binning_x/y > 1 divide the size and K as
  /// image_geometry does; a region of interest other than the whole image shifts cx, cy and
  /// sets the size to the ROI's. P, R are not used: the depth images raymap reads are in the
  /// camera's own (unrectified) frame. A D of all zeros (as drivers of rectified depth send
  /// "plumb_bob") decodes as DistortionModel::kNone.
  CameraIntrinsics camera;
};
static_assert(std::is_trivially_copyable_v<CameraInfoHeader>);

/// Why a CameraInfo was rejected. Nothing is read out of bounds.
enum class CameraInfoError : std::uint8_t {
  kTruncated,              ///< the bytes end before the message does
  kBadEncapsulation,       ///< shorter than 4 bytes or not CDR_LE / CDR_BE
  kMalformed,              ///< a string without its NUL, or similar structural damage
  kFrameIdTooLong,         ///< header.frame_id has 64 or more characters
  kUnsupportedDistortion,  ///< a distortion_model other than "", "plumb_bob" and
                           ///< "rational_polynomial" (with its k4..k6 zero), or too few D
                           ///< (fewer than 5), or "" with a non-zero D (coefficients of no model)
  kInvalidIntrinsics,      ///< zero or non-finite focal length, size 0, non-finite D, or a
                           ///< distortion that folds over the image (CameraIntrinsics::validate);
                           ///< also a ROI that is not all zero and not inside the image
  kTooLarge,               ///< a camera whose images would give more points than the sensor
                           ///< takes (sensors[].max_points at its downsample): refused before
                           ///< its pixel rays are built (the size of a huge table, the time)
};
inline constexpr std::size_t kCameraInfoErrorCount =
    static_cast<std::size_t>(CameraInfoError::kTooLarge) + 1;

/// @brief Short, stable name ("truncated", "invalid_intrinsics", ...). @rt allocates: no.
const char* toString(CameraInfoError error) noexcept;

/// @brief Decodes a serialized sensor_msgs/CameraInfo (with its 4-byte encapsulation header).
/// kTooLarge is never returned here (it is the sensor's policy: pipeline::SensorDecoder).
/// @rt allocates: no; blocks: no.
Expected<CameraInfoHeader, CameraInfoError> decodeCameraInfo(
    std::span<const std::byte> cdr) noexcept;

}  // namespace raymap::msgs
