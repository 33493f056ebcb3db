// SPDX-License-Identifier: BSD-3-Clause
// A depth camera's images and intrinsics as raymap::Mapper integrates them (docs/library.md,
// "Depth images"): the pinhole model of sensor_msgs/CameraInfo and a view of the pixels of a
// sensor_msgs/Image in 16UC1 (millimetres) or 32FC1 (metres).
#pragma once

#include <cstddef>
#include <cstdint>

#include "raymap/error.hpp"
#include "raymap/expected.hpp"

namespace raymap {

/// Lens distortion models of sensor_msgs/CameraInfo::distortion_model.
enum class DistortionModel : std::uint8_t {
  kNone,      ///< "" or every coefficient zero: a rectified image
  kPlumbBob,  ///< "plumb_bob" (and "rational_polynomial" with its extra terms zero): k1 k2 p1 p2 k3
};

/// @brief Intrinsics of a pinhole camera, as sensor_msgs/CameraInfo states them.
///
/// Frames and units: the optical frame (REP 103 "_optical": x right, y down, z forward); pixel
/// coordinates in pixels, (0, 0) the centre of the top-left pixel, u to the right, v down (as
/// OpenCV and ROS image_geometry use them). A point (x, y, z) with z > 0 projects to normalised
/// coordinates (x / z, y / z), then through distortion to (u, v) = (fx x_d + cx, fy y_d + cy).
/// Plain value type. Thread-safety: immutable use from any thread.
struct CameraIntrinsics {
  std::uint32_t width = 0;   ///< pixels
  std::uint32_t height = 0;  ///< pixels
  double fx = 0.0;           ///< focal length, pixels (K[0])
  double fy = 0.0;           ///< focal length, pixels (K[4])
  double cx = 0.0;           ///< principal point, pixels (K[2])
  double cy = 0.0;           ///< principal point, pixels (K[5])
  DistortionModel distortion = DistortionModel::kNone;
  /// plumb_bob coefficients in CameraInfo's order: k1, k2, p1 (t1), p2 (t2), k3.
  double k1 = 0.0;
  double k2 = 0.0;
  double p1 = 0.0;
  double p2 = 0.0;
  double k3 = 0.0;

  /// @brief Checks that the camera can be used: a size of at least 1 × 1 pixel and at most
  /// 65,535 on a side, finite focal lengths > 0, finite principal point and coefficients, and a
  /// distortion that is invertible over the image (checked at the corners and edge midpoints).
  /// The message names the field and the reason.
  Expected<void, Error> validate() const;
  /// @brief What validate() checks, without describing the failure. @rt allocates: no.
  bool usable() const noexcept;

  bool operator==(const CameraIntrinsics&) const = default;
};

/// @brief How a depth image's pixels are stored (sensor_msgs/Image::encoding).
enum class DepthEncoding : std::uint8_t {
  k16UC1,  ///< "16UC1" (or "mono16"): unsigned 16-bit millimetres, 0 = no depth
  k32FC1,  ///< "32FC1": float metres; 0, NaN and +inf = no return, -inf = too near
};

/// @brief The pixels of one depth image, borrowed from the caller for the duration of the call.
/// Row-major, row 0 the top row; `step` bytes from one row to the next (>= width × 2 or × 4);
/// pixels in the host's byte order unless big_endian says otherwise. Plain value type.
struct DepthImageView {
  const void* data = nullptr;
  std::uint32_t width = 0;   ///< pixels; must equal the camera's
  std::uint32_t height = 0;  ///< pixels; must equal the camera's
  std::size_t step = 0;      ///< bytes per row
  DepthEncoding encoding = DepthEncoding::k32FC1;
  bool big_endian = false;  ///< sensor_msgs/Image::is_bigendian
};

/// @brief How a depth image becomes rays (raymapd's `sensors[]` with `kind: depth`, and `raymap
/// populate`'s depth options). Metres along each pixel's ray. Value type.
struct DepthOptions {
  /// N >= 1: each N × N block of pixels gives one ray, to its nearest valid depth (so a thin
  /// near obstacle survives); 1 = every pixel (`--downsample`).
  std::uint32_t downsample = 1;
  /// Depths nearer than this are the robot itself: left out. 0 = none (`--min-range`).
  double min_range = 0.0;
  /// The length of invalid_as_free rays (`--max-range`; 0 = none). Depths further away are
  /// integrated as they are: like every ray, they are clipped to free space by the mapper's
  /// RayOptions::max_range (which `raymap populate --max-range` sets as well).
  double max_range = 0.0;
  /// A block with no depth at all (0, NaN, +inf) clears free space max_range along its centre
  /// pixel's ray instead of giving nothing; needs max_range > 0 (`--invalid-as-free`).
  bool invalid_as_free = false;
};

}  // namespace raymap
