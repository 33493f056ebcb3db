// SPDX-License-Identifier: BSD-3-Clause
// The pinhole camera of sensor_msgs/CameraInfo (K, and D for the plumb_bob distortion model):
// pixels to the rays they see and back. One definition for the depth-image decoder (raymapd and
// bags) and the simulated depth camera, so what the simulator renders is what the decoder reads.
#pragma once

#include <cstdint>
#include <vector>

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

/// @brief Normalised image coordinates: the ray through (x, y, 1) in the optical frame.
struct NormalisedPoint {
  double x = 0.0;
  double y = 0.0;
};

/// @brief Pixel (u, v) of a normalised, undistorted point: distortion applied, then K.
/// @rt allocates: no.
NormalisedPoint projectNormalised(const CameraIntrinsics& camera, NormalisedPoint point) noexcept;

/// @brief The normalised, undistorted coordinates of pixel (u, v): K inverted, then the
/// distortion inverted by Newton's method in double precision (to 1e-12 of a normalised unit, so
/// projectNormalised(pixelToNormalised(u, v)) gives (u, v) back to about 1e-9 pixel).
/// @return false when the iteration did not converge (a distortion that folds over there).
/// @rt allocates: no.
bool pixelToNormalised(const CameraIntrinsics& camera, double u, double v,
                       NormalisedPoint* out) noexcept;

/// @brief The undistorted ray of every pixel of one camera, computed once per CameraInfo (the
/// inversion is iterative: far too slow per pixel per frame).
///
/// Storage is two floats per pixel (x / z and y / z), row-major; rebuilt only when the
/// intrinsics change. Thread-safety: build() on one thread; the const accessors from any thread
/// once built. @rt build(): allocates only when the image is larger than reserve() allowed for;
/// ray(): allocates no, blocks no.
class PixelRayTable {
 public:
  /// @brief Room for `pixels` pixels, so that build() for any camera up to that size does not
  /// allocate (start-up).
  void reserve(std::size_t pixels);

  /// @brief Computes the rays of `camera`'s pixels; a table already built for the same
  /// intrinsics is kept as it is.
  /// @return an error naming the field when the camera is invalid, or the pixel whose
  /// distortion cannot be inverted; the table is then empty.
  Expected<void, Error> build(const CameraIntrinsics& camera);

  /// @brief Whether build() succeeded for these intrinsics.
  bool matches(const CameraIntrinsics& camera) const noexcept {
    return built_ && camera == camera_;
  }
  bool built() const noexcept { return built_; }
  const CameraIntrinsics& camera() const noexcept { return camera_; }
  std::uint32_t width() const noexcept { return camera_.width; }
  std::uint32_t height() const noexcept { return camera_.height; }

  /// @brief x / z and y / z of the ray of pixel (u, v). @pre built(), u < width(), v < height()
  const float* ray(std::uint32_t u, std::uint32_t v) const noexcept {
    return &rays_[2 * (static_cast<std::size_t>(v) * camera_.width + u)];
  }

  /// @brief Forgets the table (the next build() computes it again).
  void clear() noexcept { built_ = false; }

 private:
  CameraIntrinsics camera_;
  bool built_ = false;
  std::vector<float> rays_;
};

}  // namespace raymap
